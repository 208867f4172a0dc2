#include "insert/stream.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/errors.hpp"
#include "insert/placement.hpp"

namespace grainscale {

StreamInserter::StreamInserter(const StreamSpec& spec, Real density)
    : spec_(spec), density_(density), rng_(spec.seed) {
  if (!(spec.mass_rate > 0) || !std::isfinite(spec.mass_rate))
    throw_invalid("Stream.mass_rate", "positive and finite (kg/s)", spec.mass_rate);
  if (!spec.velocity.allFinite())
    throw_invalid("Stream.velocity", "finite (m/s)", spec.velocity.transpose());
  if (!(spec.start >= 0) || !std::isfinite(spec.start))
    throw_invalid("Stream.start", "non-negative and finite (s)", spec.start);
  if (!(spec.stop > spec.start)) throw_invalid("Stream.stop", "greater than start (s)", spec.stop);
  if (!(spec.every >= 0) || !std::isfinite(spec.every))
    throw_invalid("Stream.every", "positive and finite (s)", spec.every);
  if (spec.max_attempts < 1) throw_invalid("Stream.max_attempts", "at least 1", spec.max_attempts);
  const Real r_max = spec.radius.max_radius();
  if (!spec.face.fits(r_max)) {
    std::ostringstream c;
    c << "large enough for the largest particle (diameter " << shortest(2 * r_max) << " m)";
    throw_invalid("Stream.face", c.str(), spec.face.area());
  }
  // The slab lies on the side the velocity points to; with no normal velocity component the face
  // normal decides and the batch interval must be given.
  const Real vn = spec.velocity.dot(spec.face.normal());
  direction_ = vn < 0 ? Vec3(-spec.face.normal()) : spec.face.normal();
  const Real speed = std::abs(vn);
  if (spec.every > 0) {
    every_ = spec.every;
  } else {
    if (!(speed > 0))
      throw_invalid("Stream.every", "given when the velocity has no component across the face (s)",
                    spec.every);
    every_ = 2 * r_max / speed;
  }
  thickness_ = std::max(4 * r_max, speed * every_);
  slab_ = spec.face.slab(direction_, thickness_);
}

bool StreamInserter::schedule(Real time, Real tolerance) {
  bool due = false;
  for (;;) {
    const Real t_k = spec_.start + static_cast<Real>(next_batch_) * every_;
    if (t_k > time + tolerance) break;
    if (t_k < spec_.stop) {
      const Real target = spec_.mass_rate * (std::min(t_k + every_, spec_.stop) - spec_.start);
      while (scheduled_mass_ < target) {
        const Real r = spec_.radius.sample(rng_);
        pending_.push_back(r);
        scheduled_mass_ += mass_of(r);
      }
    }
    ++next_batch_;
    due = true;
  }
  return due && !pending_.empty();
}

void StreamInserter::place(OccupancyGrid& grid, const WallClearance& walls,
                           std::vector<Vec3>& position, std::vector<Real>& radius) {
  const std::size_t before = radius.size();
  place_pending(pending_, slab_, spec_.max_attempts, rng_, grid, walls, position, radius);
  for (std::size_t k = before; k < radius.size(); ++k) {
    inserted_mass_ += mass_of(radius[k]);
    ++inserted_count_;
  }
}

Real StreamInserter::requested_mass(Real time) const {
  const Real t = std::min(time, spec_.stop);
  return t > spec_.start ? spec_.mass_rate * (t - spec_.start) : 0;
}

Real StreamInserter::pending_mass() const {
  Real m = 0;
  for (Real r : pending_) m += mass_of(r);
  return m;
}

std::string StreamInserter::save_state() const {
  std::ostringstream out;
  out.precision(std::numeric_limits<Real>::max_digits10);
  out << "stream-v1 " << spec_.start << ' ' << next_batch_ << ' ' << scheduled_mass_ << ' '
      << inserted_mass_ << ' ' << inserted_count_;
  write_pending(out, pending_, rng_);
  return out.str();
}

void StreamInserter::load_state(const std::string& state) {
  std::istringstream in(state);
  std::string tag;
  std::int64_t batch = 0, count = 0;
  Real start = 0, scheduled = 0, inserted = 0;
  in >> tag >> start >> batch >> scheduled >> inserted >> count;
  std::vector<Real> pending;
  Rng rng;
  read_pending(in, pending, rng);
  if (tag != "stream-v1" || in.fail())
    throw_invalid("Stream state", "text written by get_state() of a stream", "'" + tag + " ...'");
  spec_.start = start;  // as registered in the run that wrote the state (may default to "now")
  next_batch_ = batch;
  scheduled_mass_ = scheduled;
  inserted_mass_ = inserted;
  inserted_count_ = count;
  pending_.swap(pending);
  rng_ = rng;
}

}  // namespace grainscale
