// WallSet: the walls of a level — their shapes with the checks on adding one, prescribed motion
// and servo control, the primitive table of the wall loop, mesh bins, how far each wall moved
// since the last list build (shift) and how far its points reach from its origin, the loads and
// their sum over the ranks, and the walls' part of a checkpoint.
#pragma once

#include <vector>

#include "contact/wall_loop.hpp"
#include "geometry/wall.hpp"
#include "level/level_state.hpp"
#include "parallel/communicator.hpp"
#include "state/domain.hpp"
#include "state/material_table.hpp"

namespace grainscale {

class WallSet {
 public:
  // The wall checked and normalised as add() stores it; `reach` receives the largest distance
  // of a wall point that matters from its origin. Throws InvalidArgument, changing nothing.
  static Wall validated(const Wall& wall, const Domain& domain, int n_materials, Real& reach);
  // Appends a wall returned by validated(); returns its index.
  int add(const Wall& wall, Real reach);
  void set_motion(int index, const Vec3& velocity, const Vec3& angular_velocity,
                  const Vec3& origin);
  void set_servo(int index, const Servo& servo);

  std::vector<Wall>& walls() { return walls_; }
  Real reach(int index) const { return wall_reach_[index]; }
  const std::vector<Wall>& walls() const { return walls_; }
  const WallPrimitives& primitives() const { return primitives_; }
  std::size_t size() const { return walls_.size(); }
  bool empty() const { return walls_.empty(); }
  bool any_servo() const { return any_servo_; }

  // The material index every wall's law uses (after the law tables were prepared).
  void set_law_materials(const MaterialTable& materials);
  // Moves every wall by one step; returns the largest shift since the last build.
  Real advance(Real dt) {
    Real wall_shift = 0;
    for (std::size_t k = 0; k < walls_.size(); ++k) {
      wall_shift_[k] += walls_[k].advance(dt, wall_reach_[k]);
      wall_shift = std::max(wall_shift, wall_shift_[k]);
    }
    return wall_shift;
  }
  // Mesh bins at a list build: once for a wall at rest, again after it moved or the reach grew.
  void build_mesh_bins(Real margin, Real cutoff);
  // After a list build: no wall has moved since.
  void reset_shift() { wall_shift_.assign(walls_.size(), 0); }
  void reset_loads() {
    for (Wall& w : walls_) {
      w.force.setZero();
      w.torque.setZero();
    }
  }
  // The loads summed over the ranks (collective).
  void reduce_loads(const Communicator& comm);

  // Checkpoint: shift, bin margin and every wall's position, motion, loads, servo and vertices.
  void save_state(LevelState& s) const;
  // The mesh bin margin is a scalar of the level's state ("scalars"), loaded with them.
  void load_state(const LevelState& s);
  // The checks of load_state, changing nothing (throws std::runtime_error on a damaged state).
  void check_state(const LevelState& s) const;
  Real mesh_bin_margin() const { return mesh_bin_margin_; }
  void set_mesh_bin_margin(Real margin) { mesh_bin_margin_ = margin; }

 private:
  void update_any_servo();

  std::vector<Wall> walls_;
  WallPrimitives primitives_;
  std::vector<Real> wall_shift_;  // how far each wall may have moved since the last build
  std::vector<Real> wall_reach_;  // largest distance of a wall point that matters from origin
  std::vector<char> mesh_bins_valid_;
  Real mesh_bin_margin_ = -1;
  bool any_servo_ = false;
};

}  // namespace grainscale
