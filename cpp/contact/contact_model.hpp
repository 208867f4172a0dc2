// ContactModel: a contact law composed at compile time from sub-models (normal spring, damping,
// tangential spring with Coulomb limit, rolling resistance), in the manner of LAMMPS GRANULAR
// and MercuryDPM species. One struct per combination, an inlinable force(); the pair and wall
// loops are templates over it, so a law costs no virtual call per contact.
//
// Normal force:      F_n = spring(d) - gamma_n v_n,  gamma_n = Damping::factor |beta| sqrt(S m*)
//                    (v_n = v_rel . n < 0 while approaching; optional clamp F_n >= 0)
// Tangential force:  MindlinTangential with k_t from the normal model and
//                    gamma_t = Damping::factor |beta| sqrt(k_t m*)
// Rolling torque:    Rolling::evaluate with k_n, k_t and F_n from above.
// History layout per contact: [normal | tangential (3) | rolling].
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "contact/contact_input.hpp"
#include "contact/damping.hpp"
#include "contact/interaction.hpp"
#include "contact/normal_models.hpp"
#include "contact/rolling_models.hpp"
#include "contact/tangential_models.hpp"
#include "state/material_table.hpp"

namespace grainscale {

struct ContactSettings {
  bool limit_force = false;  // clamp F_n >= 0 (no tension from damping or adhesion)
  bool tangential_damping = true;
  TangentialHistory history = TangentialHistory::Total;
  SpringRotation spring_rotation = SpringRotation::Rescale;  // tangential and rolling springs
};

template <class Normal, class Damping, class Rolling>
class ContactModel {
 public:
  using NormalModel = Normal;
  using DampingModel = Damping;
  using RollingModel = Rolling;
  static constexpr int kTangentialOffset = Normal::kHistorySize;
  static constexpr int kRollingOffset = kTangentialOffset + MindlinTangential::kHistorySize;
  static constexpr int kHistorySize = kRollingOffset + Rolling::kHistorySize;
  static constexpr bool kRolling = Rolling::kActive;

  struct Pair {
    typename Normal::Pair normal;
    Real damping;  // Damping::factor() * |beta(e)|
    Real friction;
    RollingPair rolling;
  };

  explicit ContactModel(const ContactSettings& settings) : settings_(settings) {}
  const ContactSettings& settings() const { return settings_; }
  static std::string name() { return std::string(Normal::kName) + "+" + Rolling::kName; }

  // Builds the per-pair table. interactions[i * stride + j] with stride = n_materials + 1 (the
  // last index is the rigid-wall pseudo-material).
  void prepare(const MaterialTable& materials, const std::vector<Interaction>& interactions) {
    stride_ = materials.n_materials() + 1;
    pairs_.assign(static_cast<std::size_t>(stride_) * stride_, Pair{});
    for (int i = 0; i < stride_; ++i)
      for (int j = 0; j < stride_; ++j) {
        if (materials.rigid(i) && materials.rigid(j)) continue;  // walls never touch walls
        const Interaction& in = interactions[i * stride_ + j];
        pairs_[i * stride_ + j] = {Normal::make_pair(materials.pair_moduli(i, j), in),
                                   -Damping::factor() * restitution_beta(in.restitution),
                                   in.friction,
                                   {in.rolling_friction, in.rolling_damping}};
      }
  }
  const Pair& pair(int mi, int mj) const { return pairs_[mi * stride_ + mj]; }

  [[gnu::always_inline]] inline ContactOutput force(const Pair& p, const ContactInput& c,
                                                    Real* history) const {
    // The stored springs follow the contact's rotation (both at once where there are two).
    Eigen::Map<Vec3> tangential_spring(history + kTangentialOffset);
    if constexpr (Rolling::kSpring) {
      Eigen::Map<Vec3> rolling_spring(history + kRollingOffset);
      follow_normal(settings_.spring_rotation, tangential_spring, rolling_spring, c.normal);
    } else {
      follow_normal(settings_.spring_rotation, tangential_spring, c.normal);
    }
    const NormalState ns = Normal::evaluate(p.normal, c, history);
    const Real vn = c.v_rel.dot(c.normal);
    Real fn = ns.spring - p.damping * std::sqrt(ns.damping_stiffness * c.m_eff) * vn;
    if (settings_.limit_force && fn < 0) fn = 0;
    const Vec3 vt = c.v_rel - vn * c.normal;
    const Real gt =
        settings_.tangential_damping ? p.damping * std::sqrt(ns.tangential_stiffness * c.m_eff) : 0;
    const Vec3 ft = MindlinTangential::evaluate(settings_.history, ns.tangential_stiffness, gt,
                                                p.friction * std::max<Real>(fn, 0), c, vt,
                                                history + kTangentialOffset);
    ContactOutput out{fn * c.normal + ft, Vec3::Zero()};
    if constexpr (kRolling)
      out.rolling_torque = Rolling::evaluate(p.rolling, {fn, ns.stiffness, ns.tangential_stiffness},
                                             c, history + kRollingOffset);
    return out;
  }

 private:
  ContactSettings settings_;
  std::vector<Pair> pairs_;
  int stride_ = 0;
};

}  // namespace grainscale
