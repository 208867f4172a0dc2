// Insertion: packing, scheduled stream insertion and outlets (the per-step hook of Level::run).
#include "level/insertion.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/errors.hpp"
#include "field/exchange_grid.hpp"
#include "integrate/time_step.hpp"
#include "level/level.hpp"

namespace grainscale {

namespace {

// Throws unless the region's bounding box lies inside the domain (on every axis: the placement
// does not wrap periodic images of the new particles).
void require_inside(const Region& region, const Domain& domain, const std::string& what) {
  Vec3 lo, hi;
  region.bounds(lo, hi);
  for (int a = 0; a < 3; ++a) {
    const Real tol = 1e-12 * (domain.hi[a] - domain.lo[a]);
    if (lo[a] < domain.lo[a] - tol || hi[a] > domain.hi[a] + tol) {
      std::ostringstream c, v;
      c << "inside the simulation domain [" << shortest(domain.lo[a]) << ", "
        << shortest(domain.hi[a]) << "] on axis " << "xyz"[a];
      v << "[" << shortest(lo[a]) << ", " << shortest(hi[a]) << "]";
      throw_invalid(what, c.str(), v.str());
    }
  }
}

// Position mapped into the box on periodic axes (owned positions drift out of it between
// rebuilds by less than a box length).
Vec3 wrapped(const Domain& d, Vec3 x) {
  for (int a = 0; a < 3; ++a) {
    if (!d.periodic[a]) continue;
    const Real len = d.hi[a] - d.lo[a];
    if (x[a] < d.lo[a]) x[a] += len;
    if (x[a] >= d.hi[a]) x[a] -= len;
  }
  return x;
}

// The pack spec of the 2-D mode: discs in the plane z, inside the region's x-y rectangle.
PackSpec planar_pack_spec(const PackSpec& spec, Real z) {
  Vec3 lo, hi;
  spec.region.bounds(lo, hi);
  if (!(lo[2] <= z && z <= hi[2])) {
    std::ostringstream c;
    c << "to contain the plane z = " << shortest(z) << " m of the 2-D mode";
    throw_invalid("Pack.region z range", c.str(),
                  "[" + shortest(lo[2]) + ", " + shortest(hi[2]) + "]");
  }
  // The x-y rectangle of the region, as a slab thick enough in z for every disc.
  PackSpec s = spec;
  const Real half = spec.radius.max_radius();
  s.region = Region::box(Vec3(lo[0], lo[1], z - half), Vec3(hi[0], hi[1], z + half));
  s.planar = true;
  s.plane_z = z;
  return s;
}

}  // namespace

std::pair<GlobalId, Index> Insertion::pack(Level& level, const PackSpec& spec) {
  const MaterialTable& materials = level.materials();
  if (spec.material < 0 || spec.material >= materials.n_materials())
    throw_invalid("Pack.material", "a material known to the simulation", spec.material);
  if (!materials.deformable(spec.material))
    throw_invalid("Pack.material", "deformable (finite youngs_modulus)", spec.material);
  if ((spec.count >= 0) == (spec.volume_fraction >= 0))
    throw_invalid("Pack", "given exactly one of count and volume_fraction", "both or neither");
  if (spec.volume_fraction >= 0 && !(spec.volume_fraction <= 1))
    throw_invalid("Pack.volume_fraction", "in [0, 1]", spec.volume_fraction);
  if (!spec.velocity.allFinite())
    throw_invalid("Pack.velocity", "finite (m/s)", spec.velocity.transpose());
  if (spec.max_attempts < 1) throw_invalid("Pack.max_attempts", "at least 1", spec.max_attempts);
  require_inside(spec.region, level.domain(), "Pack.region");
  const PackSpec s = level.dimension() == 2 ? planar_pack_spec(spec, level.plane_z()) : spec;

  Rng rng(s.seed);
  const std::vector<Real> radii = pack_radii(s, rng);
  if (radii.empty()) return {level.next_id(), 0};
  Vec3 lo, hi;
  s.region.bounds(lo, hi);
  // Every rank places the same particles among all ranks' spheres; add_particles keeps its own.
  InsertionSite site = level.insertion_site(lo, hi, radii.front());
  const Placement p = place_in_region(s, radii, site.grid, site.walls, rng);
  const GlobalId first =
      level.place_particles(p.position, p.radius, s.velocity, nullptr, s.material);
  return {first, static_cast<Index>(p.radius.size())};
}

int Insertion::add_stream(const Level& level, const StreamSpec& spec) {
  if (level.dimension() == 2)
    throw_invalid("Simulation.insert(Stream)", "used in 3-D only (dimension=3)", "dimension=2");
  const MaterialTable& materials = level.materials();
  if (spec.material < 0 || spec.material >= materials.n_materials())
    throw_invalid("Stream.material", "a material known to the simulation", spec.material);
  if (!materials.deformable(spec.material))
    throw_invalid("Stream.material", "deformable (finite youngs_modulus)", spec.material);
  StreamInserter s(spec, materials[spec.material].density);
  require_inside(s.slab(), level.domain(),
                 "Stream.face (with its insertion slab " + shortest(s.thickness()) +
                     " m deep on the side the velocity points to)");
  const MaterialProperties& m = materials[spec.material];
  const Real t_r =
      rayleigh_time(spec.radius.min_radius(), m.density, m.youngs_modulus, m.poisson_ratio);
  const Real dt = level.time_step();
  if (dt > 0 && !level.force_time_step() && dt > kMaxRayleighFraction * t_r) {
    std::ostringstream c;
    c << "at most 0.3 x the Rayleigh time of the smallest streamed particle ("
      << kMaxRayleighFraction * t_r << " s); pass force_time_step=True to override";
    throw_invalid("Simulation.time_step", c.str(), dt);
  }
  streams_.push_back(std::move(s));
  return static_cast<int>(streams_.size()) - 1;
}

int Insertion::add_outlet(const OutletSpec& spec, Real time, OutletKeep keep) {
  outlets_.emplace_back(spec, time);
  keeps_.push_back(std::move(keep));
  return static_cast<int>(outlets_.size()) - 1;
}

Real Insertion::smallest_rayleigh_time(const MaterialTable& materials) const {
  Real t = INFINITY;
  for (const StreamInserter& s : streams_) {
    const MaterialProperties& m = materials[s.spec().material];
    t = std::min(t, rayleigh_time(s.spec().radius.min_radius(), m.density, m.youngs_modulus,
                                  m.poisson_ratio));
  }
  return t;
}

// Checkpoints: the complete mutable state of every stream (batch counter, masses, pending
// particles, random engine) and outlet (counters, history) as text; the set-up itself is
// re-created by the script and checked through the level's signature.
void Insertion::save_state(LevelState& s) const {
  for (std::size_t k = 0; k < streams_.size(); ++k)
    s.texts["stream/" + std::to_string(k)] = streams_[k].save_state();
  for (std::size_t k = 0; k < outlets_.size(); ++k)
    s.texts["outlet/" + std::to_string(k)] = outlets_[k].save_state();
}

namespace {

const std::string& saved_text(const LevelState& s, const std::string& key) {
  const auto it = s.texts.find(key);
  if (it == s.texts.end()) throw std::runtime_error("checkpoint lacks the state of " + key);
  return it->second;
}

}  // namespace

void Insertion::load_state(const LevelState& s) {
  for (std::size_t k = 0; k < streams_.size(); ++k)
    streams_[k].load_state(saved_text(s, "stream/" + std::to_string(k)));
  for (std::size_t k = 0; k < outlets_.size(); ++k)
    outlets_[k].load_state(saved_text(s, "outlet/" + std::to_string(k)));
}

void Insertion::check_state(const LevelState& s) const {
  for (std::size_t k = 0; k < streams_.size(); ++k) {
    StreamInserter copy = streams_[k];
    copy.load_state(saved_text(s, "stream/" + std::to_string(k)));
  }
  for (std::size_t k = 0; k < outlets_.size(); ++k) {
    Outlet copy = outlets_[k];
    copy.load_state(saved_text(s, "outlet/" + std::to_string(k)));
  }
}

void Insertion::step(Level& level) {
  if (!outlets_.empty()) apply_outlets(level);
  if (!streams_.empty()) run_streams(level);
}

void Insertion::apply_outlets(Level& level) {
  const ParticleStore& ps = level.particles();
  const Domain& domain = level.domain();
  const std::int64_t step = level.step();
  std::vector<Index> gone;
  std::vector<char> taken;  // a particle inside two outlets is counted by the first
  // Per outlet due now, summed over the ranks: count, mass, moment (3), then the face masses of
  // an outlet with a `keep` grid.
  std::vector<Real> tally;
  for (std::size_t k = 0; k < outlets_.size(); ++k) {
    Outlet& outlet = outlets_[k];
    if (!outlet.due(step)) continue;
    const Region& region = outlet.spec().region;
    const ExchangeGrid* keep = keeps_[k].grid.get();
    const Real band = keeps_[k].band;
    // Most particles are far from an outlet: a bounding-box test first (this runs every step).
    Vec3 lo, hi;
    region.bounds(lo, hi);
    const std::size_t at = tally.size();
    tally.resize(at + 5 + outlet.n_faces(), 0.0);
    for (Index i = 0; i < ps.n_owned(); ++i) {
      const Vec3 x = wrapped(domain, ps.position[i]);
      if (keep ? keep->near_region(x, band)
               : (x[0] < lo[0] || x[1] < lo[1] || x[2] < lo[2] || x[0] > hi[0] || x[1] > hi[1] ||
                  x[2] > hi[2] || !region.contains(x)))
        continue;
      if (!taken.empty() && taken[i]) continue;
      if (outlets_.size() > 1) {
        taken.resize(ps.n_owned(), 0);
        taken[i] = 1;
      }
      gone.push_back(i);
      const Real m = ps.mass[i];
      tally[at] += 1;
      tally[at + 1] += m;
      for (int a = 0; a < 3; ++a) tally[at + 2 + a] += m * x[a];
      if (keep) {
        const int f = keep->nearest_face(x);
        if (f >= 0) tally[at + 5 + f] += m;
      }
    }
  }
  if (tally.empty()) return;  // no outlet due (the same on every rank: a function of the step)
  level.comm().sum_in_place(tally);
  std::size_t at = 0;
  for (Outlet& outlet : outlets_) {
    if (!outlet.due(step)) continue;
    const auto count = static_cast<std::int64_t>(tally[at]);
    const std::size_t nf = outlet.n_faces();
    if (count > 0)
      outlet.record(level.time(), count, tally[at + 1],
                    Vec3(tally[at + 2], tally[at + 3], tally[at + 4]),
                    std::vector<Real>(tally.begin() + at + 5, tally.begin() + at + 5 + nf));
    at += 5 + nf;
  }
  if (!gone.empty()) level.remove_owned(gone);
}

void Insertion::run_streams(Level& level) {
  const Real tolerance = 1e-6 * level.time_step();  // a batch due at t_k runs at the first
                                                    // step with t >= t_k
  std::vector<Vec3> x;
  std::vector<Real> r;
  for (StreamInserter& s : streams_) {
    if (!s.schedule(level.time(), tolerance)) continue;
    Vec3 lo, hi;
    s.slab().bounds(lo, hi);
    // The walls where they are now (they moved before this hook in the step).
    InsertionSite site = level.insertion_site(lo, hi, s.spec().radius.max_radius());
    x.clear();
    r.clear();
    s.place(site.grid, site.walls, x, r);
    if (r.empty()) continue;
    level.place_particles(x, r, s.spec().velocity, nullptr, s.spec().material);
  }
}

}  // namespace grainscale
