// Level: packing, scheduled stream insertion, outlets and particle deletion (the per-step hook of
// run() lives here). See insert/*.hpp for the algorithms and their bookkeeping.
#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_set>

#include "core/errors.hpp"
#include "coupling/exchange_grid.hpp"
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

}  // namespace

std::pair<GlobalId, Index> Level::pack(const PackSpec& spec) {
  if (spec.material < 0 || spec.material >= materials_.n_materials())
    throw_invalid("Pack.material", "a material known to the simulation", spec.material);
  if (!materials_.deformable(spec.material))
    throw_invalid("Pack.material", "deformable (finite youngs_modulus)", spec.material);
  if ((spec.count >= 0) == (spec.volume_fraction >= 0))
    throw_invalid("Pack", "given exactly one of count and volume_fraction", "both or neither");
  if (spec.volume_fraction >= 0 && !(spec.volume_fraction <= 1))
    throw_invalid("Pack.volume_fraction", "in [0, 1]", spec.volume_fraction);
  if (!spec.velocity.allFinite())
    throw_invalid("Pack.velocity", "finite (m/s)", spec.velocity.transpose());
  if (spec.max_attempts < 1) throw_invalid("Pack.max_attempts", "at least 1", spec.max_attempts);
  require_inside(spec.region, domain_, "Pack.region");
  const PackSpec s = dimension_ == 2 ? planar_pack_spec(spec) : spec;

  Rng rng(s.seed);
  const std::vector<Real> radii = pack_radii(s, rng);
  if (radii.empty()) return {next_id_, 0};
  Vec3 lo, hi;
  s.region.bounds(lo, hi);
  // Every rank places the same particles among all ranks' spheres; add_particles keeps its own.
  Real r_old = 0;
  const SphereSet present = gather_nearby(lo, hi, radii.front(), r_old);
  OccupancyGrid grid(lo, hi, radii.front(), r_old, present, domain_);
  const WallClearance walls(walls_, lo, hi, radii.front());
  const Placement p = place_in_region(s, radii, grid, walls, rng);

  const Index n = static_cast<Index>(p.radius.size());
  std::vector<Real> x(3 * n), v(3 * n);
  for (Index k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      x[3 * k + a] = p.position[k][a];
      v[3 * k + a] = s.velocity[a];
    }
  const std::vector<std::int32_t> mat(n, s.material);
  const GlobalId first = add_particles(n, x.data(), v.data(), nullptr, p.radius.data(), mat.data());
  return {first, n};
}

PackSpec Level::planar_pack_spec(const PackSpec& spec) const {
  Vec3 lo, hi;
  spec.region.bounds(lo, hi);
  const Real z = plane_z();
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

int Level::add_stream(const StreamSpec& spec) {
  if (dimension_ == 2)
    throw_invalid("Simulation.insert(Stream)", "used in 3-D only (dimension=3)", "dimension=2");
  if (spec.material < 0 || spec.material >= materials_.n_materials())
    throw_invalid("Stream.material", "a material known to the simulation", spec.material);
  if (!materials_.deformable(spec.material))
    throw_invalid("Stream.material", "deformable (finite youngs_modulus)", spec.material);
  StreamInserter s(spec, materials_[spec.material].density);
  require_inside(s.slab(), domain_,
                 "Stream.face (with its insertion slab " + shortest(s.thickness()) +
                     " m deep on the side the velocity points to)");
  const MaterialProperties& m = materials_[spec.material];
  const Real t_r =
      rayleigh_time(spec.radius.min_radius(), m.density, m.youngs_modulus, m.poisson_ratio);
  if (dt_ > 0 && !force_dt_ && dt_ > kMaxRayleighFraction * t_r) {
    std::ostringstream c;
    c << "at most 0.3 x the Rayleigh time of the smallest streamed particle ("
      << kMaxRayleighFraction * t_r << " s); pass force_time_step=True to override";
    throw_invalid("Simulation.time_step", c.str(), dt_);
  }
  streams_.push_back(std::move(s));
  return static_cast<int>(streams_.size()) - 1;
}

int Level::add_outlet(const OutletSpec& spec) {
  outlets_.emplace_back(spec, time_);
  return static_cast<int>(outlets_.size()) - 1;
}

Real Level::smallest_insertion_rayleigh_time() const {
  Real t = INFINITY;
  for (const StreamInserter& s : streams_) {
    const MaterialProperties& m = materials_[s.spec().material];
    t = std::min(t, rayleigh_time(s.spec().radius.min_radius(), m.density, m.youngs_modulus,
                                  m.poisson_ratio));
  }
  return t;
}

void Level::remove_owned(const std::vector<Index>& indices) {
  const Index n = ps_.n_owned();
  std::vector<char> drop(n, 0);
  for (Index i : indices) {
    if (i < 0 || i >= n) throw_invalid("remove_owned.index", "an owned particle index", i);
    drop[i] = 1;
  }
  if (indices.empty()) return;
  // As in add_particles/rebuild: histories are keyed by global ids while the lists are valid,
  // and origin_ maps each survivor to the index it had then, so rebuild() restores them.
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  ps_.clear_ghosts();
  ghosts_.clear();
  std::vector<Index> order;
  order.reserve(n);
  for (Index i = 0; i < n; ++i)
    if (!drop[i]) order.push_back(i);
  ps_.select_owned(order);
  std::vector<Index> new_origin(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_origin[k] = origin_[order[k]];
  origin_.swap(new_origin);
}

std::int64_t Level::remove_particles(const std::vector<GlobalId>& ids) {
  const std::unordered_set<GlobalId> wanted(ids.begin(), ids.end());
  std::vector<Index> indices;
  for (Index i = 0; i < ps_.n_owned(); ++i)
    if (wanted.count(ps_.id[i])) indices.push_back(i);
  // The stored forces stay exact unless a removed particle touched a survivor (forces are then
  // re-evaluated before the next step). Every pair is stored on one rank, and every rank knows
  // all removed ids, so the ranks' verdicts combine to the serial one. Unknown contacts (lists
  // invalid): re-evaluate.
  bool touched = !lists_valid_ && !indices.empty();
  for (Index i = 0; lists_valid_ && i < ps_.n_owned() && !touched; ++i) {
    const bool gone = wanted.count(ps_.id[i]) > 0;
    for (Index k = pairs_.first[i]; k < pairs_.first[i + 1]; ++k)
      if (pairs_.touching[k] && gone != (wanted.count(ps_.id[pairs_.partner[k]]) > 0))
        touched = true;
  }
  remove_owned(indices);
  if (comm_.any(touched)) forces_valid_ = false;
  return comm_.sum(static_cast<std::int64_t>(indices.size()));
}

// Checkpoints: the complete mutable state of every stream (batch counter, masses, pending
// particles, random engine) and outlet (counters, history) as text; the set-up itself is
// re-created by the script and checked through signature().
void Level::save_insertion_state(LevelState& s) const {
  for (std::size_t k = 0; k < streams_.size(); ++k)
    s.texts["stream/" + std::to_string(k)] = streams_[k].save_state();
  for (std::size_t k = 0; k < outlets_.size(); ++k)
    s.texts["outlet/" + std::to_string(k)] = outlets_[k].save_state();
}

void Level::load_insertion_state(const LevelState& s) {
  auto text = [&](const std::string& key) -> const std::string& {
    const auto it = s.texts.find(key);
    if (it == s.texts.end()) throw std::runtime_error("checkpoint lacks the state of " + key);
    return it->second;
  };
  for (std::size_t k = 0; k < streams_.size(); ++k)
    streams_[k].load_state(text("stream/" + std::to_string(k)));
  for (std::size_t k = 0; k < outlets_.size(); ++k)
    outlets_[k].load_state(text("outlet/" + std::to_string(k)));
}

void Level::apply_insertions_and_outlets() {
  // The step evaluates the forces of every particle right after this hook, so adding or removing
  // particles here must not mark the forces invalid: that would make the next run() re-evaluate
  // them (without history update) and the result depend on how run() is chunked.
  const bool forces_valid = forces_valid_;
  // Outlets first: removing particles frees room for the inserters of the same step.
  if (!outlets_.empty()) apply_outlets();
  if (!streams_.empty()) run_streams();
  forces_valid_ = forces_valid;
}

void Level::apply_outlets() {
  std::vector<Index> gone;
  std::vector<char> taken;  // a particle inside two outlets is counted by the first
  // Per outlet due now, summed over the ranks: count, mass, moment (3), then the face masses of
  // an outlet with a `keep` grid.
  std::vector<Real> tally;
  for (Outlet& outlet : outlets_) {
    if (!outlet.due(step_)) continue;
    const Region& region = outlet.spec().region;
    const ExchangeGrid* keep = outlet.spec().keep.get();
    const Real band = outlet.spec().band;
    // Most particles are far from an outlet: a bounding-box test first (this runs every step).
    Vec3 lo, hi;
    region.bounds(lo, hi);
    const std::size_t at = tally.size();
    tally.resize(at + 5 + outlet.n_faces(), 0.0);
    for (Index i = 0; i < ps_.n_owned(); ++i) {
      const Vec3 x = wrapped(domain_, ps_.position[i]);
      if (keep ? keep->near_region(x, band)
               : (x[0] < lo[0] || x[1] < lo[1] || x[2] < lo[2] || x[0] > hi[0] || x[1] > hi[1] ||
                  x[2] > hi[2] || !region.contains(x)))
        continue;
      if (!taken.empty() && taken[i]) continue;
      if (outlets_.size() > 1) {
        taken.resize(ps_.n_owned(), 0);
        taken[i] = 1;
      }
      gone.push_back(i);
      const Real m = ps_.mass[i];
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
  comm_.sum_in_place(tally);
  std::size_t at = 0;
  for (Outlet& outlet : outlets_) {
    if (!outlet.due(step_)) continue;
    const auto count = static_cast<std::int64_t>(tally[at]);
    const std::size_t nf = outlet.n_faces();
    if (count > 0)
      outlet.record(time_, count, tally[at + 1], Vec3(tally[at + 2], tally[at + 3], tally[at + 4]),
                    std::vector<Real>(tally.begin() + at + 5, tally.begin() + at + 5 + nf));
    at += 5 + nf;
  }
  if (!gone.empty()) remove_owned(gone);
}

std::int64_t Level::insert_flux(std::vector<FluxInserter>& inserters) {
  // One occupancy grid over every shell with particles waiting (the same on every rank).
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  Real max_new = 0;
  for (const FluxInserter& f : inserters) {
    if (!f.waiting()) continue;
    Vec3 a, b;
    f.placing_region().bounds(a, b);
    lo = lo.cwiseMin(a);
    hi = hi.cwiseMax(b);
    max_new = std::max(max_new, f.max_radius());
  }
  if (!(max_new > 0)) return 0;
  Real r_old = 0;
  const SphereSet present = gather_nearby(lo, hi, max_new, r_old);
  OccupancyGrid grid(lo, hi, max_new, r_old, present, domain_);
  const WallClearance walls(walls_, lo, hi, max_new);
  std::int64_t placed = 0;
  std::vector<Vec3> x;
  std::vector<Real> r;
  for (FluxInserter& f : inserters) {
    if (!f.waiting()) continue;
    x.clear();
    r.clear();
    f.place(grid, walls, x, r);
    if (r.empty()) continue;
    const Index n = static_cast<Index>(r.size());
    std::vector<Real> flat(3 * n), v(3 * n), w(3 * n);
    for (Index k = 0; k < n; ++k)
      for (int a = 0; a < 3; ++a) {
        flat[3 * k + a] = x[k][a];
        v[3 * k + a] = f.velocity()[a];
        w[3 * k + a] = f.spin()[a];
      }
    const std::vector<std::int32_t> mat(n, f.material());
    add_particles(n, flat.data(), v.data(), w.data(), r.data(), mat.data());
    placed += n;
  }
  return placed;
}

int Level::add_coupling(CouplingForces forces) {
  couplings_.push_back(std::move(forces));
  forces_valid_ = false;
  return static_cast<int>(couplings_.size()) - 1;
}

CouplingForces& Level::coupling(int index) {
  if (index < 0 || index >= static_cast<int>(couplings_.size()))
    throw_invalid("coupling index", "in [0, " + std::to_string(couplings_.size()) + ")", index);
  return couplings_[index];
}

std::vector<Real> Level::coupling_push_scale(const CouplingForces& c) {
  if (c.pressure.empty()) return {};  // no stress condition (every rank alike): nothing pushed
  std::vector<Real> total = c.push_total(ps_, domain_);
  comm_.sum_in_place(total);
  return c.push_scale(total);
}

std::vector<Real> Level::coupling_push_moment(int index) {
  const CouplingForces& c = coupling(index);
  std::vector<Real> moment = c.push_moment(ps_, domain_, coupling_push_scale(c));
  comm_.sum_in_place(moment);
  return moment;
}

void Level::run_streams() {
  const Real tolerance = 1e-6 * dt_;  // a batch due at t_k runs at the first step with t >= t_k
  std::vector<Vec3> x;
  std::vector<Real> r;
  for (StreamInserter& s : streams_) {
    if (!s.schedule(time_, tolerance)) continue;
    Vec3 lo, hi;
    s.slab().bounds(lo, hi);
    Real r_old = 0;
    const SphereSet present = gather_nearby(lo, hi, s.spec().radius.max_radius(), r_old);
    OccupancyGrid grid(lo, hi, s.spec().radius.max_radius(), r_old, present, domain_);
    // The walls where they are now (they moved before this hook in the step).
    const WallClearance walls(walls_, lo, hi, s.spec().radius.max_radius());
    x.clear();
    r.clear();
    s.place(grid, walls, x, r);
    if (r.empty()) continue;
    const Index n = static_cast<Index>(r.size());
    std::vector<Real> flat(3 * n), v(3 * n);
    for (Index k = 0; k < n; ++k)
      for (int a = 0; a < 3; ++a) {
        flat[3 * k + a] = x[k][a];
        v[3 * k + a] = s.spec().velocity[a];
      }
    const std::vector<std::int32_t> mat(n, s.spec().material);
    add_particles(n, flat.data(), v.data(), nullptr, r.data(), mat.data());
  }
}

}  // namespace grainscale
