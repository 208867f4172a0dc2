#include "coupling/flux_inserter.hpp"

#include <algorithm>
#include <limits>
#include <sstream>

#include "core/errors.hpp"
#include "insert/placement.hpp"

namespace grainscale {

namespace {

// Random centres tried per grain, and grains in a row that find none before a face gives up
// until the next interval. A face is filled again every interval (10^4 intervals in a run): a
// shell with no room for four grains in a row is full, and the 32 a one-off batch allows
// (placement.hpp) cost the industrial silo most of its exchange time in futile centres
// (studies/silo_industrial/NOTES.md). What finds no room waits; nothing is dropped.
constexpr int kAttempts = 50;
constexpr int kGiveUpAfter = 4;

}  // namespace

FluxInserter::FluxInserter(const InterfaceFace& face, const FieldGrid& grid,
                           const SizeDistribution& radius, Real density, std::int32_t material,
                           Real spin_scale, Real deadband, std::uint64_t seed)
    : radius_(radius),
      density_(density),
      material_(material),
      spin_scale_(spin_scale),
      deadband_(deadband),
      rng_(seed) {
  const int a = face.axis, b = (a + 1) % 3, c = (a + 2) % 3;
  Vec3 e1 = Vec3::Zero(), e2 = Vec3::Zero();
  e1[b] = grid.edge[b];
  e2[c] = grid.edge[c];
  face_size_ = std::max(grid.edge[b], grid.edge[c]);
  const Vec3 corner = face.centre - 0.5 * e1 - 0.5 * e2;
  const Real depth = std::min(4 * radius.max_radius(), grid.edge[a]);
  // From r_min outside the face: centres reach the face (see the header).
  const Real out = radius.min_radius();
  shell_ = Region::parallelepiped(corner - out * face.normal, e1, e2, (depth + out) * face.normal);
  // Placement: the same depth, the face rectangle widened by the largest fine radius on every
  // side, so that a sphere whose centre is on the face may straddle its edges (see the header).
  const Real r = radius.max_radius();
  const Vec3 w1 = e1.normalized() * r, w2 = e2.normalized() * r;
  placing_ = Region::parallelepiped(corner - out * face.normal - w1 - w2, e1 + 2 * w1, e2 + 2 * w2,
                                    (depth + out) * face.normal);
  next_ = radius_.sample(rng_);
}

void FluxInserter::feed(Real mass, const Vec3& velocity, const Vec3& spin) {
  if (!(mass > 0)) return;
  fed_mass_ += mass;
  owed_ += mass;
  velocity_ = velocity;
  spin_ = spin_scale_ * spin;
  settle();
}

void FluxInserter::set_velocity(const Vec3& velocity) {
  velocity_ = velocity;
  spin_ = Vec3::Zero();
}

void FluxInserter::credit(Real mass) {
  if (!(mass > 0)) return;
  credited_mass_ += mass;
  owed_ += mass;
  settle();
}

void FluxInserter::debit(Real mass) {
  if (!(mass > 0)) return;
  debited_mass_ += mass;
  owed_ -= mass;
  settle();
}

void FluxInserter::extracted(Real mass) {
  extracted_mass_ += mass;
  owed_ += mass;
}

void FluxInserter::settle() {
  if (owed_ > 0 && advance_ > 0) {  // what comes in repays the advance first
    const Real repaid = std::min(owed_, advance_);
    owed_ -= repaid;
    advance_ -= repaid;
  }
  // Out of the dead band (or already scheduling): the whole balance.
  if (owed_ > deadband_ || !pending_.empty())
    while (owed_ >= mass_of(next_)) {
      owed_ -= mass_of(next_);
      pending_.push_back(next_);
      next_ = radius_.sample(rng_);
    }
  // A debt cancels what waits, latest first, before anything is taken from the child's bed.
  while (owed_ < 0 && !pending_.empty()) {
    owed_ += mass_of(pending_.back());
    pending_.pop_back();
  }
}

std::size_t FluxInserter::place(OccupancyGrid& grid, const WallClearance& walls,
                                const Domain& domain, const MaterialSight& parent,
                                std::vector<Vec3>& position, std::vector<Real>& radius) {
  const std::size_t before = radius.size();
  place_pending(pending_, placing_, kAttempts, rng_, grid, walls, position, radius, &domain,
                &parent, kGiveUpAfter);
  for (std::size_t k = before; k < radius.size(); ++k) inserted_mass_ += mass_of(radius[k]);
  if (advance_budget_ > 0 && pending_.empty()) {
    // Ahead of the flux, up to the budget, by the same placement rule; what finds no room
    // lapses with the budget.
    std::vector<Real> extra;
    for (Real budget = advance_budget_;;) {
      const Real r = radius_.sample(rng_);
      if (mass_of(r) > budget) break;
      budget -= mass_of(r);
      extra.push_back(r);
    }
    const std::size_t start = radius.size();
    place_pending(extra, placing_, kAttempts, rng_, grid, walls, position, radius, &domain, &parent,
                  kGiveUpAfter);
    for (std::size_t k = start; k < radius.size(); ++k) {
      inserted_mass_ += mass_of(radius[k]);
      advanced_mass_ += mass_of(radius[k]);
      advance_ += mass_of(radius[k]);
    }
  }
  advance_budget_ = 0;
  const std::size_t placed = radius.size() - before;
  inserted_count_ += static_cast<std::int64_t>(placed);
  return placed;
}

Real FluxInserter::pending_mass() const {
  Real m = owed_ - advance_;
  for (Real r : pending_) m += mass_of(r);
  return m;
}

std::string FluxInserter::save_state() const {
  std::ostringstream out;
  out.precision(std::numeric_limits<Real>::max_digits10);
  out << "flux-v3 " << owed_ << ' ' << next_ << ' ' << fed_mass_ << ' ' << credited_mass_ << ' '
      << debited_mass_ << ' ' << inserted_mass_ << ' ' << extracted_mass_ << ' ' << advanced_mass_
      << ' ' << advance_ << ' ' << inserted_count_ << ' ' << velocity_[0] << ' ' << velocity_[1]
      << ' ' << velocity_[2] << ' ' << spin_[0] << ' ' << spin_[1] << ' ' << spin_[2];
  write_pending(out, pending_, rng_);
  return out.str();
}

void FluxInserter::load_state(const std::string& state) {
  std::istringstream in(state);
  std::string tag;
  Real owed = 0, next = 0, fed = 0, credited = 0, debited = 0, inserted = 0, extracted = 0;
  Real advanced = 0, advance = 0, topped = 0;
  std::int64_t count = 0;
  Vec3 v, w;
  in >> tag;
  if (tag == "flux-v3") {
    in >> owed >> next >> fed >> credited >> debited >> inserted >> extracted >> advanced >>
        advance >> count;
  } else {
    if (tag == "flux-v2") in >> topped;  // v1: written before the top-up
    in >> owed >> next >> fed >> inserted >> count;
  }
  in >> v[0] >> v[1] >> v[2] >> w[0] >> w[1] >> w[2];
  std::vector<Real> pending;
  Rng rng;
  read_pending(in, pending, rng);
  if ((tag != "flux-v1" && tag != "flux-v2" && tag != "flux-v3") || in.fail())
    throw_invalid("FluxInserter state", "text written by save_state()", "'" + tag + " ...'");
  owed_ = owed;
  next_ = next;
  fed_mass_ = fed;
  credited_mass_ = credited;
  debited_mass_ = debited;
  inserted_mass_ = inserted;
  extracted_mass_ = extracted;
  advanced_mass_ = advanced;
  advance_ = advance;
  advance_budget_ = 0;
  inserted_count_ = count;
  velocity_ = v;
  spin_ = w;
  pending_.swap(pending);
  rng_ = rng;
}

}  // namespace grainscale
