// Coarse -> fine, particles entering (DESIGN.md 4): the fine level's insertion at one interface
// face. The mass the coarse level carried across the face in an interval (FaceFluxMeter) is
// fed here and turned into fine particles drawn from the fine size distribution: a particle is
// scheduled once the mass owed reaches its mass, so inserted + pending + owed always equals the
// mass fed (nothing is dropped; the owed remainder is less than one fine particle). Scheduled
// particles are placed without overlaps in a shell at the face (the face rectangle, two largest
// fine diameters deep, at most the cell's depth, starting one smallest radius outside the face so
// that centres reach the face: a grain of the bed beyond straddles it, and a shell flush with the
// face would leave the face's cell short of a layer r thick) with the face's mass-weighted
// velocity and its spin scaled by the size ratio (w R kept: the surface speed of a spinning
// grain); what finds no room waits for the next interval.
//
// Top-up (Exchange.top_up): where the coarse level holds a dense bed above the face, that bed
// sinks into any room the fine bed leaves below it, which the flux measured on the coarse level
// does not see. A top-up budget lets the inserter place extra particles in the shell, with the
// coarse cell's velocity, up to the budget, by the flux's placement rule; they are booked apart
// (topped_up_mass) and never owed: what does not fit lapses with the budget.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "coupling/exchange_grid.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/random.hpp"
#include "insert/region.hpp"
#include "insert/size_distribution.hpp"
#include "insert/wall_clearance.hpp"

namespace grainscale {

class FluxInserter {
 public:
  // spin_scale: coarse / fine particle size, applied to the fed spin.
  FluxInserter(const InterfaceFace& face, const FieldGrid& grid, const SizeDistribution& radius,
               Real density, std::int32_t material, Real spin_scale, std::uint64_t seed);

  // Books `mass` (kg) entering with mean velocity `velocity` and spin `spin` (coarse).
  void feed(Real mass, const Vec3& velocity, const Vec3& spin);
  // At most `mass` (kg) of extra particles, entering with `velocity` (the coarse cell's), at the
  // next place(); then the budget lapses.
  void allow_top_up(Real mass, const Vec3& velocity) {
    top_up_ = mass > 0 ? mass : 0;
    top_up_velocity_ = velocity;
  }
  const Region& shell() const { return shell_; }
  Real max_radius() const { return radius_.max_radius(); }
  // Places scheduled particles (in order), then the top-up; placed ones are appended. Returns
  // how many of the appended came from the flux (the rest are top-up).
  std::size_t place(OccupancyGrid& grid, const WallClearance& walls, std::vector<Vec3>& position,
                    std::vector<Real>& radius);
  bool waiting() const { return !pending_.empty() || top_up_ > 0; }

  std::int32_t material() const { return material_; }
  const Vec3& velocity() const { return velocity_; }
  const Vec3& top_up_velocity() const { return top_up_velocity_; }
  const Vec3& spin() const { return spin_; }
  Real fed_mass() const { return fed_mass_; }
  Real inserted_mass() const { return inserted_mass_; }
  std::int64_t inserted_count() const { return inserted_count_; }
  Real topped_up_mass() const { return topped_up_mass_; }
  // Scheduled but not placed, plus the owed remainder: fed = inserted + pending, exactly up to
  // the rounding of the sums.
  Real pending_mass() const;
  Real mass_of(Real r) const { return density_ * (4.0 / 3.0) * M_PI * r * r * r; }
  // Adds the masses of radius[first:] to `total`, one by one.
  void add_mass(Real& total, const std::vector<Real>& radius, std::size_t first) const;

  std::string save_state() const;
  void load_state(const std::string& state);

 private:
  SizeDistribution radius_;
  Real density_ = 0;
  std::int32_t material_ = 0;
  Real spin_scale_ = 1;
  Region shell_ = Region::box(Vec3::Zero(), Vec3::Ones());
  Rng rng_;
  Real owed_ = 0;  // fed but not yet scheduled (less than next_'s mass)
  Real next_ = 0;  // radius of the next particle to schedule
  std::vector<Real> pending_;
  Vec3 velocity_ = Vec3::Zero(), spin_ = Vec3::Zero();
  Real fed_mass_ = 0, inserted_mass_ = 0;
  std::int64_t inserted_count_ = 0;
  Real top_up_ = 0;  // budget of the next place() (kg)
  Vec3 top_up_velocity_ = Vec3::Zero();
  Real topped_up_mass_ = 0;
};

}  // namespace grainscale
