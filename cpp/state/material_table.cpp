#include "state/material_table.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace grainscale {

int MaterialTable::add(const MaterialProperties& p) {
  if (!(p.density > 0) || !std::isfinite(p.density))
    throw_invalid("Material.density", "positive and finite (kg/m^3)", p.density);
  if (!(p.youngs_modulus > 0))  // +inf: a rigid wall material (zero compliance below)
    throw_invalid("Material.youngs_modulus", "positive (Pa; inf for a rigid wall material)",
                  p.youngs_modulus);
  if (!(p.poisson_ratio >= 0 && p.poisson_ratio < 0.5))
    throw_invalid("Material.poisson_ratio", "in [0, 0.5)", p.poisson_ratio);
  materials_.push_back(p);
  return n_materials() - 1;
}

PairModuli MaterialTable::pair_moduli(int i, int j) const {
  auto compliance = [&](int k, Real& c_normal, Real& c_shear) {
    if (k == rigid_index()) {
      c_normal = 0;
      c_shear = 0;
      return;
    }
    const Real E = materials_[k].youngs_modulus, nu = materials_[k].poisson_ratio;
    c_normal = (1 - nu * nu) / E;
    c_shear = 2 * (2 - nu) * (1 + nu) / E;
  };
  Real cn_i, cs_i, cn_j, cs_j;
  compliance(i, cn_i, cs_i);
  compliance(j, cn_j, cs_j);
  if (cn_i + cn_j == 0)
    throw InvalidArgument("a contact between two rigid bodies has no stiffness");
  return {1 / (cn_i + cn_j), 1 / (cs_i + cs_j)};
}

}  // namespace grainscale
