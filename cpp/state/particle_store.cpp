#include "state/particle_store.hpp"

#include <stdexcept>

namespace grainscale {

void ParticleStore::resize_all(Index n) {
  position.resize(n);
  velocity.resize(n);
  angular_velocity.resize(n);
  force.resize(n);
  torque.resize(n);
  radius.resize(n);
  mass.resize(n);
  inv_mass.resize(n);
  inv_inertia.resize(n);
  inv_rolling_inertia.resize(n);
  material.resize(n);
  id.resize(n);
  n_local_ = n;
}

void ParticleStore::reserve(Index n) {
  position.reserve(n);
  velocity.reserve(n);
  angular_velocity.reserve(n);
  force.reserve(n);
  torque.reserve(n);
  radius.reserve(n);
  mass.reserve(n);
  inv_mass.reserve(n);
  inv_inertia.reserve(n);
  inv_rolling_inertia.reserve(n);
  material.reserve(n);
  id.reserve(n);
}

void ParticleStore::add_owned(GlobalId gid, const Vec3& x, const Vec3& v, const Vec3& w, Real r,
                              Real m, Real inertia, std::int32_t mat) {
  if (n_local_ != n_owned_) throw std::logic_error("ParticleStore::add_owned with ghosts present");
  Index i = n_owned_;
  resize_all(i + 1);
  position[i] = x;
  velocity[i] = v;
  angular_velocity[i] = w;
  force[i] = Vec3::Zero();
  torque[i] = Vec3::Zero();
  radius[i] = r;
  mass[i] = m;
  inv_mass[i] = 1.0 / m;
  inv_inertia[i] = 1.0 / inertia;
  inv_rolling_inertia[i] = 1.0 / (inertia + m * r * r);
  material[i] = mat;
  id[i] = gid;
  n_owned_ = i + 1;
}

void ParticleStore::clear_ghosts() { resize_all(n_owned_); }

Index ParticleStore::add_ghost_slots(Index count) {
  const Index first = n_local_;
  resize_all(n_local_ + count);
  return first;
}

namespace {
template <class T>
void gather(SharedArray<T>& a, const std::vector<Index>& order, std::vector<T>& scratch) {
  scratch.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) scratch[k] = a[order[k]];
  for (std::size_t k = 0; k < order.size(); ++k) a[k] = scratch[k];
}
}  // namespace

void ParticleStore::select_owned(const std::vector<Index>& order) {
  if (n_local_ != n_owned_) throw std::logic_error("ParticleStore::select_owned with ghosts");
  std::vector<Vec3>& sv = scratch_vec_;
  std::vector<Real>& sr = scratch_real_;
  std::vector<std::int32_t>& si = scratch_int_;
  std::vector<GlobalId>& sg = scratch_id_;
  gather(position, order, sv);
  gather(velocity, order, sv);
  gather(angular_velocity, order, sv);
  gather(force, order, sv);
  gather(torque, order, sv);
  gather(radius, order, sr);
  gather(mass, order, sr);
  gather(inv_mass, order, sr);
  gather(inv_inertia, order, sr);
  gather(inv_rolling_inertia, order, sr);
  gather(material, order, si);
  gather(id, order, sg);
  resize_all(static_cast<Index>(order.size()));
  n_owned_ = n_local_;
}

}  // namespace grainscale
