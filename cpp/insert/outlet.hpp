// Outlet: particles whose centre lies inside a region are deleted and counted.
//
// The containment test runs every `every` steps (default 1: every step). It costs a few
// nanoseconds per particle, small next to the force loop, and checking every step makes the
// removal time exact to one step; a removal forces a neighbour-list rebuild, so with very high
// discharge rates a larger `every` bounds the number of extra rebuilds. The schedule is a
// function of the step counter only, so results never depend on how run() is chunked.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "insert/region.hpp"

namespace grainscale {

struct OutletSpec {
  Region region = Region::box(Vec3::Zero(), Vec3::Ones());
  int every = 1;  // steps between checks
  // Interface faces the removed mass is booked on (0: none). A level's region outlet
  // (Level::add_region_outlet: the fine level of a hierarchy) sets it to its grid's face count;
  // the level then decides which particles leave and on which face they are booked.
  std::size_t keep_faces = 0;
};

class Outlet {
 public:
  // time: the simulated time at registration (first point of the history).
  Outlet(const OutletSpec& spec, Real time);

  const OutletSpec& spec() const { return spec_; }
  bool due(std::int64_t step) const { return step % spec_.every == 0; }
  // Books removed particles (count, total mass, first moment sum m x, and with a `keep` grid the
  // mass per interface face) at `time`.
  void record(Real time, std::int64_t count, Real mass, const Vec3& moment,
              const std::vector<Real>& face_mass);
  // Interface faces booked per removal (0 without a `keep` grid).
  std::size_t n_faces() const { return face_mass_.size(); }

  std::int64_t removed_count() const { return removed_count_; }
  Real removed_mass() const { return removed_mass_; }
  // Sum of m x over the removed particles (kg m): their centre of mass is moment / mass.
  const Vec3& removed_moment() const { return moment_; }
  // With a `keep` grid: removed mass per interface face (kg).
  const std::vector<Real>& removed_face_mass() const { return face_mass_; }
  // History: one entry at registration and one per check that removed something.
  const std::vector<Real>& history_time() const { return time_; }
  const std::vector<Real>& history_mass() const { return mass_; }
  const std::vector<std::int64_t>& history_count() const { return count_; }

  std::string save_state() const;
  void load_state(const std::string& state);

 private:
  OutletSpec spec_;
  std::int64_t removed_count_ = 0;
  Real removed_mass_ = 0;
  Vec3 moment_ = Vec3::Zero();
  std::vector<Real> face_mass_;
  std::vector<Real> time_, mass_;
  std::vector<std::int64_t> count_;
};

}  // namespace grainscale
