// MaterialTable: per-material elastic properties and the derived per-pair effective moduli.
// Index n_materials() is reserved for the rigid wall pseudo-material (E -> infinity), so that
// rigid walls use exactly the same pair formulas as everything else. A material with E = +inf
// is a rigid wall material of its own (zero compliance, its own pair entries); particles
// need a deformable one.
#pragma once

#include <cmath>
#include <vector>

#include "core/types.hpp"

namespace grainscale {

struct MaterialProperties {
  Real density;
  Real youngs_modulus;
  Real poisson_ratio;
};

// Effective pair moduli (CASES.md section 0; LIGGGHTS createYeff/createGeff):
//   1/E* = (1-nu_i^2)/E_i + (1-nu_j^2)/E_j,   1/G* = 2(2-nu_i)(1+nu_i)/E_i + 2(2-nu_j)(1+nu_j)/E_j
struct PairModuli {
  Real effective_youngs;
  Real effective_shear;
};

class MaterialTable {
 public:
  // Validates and appends a material; returns its index.
  int add(const MaterialProperties& props);
  int n_materials() const { return static_cast<int>(materials_.size()); }
  int rigid_index() const { return n_materials(); }
  const MaterialProperties& operator[](int i) const { return materials_[i]; }
  // The rigid pseudo-material or a rigid wall material (E = +inf).
  bool rigid(int i) const {
    return i == rigid_index() || !std::isfinite(materials_[i].youngs_modulus);
  }
  bool deformable(int i) const { return !rigid(i); }
  PairModuli pair_moduli(int i, int j) const;

 private:
  std::vector<MaterialProperties> materials_;
};

}  // namespace grainscale
