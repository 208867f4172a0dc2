// Level: construction, configuration (materials, interactions, gravity, time step, skin,
// dimension), adding and placing particles, and the diagnostics read from Python.
#include "level/level.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "integrate/time_step.hpp"
#include "state/body_shape.hpp"

namespace grainscale {

Level::Level(const Domain& domain, Communicator comm)
    : domain_(domain),
      law_(make_contact_law("hertz", "none", ContactSettings{})),
      comm_(std::move(comm)),
      partition_(comm_.parallel()) {}

namespace {

void validate(const Interaction& in) {
  if (!(in.restitution >= 0 && in.restitution <= 1))
    throw_invalid("restitution", "in [0, 1]", in.restitution);
  if (!(in.friction >= 0) || !std::isfinite(in.friction))
    throw_invalid("friction", "non-negative and finite", in.friction);
  if (!(in.rolling_friction >= 0) || !std::isfinite(in.rolling_friction))
    throw_invalid("rolling_friction", "non-negative and finite", in.rolling_friction);
  if (!(in.rolling_damping >= 0) || !std::isfinite(in.rolling_damping))
    throw_invalid("rolling_damping", "non-negative and finite", in.rolling_damping);
  if (!(in.normal_stiffness >= 0) || !std::isfinite(in.normal_stiffness))
    throw_invalid("normal_stiffness", "non-negative (N/m; 0 derives it)", in.normal_stiffness);
  if (!(in.tangential_stiffness >= 0) || !std::isfinite(in.tangential_stiffness))
    throw_invalid("tangential_stiffness", "non-negative (N/m; 0 means 2/7 k_n)",
                  in.tangential_stiffness);
  if (!(in.characteristic_velocity > 0) || !std::isfinite(in.characteristic_velocity))
    throw_invalid("characteristic_velocity", "positive (m/s)", in.characteristic_velocity);
  if (!(in.eepa_exponent == 1 || in.eepa_exponent == 1.5))
    throw_invalid("exponent", "1 or 1.5", in.eepa_exponent);
  if (!(in.loading_stiffness >= 0) || !std::isfinite(in.loading_stiffness))
    throw_invalid("loading_stiffness", "non-negative (0 derives it)", in.loading_stiffness);
  if (!(in.unloading_ratio >= 1) || !std::isfinite(in.unloading_ratio))
    throw_invalid("unloading_ratio", ">= 1 (k2/k1)", in.unloading_ratio);
  if (!(in.adhesive_stiffness >= 0) || !std::isfinite(in.adhesive_stiffness))
    throw_invalid("adhesive_stiffness", "non-negative", in.adhesive_stiffness);
  if (!std::isfinite(in.pull_off_force))
    throw_invalid("pull_off_force", "finite (N)", in.pull_off_force);
  if (!(in.adhesion_exponent > 0) || !std::isfinite(in.adhesion_exponent))
    throw_invalid("adhesion_exponent", "positive", in.adhesion_exponent);
}

}  // namespace

void Level::set_interaction(int i, int j, const Interaction& interaction) {
  for (int k : {i, j})
    if (k < -1 || k >= materials_.n_materials())
      throw_invalid("interaction material index", "-1 (rigid wall) or a known material", k);
  validate(interaction);
  interactions_[{std::min(i, j), std::max(i, j)}] = interaction;
  law_prepared_ = false;
  forces_valid_ = false;
}

void Level::set_default_interaction(const Interaction& interaction) {
  validate(interaction);
  default_interaction_ = interaction;
  law_prepared_ = false;
  forces_valid_ = false;
}

std::vector<Interaction> Level::interaction_table() const {
  const int stride = materials_.n_materials() + 1;
  std::vector<Interaction> table(static_cast<std::size_t>(stride) * stride, default_interaction_);
  auto index = [&](int k) { return k < 0 ? materials_.rigid_index() : k; };
  for (const auto& [key, in] : interactions_) {
    const int a = index(key.first), b = index(key.second);
    table[a * stride + b] = in;
    table[b * stride + a] = in;
  }
  return table;
}

int Level::add_material(const MaterialProperties& props) {
  const int index = materials_.add(props);
  law_prepared_ = false;
  return index;
}

void Level::set_contact_law(const ContactLaw& law) {
  if (lists_valid_) save_histories();
  law_ = law;
  law_prepared_ = false;
  lists_valid_ = false;
  forces_valid_ = false;
  // A different law has a different history layout: contacts restart from zero.
  contacts_.pair_carry = HistoryCarry();
  contacts_.wall_carry = HistoryCarry();
}

void Level::set_gravity(const Vec3& g) {
  if (!g.allFinite()) throw_invalid("Simulation.gravity", "finite (m/s^2)", g.transpose());
  // + 0 turns a -0 component into +0: the forces start at m g, and the pair loop relies on
  // them never being -0 (pair_loop.hpp).
  gravity_ = g + Vec3::Zero();
  forces_valid_ = false;
}

void Level::set_time_step(Real dt, bool force) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw_invalid("Simulation.time_step", "positive and finite (s)", dt);
  time_at_dt_change_ = time_;
  step_at_dt_change_ = step_;
  dt_ = dt;
  force_dt_ = force;
}

void Level::set_dimension(int dimension) {
  if (dimension != 2 && dimension != 3) throw_invalid("Simulation.dimension", "2 or 3", dimension);
  if (next_id_ > 0 || !insertion_.streams().empty())
    throw_invalid("Simulation.dimension", "set before particles or streams are added", dimension);
  dimension_ = dimension;
}

void Level::set_skin(Real skin) {
  if (!(skin > 0) || !std::isfinite(skin))
    throw_invalid("Simulation.skin", "positive and finite (m)", skin);
  if (lists_valid_) save_histories();
  skin_ = skin;
  lists_valid_ = false;
}

void Level::mark_positions_changed() {
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  forces_valid_ = false;
}

GlobalId Level::add_particles(Index n, const Real* position, const Real* velocity,
                              const Real* angular_velocity, const Real* radius,
                              const std::int32_t* material) {
  if (n < 0) throw_invalid("add_particles.count", "non-negative", n);
  for (Index k = 0; k < n; ++k) {
    const Vec3 x(position[3 * k], position[3 * k + 1], position[3 * k + 2]);
    if (!x.allFinite()) throw_invalid("add_particles.position", "finite (m)", x.transpose());
    for (int a = 0; a < 3; ++a)
      if (!domain_.periodic[a] && !domain_.inside(x, a)) {
        std::ostringstream range;
        range << "inside the domain [" << domain_.lo[a] << ", " << domain_.hi[a] << "] on axis "
              << "xyz"[a] << " (particle " << k << ")";
        throw_invalid("add_particles.position", range.str(), x[a]);
      }
    if (dimension_ == 2 && x[2] != plane_z()) {
      std::ostringstream c;
      c << "equal to the plane z = " << shortest(plane_z()) << " m of the 2-D mode (particle " << k
        << ")";
      throw_invalid("add_particles.position z", c.str(), x[2]);
    }
    if (!(radius[k] > 0) || !std::isfinite(radius[k]))
      throw_invalid("add_particles.radius", "positive and finite (m)", radius[k]);
    if (material[k] < 0 || material[k] >= materials_.n_materials())
      throw_invalid("add_particles.material", "a material index known to the simulation",
                    material[k]);
    if (!materials_.deformable(material[k]))
      throw_invalid("add_particles.material", "deformable (finite youngs_modulus)", material[k]);
    if (velocity && !Vec3(velocity[3 * k], velocity[3 * k + 1], velocity[3 * k + 2]).allFinite())
      throw_invalid("add_particles.velocity", "finite (m/s)", k);
    if (angular_velocity &&
        !Vec3(angular_velocity[3 * k], angular_velocity[3 * k + 1], angular_velocity[3 * k + 2])
             .allFinite())
      throw_invalid("add_particles.angular_velocity", "finite (rad/s)", k);
  }
  if (lists_valid_) save_histories();
  lists_valid_ = false;
  forces_valid_ = false;
  ps_.clear_ghosts();
  ghosts().clear();
  ensure_decomposition();
  const GlobalId first = next_id_;
  std::vector<char> mine(n, 1);
  Index kept = n;
  if (comm_.parallel()) {
    kept = 0;
    for (Index k = 0; k < n; ++k) {
      mine[k] = owns(Vec3(position[3 * k], position[3 * k + 1], position[3 * k + 2]));
      kept += mine[k];
    }
  }
  ps_.reserve(ps_.n_owned() + kept);
  for (Index k = 0; k < n; ++k) {
    if (!mine[k]) {  // another rank's: its id is taken all the same
      ++next_id_;
      continue;
    }
    const Real r = radius[k];
    const Real m = particle_mass(materials_[material[k]].density, r, dimension_);
    const Vec3 x(position[3 * k], position[3 * k + 1], position[3 * k + 2]);
    Vec3 v =
        velocity ? Vec3(velocity[3 * k], velocity[3 * k + 1], velocity[3 * k + 2]) : Vec3::Zero();
    Vec3 w = angular_velocity ? Vec3(angular_velocity[3 * k], angular_velocity[3 * k + 1],
                                     angular_velocity[3 * k + 2])
                              : Vec3::Zero();
    if (dimension_ == 2) {  // a disc moves in its plane and spins about z only
      v[2] = 0;
      w[0] = w[1] = 0;
    }
    ps_.add_owned(next_id_++, x, v, w, r, m, particle_inertia(m, r, dimension_), material[k]);
    contacts_.origin.push_back(-1);
  }
  return first;
}

Real Level::kinetic_energy() const {
  Real e = 0;
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    const Real m = ps_.mass[i];
    e += 0.5 * m * ps_.velocity[i].squaredNorm() +
         0.5 / ps_.inv_inertia[i] * ps_.angular_velocity[i].squaredNorm();
  }
  return comm_.sum(e);
}

Real Level::smallest_rayleigh_time() const {
  Real t = INFINITY;
  for (Index i = 0; i < ps_.n_owned(); ++i) {
    const MaterialProperties& m = materials_[ps_.material[i]];
    t = std::min(t, rayleigh_time(ps_.radius[i], m.density, m.youngs_modulus, m.poisson_ratio));
  }
  return comm_.min(t);
}

std::vector<std::array<GlobalId, 2>> Level::neighbor_pairs() const {
  std::vector<std::array<GlobalId, 2>> out;
  if (!lists_valid_) return out;
  const ContactList& pairs = contacts_.pairs;
  for (Index i = 0; i < ps_.n_owned(); ++i)
    for (Index k = pairs.first[i]; k < pairs.first[i + 1]; ++k)
      out.push_back({ps_.id[i], ps_.id[pairs.partner[k]]});
  return out;
}

GlobalId Level::place_particles(const std::vector<Vec3>& x, const std::vector<Real>& r,
                                const Vec3& velocity, const Vec3* spin, std::int32_t material) {
  const Index n = static_cast<Index>(r.size());
  std::vector<Real> flat(3 * n), v(3 * n), w(spin ? 3 * n : 0);
  for (Index k = 0; k < n; ++k)
    for (int a = 0; a < 3; ++a) {
      flat[3 * k + a] = x[k][a];
      v[3 * k + a] = velocity[a];
      if (spin) w[3 * k + a] = (*spin)[a];
    }
  const std::vector<std::int32_t> mat(n, material);
  return add_particles(n, flat.data(), v.data(), spin ? w.data() : nullptr, r.data(), mat.data());
}

InsertionSite Level::insertion_site(const Vec3& lo, const Vec3& hi, Real max_new_radius) const {
  Real r_old = 0;
  const SphereSet present =
      partition_.gather_nearby(lo, hi, max_new_radius, r_old, ps_, domain_, comm_);
  return InsertionSite{OccupancyGrid(lo, hi, max_new_radius, r_old, present, domain_),
                       WallClearance(walls_.walls(), lo, hi, max_new_radius)};
}

CentreGrid Level::centres_near(const Vec3& lo, const Vec3& hi, Real reach) const {
  Real r_old = 0;
  const SphereSet present = partition_.gather_nearby(lo, hi, reach, r_old, ps_, domain_, comm_);
  // Cells one grain across: a bed's nearest centre is then found in the first rings.
  return CentreGrid(lo, hi, reach, std::max(2 * r_old, reach / 8), present, domain_);
}

}  // namespace grainscale
