// ParticleStore: structure-of-arrays particle data of one level on one rank.
// Layout: owned particles [0, n_owned), then ghosts [n_owned, n_local). Ghosts are periodic
// images and halo copies from neighbouring ranks; the GhostExchange knows where each came from.
#pragma once

#include <vector>

#include "core/shared_array.hpp"
#include "core/types.hpp"

namespace grainscale {

class ParticleStore {
 public:
  // Per-particle arrays (length n_local). Forces and torques include ghost slots, which the
  // ghost exchange folds back onto their owners.
  SharedArray<Vec3> position, velocity, angular_velocity, force, torque;
  SharedArray<Real> radius, mass, inv_mass, inv_inertia;
  // 1 / (I + m r^2): the rolling inertia of a pair is 1 / (this_i + this_j) (EPSD damping).
  SharedArray<Real> inv_rolling_inertia;
  SharedArray<std::int32_t> material;
  SharedArray<GlobalId> id;

  Index n_owned() const { return n_owned_; }
  Index n_ghost() const { return n_local_ - n_owned_; }
  Index n_local() const { return n_local_; }

  // Makes room for n local particles in every array (one allocation instead of growth steps).
  void reserve(Index n);
  // Appends one owned particle (ghosts must have been cleared).
  void add_owned(GlobalId gid, const Vec3& x, const Vec3& v, const Vec3& w, Real r, Real m,
                 Real inertia, std::int32_t mat);
  void clear_ghosts();
  // Appends `count` ghost slots (values unset) and returns the first one.
  Index add_ghost_slots(Index count);
  // Reorders and filters owned particles: new slot k takes old particle order[k]; particles
  // not listed are dropped. Ghosts must be cleared.
  void select_owned(const std::vector<Index>& order);

 private:
  void resize_all(Index n);
  // select_owned scratch, kept so that sorting at every rebuild does not allocate.
  std::vector<Vec3> scratch_vec_;
  std::vector<Real> scratch_real_;
  std::vector<std::int32_t> scratch_int_;
  std::vector<GlobalId> scratch_id_;
  Index n_owned_ = 0;
  Index n_local_ = 0;
};

}  // namespace grainscale
