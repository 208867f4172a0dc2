// What a contact law sees of one contact: geometry and kinematics at the contact point.
// Conventions (DESIGN.md 2.4): compression positive, n is the unit normal from body j to body i,
// v_rel is the velocity of i's contact point relative to j's. A wall is body j with R_j, m_j
// infinite, so r_eff = r_i and m_eff = m_i.
#pragma once

#include "core/types.hpp"

namespace grainscale {

struct ContactInput {
  Vec3 normal;
  Real overlap;  // > 0 while touching
  Real r_eff;    // R* = r_i r_j / (r_i + r_j)
  Real m_eff;    // m* = m_i m_j / (m_i + m_j)
  Vec3 v_rel;
  Real dt;
};

// Damping ratio factor beta = ln e / sqrt(ln^2 e + pi^2) (< 0), with beta(0) = -1.
Real restitution_beta(Real restitution);

}  // namespace grainscale
