// What a contact law sees of one contact: geometry and kinematics at the contact point.
// Conventions (DESIGN.md 2.4): compression positive, n is the unit normal from body j to body i,
// v_rel is the velocity of i's contact point relative to j's. A wall is body j with R_j, m_j
// infinite, so r_eff = r_i and m_eff = m_i.
#pragma once

#include "core/simd_pack.hpp"
#include "core/types.hpp"

namespace grainscale {

struct ContactInput {
  Vec3 normal;
  Real overlap;  // > 0 while touching
  Real r_eff;    // R* = r_i r_j / (r_i + r_j)
  Real m_eff;    // m* = m_i m_j / (m_i + m_j)
  Vec3 v_rel;
  Real dt;
  // Filled only for laws with a rolling model (Law::kRolling):
  Vec3 w_rel = Vec3::Zero();  // omega_i - omega_j
  Real rolling_inertia = 0;   // I_r = [1/(I_i + m_i r_i^2) + 1/(I_j + m_j r_j^2)]^-1
};

// What a law returns: the force on i (j gets -force) and the rolling-resistance torque on i
// (j gets -torque); the torque of the tangential force about the centres is added by the loops.
struct ContactOutput {
  Vec3 force;
  Vec3 rolling_torque;
};

// The same for the laws' lane form (core/simd_pack.hpp): one contact (T = Real) or a pack.
template <class T>
struct ContactLanes {
  LaneVec<T> normal;
  T overlap, r_eff, m_eff;
  LaneVec<T> v_rel;
  Real dt;
  LaneVec<T> w_rel;  // rolling laws only
  T rolling_inertia;
};

template <class T>
struct ContactLanesOutput {
  LaneVec<T> force;
  LaneVec<T> rolling_torque;
};

// Damping ratio factor beta = ln e / sqrt(ln^2 e + pi^2) (< 0), with beta(0) = -1.
Real restitution_beta(Real restitution);

}  // namespace grainscale
