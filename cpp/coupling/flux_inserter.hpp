// The transfer ledger of one interface face between a level of a hierarchy (the parent) and the
// finer level in its region (the child), DESIGN.md 4, and the child's insertion there.
//
// The parent's crossings define what passes the face; the child's content follows them exactly:
//   feed    mass the parent carried in across the face (FaceFluxMeter): owed to the child
//   debit   mass the parent carried out across the face: the child owes it
//   credit  mass of the child's particles that left its region through the face (deleted by the
//           region outlet): owed back to the child, since the parent did not carry it out
// The signed balance, owed = fed + credited - debited - inserted + extracted, is paid by the
// child once it leaves a dead band of +-`deadband` (the mass of one parent particle: a parent
// particle that crosses the face and back, as one sitting on it does, causes no churn): above
// it, fine particles drawn from the fine size distribution are scheduled for the whole balance
// (the unscheduled remainder is less than one fine particle) and placed without overlaps in a
// shell at the face; a negative balance cancels scheduled particles first, and below the band
// the child's particles nearest the face are removed for the whole balance (extracted, by the
// Interface). So fed + credited - debited = inserted - extracted + pending exactly, up to the
// rounding of the sums, with pending = owed + scheduled (signed: negative is the child's debt).
//
// Advance: where the parent holds a dense bed beyond a face, that bed sinks into any room the
// child's bed leaves below it, which the parent's crossings deliver only later (and, its packing
// being its own, in other amounts per cell). An advance budget lets the inserter place extra
// particles now; the advance stays outstanding (negative pending) until what the parent then
// carries in repays it, before anything more is scheduled. So the books stay exact:
// fed + credited - debited = inserted - extracted + pending, pending = owed + scheduled -
// outstanding advance.
//
// The shell is the face rectangle, two largest fine diameters deep (at most the cell's depth),
// starting one smallest fine radius outside the face, so that centres reach the face as the
// grains of the bed beyond do (a shell flush with the face would leave the face's cell short of
// a layer r thick). Particles are placed with the parent's bulk velocity at the face (its Favre
// velocity in the face's cell, not the crossings' speed-weighted mean: Interface::book) and the
// inflow spin scaled by the size ratio (w R kept: the surface speed of a spinning grain); what
// finds no room waits. A placed sphere needs its centre over the face rectangle, not the whole
// sphere inside it: a face is a few fine diameters across, and whole spheres would leave the rim
// unusable (half the area of a 7.5 mm face for 2 mm grains), so that a dense inflow, a pour or a
// sinking bed, could not be carried: the fine bed then formed loose and short of the parent's mass
// (jam study, stop 23).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "field/exchange_grid.hpp"
#include "insert/occupancy_grid.hpp"
#include "insert/placement.hpp"
#include "insert/random.hpp"
#include "insert/region.hpp"
#include "insert/size_distribution.hpp"
#include "insert/wall_clearance.hpp"

namespace grainscale {

class FluxInserter {
 public:
  // spin_scale: coarse / fine particle size, applied to the fed spin; deadband (kg).
  FluxInserter(const InterfaceFace& face, const FieldGrid& grid, const SizeDistribution& radius,
               Real density, std::int32_t material, Real spin_scale, Real deadband,
               std::uint64_t seed);

  // Books `mass` (kg) entering; what is placed gets `velocity` (m/s) and `spin` (coarse, rad/s).
  void feed(Real mass, const Vec3& velocity, const Vec3& spin);
  // Velocity (and zero spin) of the particles placed after an interval without inflow.
  void set_velocity(const Vec3& velocity);
  void credit(Real mass);
  void debit(Real mass);
  // At most `mass` (kg) of particles placed ahead of the flux at the next place(), with the
  // current velocity; then the budget lapses.
  void allow_advance(Real mass) { advance_budget_ = mass > 0 ? mass : 0; }
  Real outstanding_advance() const { return advance_; }
  // Mass (kg) the child owes at this face now, once beyond the dead band: what extraction must
  // remove.
  Real owing() const { return owed_ < -deadband_ ? -owed_ : 0; }
  // Books child particles of `mass` (kg) removed to pay owing().
  void extracted(Real mass);

  const Region& shell() const { return shell_; }
  const Region& placing_region() const { return placing_; }
  Real max_radius() const { return radius_.max_radius(); }
  // The longer edge of the face (m).
  Real face_size() const { return face_size_; }
  // Places scheduled particles (in order), then, if none waits, up to the advance budget; placed
  // ones are appended. Returns how many. Centres stay inside `domain` (the placing region,
  // widened past the face's edges, may reach beyond a closed side where a region face lies), and
  // where the parent's material reaches (`parent`: its particles there, MaterialSight): a child
  // grain never goes where no parent grain can be, under a floor or behind a curved wall that a
  // face's cell straddles, which the clearance test alone does not tell from the bed's side
  // (studies/silo_industrial/NOTES.md).
  std::size_t place(OccupancyGrid& grid, const WallClearance& walls, const Domain& domain,
                    const MaterialSight& parent, std::vector<Vec3>& position,
                    std::vector<Real>& radius);
  bool waiting() const { return !pending_.empty() || advance_budget_ > 0; }

  std::int32_t material() const { return material_; }
  const Vec3& velocity() const { return velocity_; }
  const Vec3& spin() const { return spin_; }
  Real fed_mass() const { return fed_mass_; }
  Real credited_mass() const { return credited_mass_; }
  Real debited_mass() const { return debited_mass_; }
  Real inserted_mass() const { return inserted_mass_; }
  Real extracted_mass() const { return extracted_mass_; }
  Real advanced_mass() const { return advanced_mass_; }  // placed ahead, in all
  std::int64_t inserted_count() const { return inserted_count_; }
  // Scheduled but not placed, plus the signed unscheduled balance, less the outstanding advance
  // (see the header).
  Real pending_mass() const;
  Real mass_of(Real r) const { return density_ * (4.0 / 3.0) * M_PI * r * r * r; }

  std::string save_state() const;
  // Reads every format save_state() has written ("flux-v1" and "flux-v2" from before the ledger:
  // nothing credited, debited, extracted or advanced; v2's top-up mass, placed outside the books,
  // is not kept).
  void load_state(const std::string& state);

 private:
  // Repays the advance from a positive balance, turns the rest into scheduled particles, or
  // cancels scheduled ones against a negative balance.
  void settle();

  SizeDistribution radius_;
  Real density_ = 0;
  std::int32_t material_ = 0;
  Real spin_scale_ = 1;
  Real face_size_ = 0;
  Real deadband_ = 0;
  Region shell_ = Region::box(Vec3::Zero(), Vec3::Ones());    // extraction: centres on the face
  Region placing_ = Region::box(Vec3::Zero(), Vec3::Ones());  // placement: spheres may straddle
  Rng rng_;
  Real owed_ = 0;  // signed unscheduled balance (less than next_'s mass when positive)
  Real next_ = 0;  // radius of the next particle to schedule
  std::vector<Real> pending_;
  Vec3 velocity_ = Vec3::Zero(), spin_ = Vec3::Zero();
  Real fed_mass_ = 0, credited_mass_ = 0, debited_mass_ = 0, inserted_mass_ = 0,
       extracted_mass_ = 0, advanced_mass_ = 0;
  Real advance_ = 0;         // outstanding (kg)
  Real advance_budget_ = 0;  // of the next place() (kg)
  std::int64_t inserted_count_ = 0;
};

}  // namespace grainscale
