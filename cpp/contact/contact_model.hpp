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
// force_lanes() is the law once, over the lane type T (core/simd_pack.hpp): the pair loop
// evaluates packs of contacts, the wall loop one contact (force()); the results are the same
// bits either way.
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
#include "core/simd_pack.hpp"
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
  static constexpr bool kRollingInertia = Rolling::kInertia;  // ContactLanes::rolling_inertia

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

  // Flat index of a material pair in the table (pair_at(pair_index(mi, mj)) == pair(mi, mj)).
  int pair_index(int mi, int mj) const { return mi * stride_ + mj; }
  // One material (the other index is the rigid walls'): every particle pair is pair 0, and the
  // pair loop need not read the partners' materials.
  bool single_material() const { return stride_ <= 2; }
  const Pair& pair_at(int index) const { return pairs_[index]; }

  // One contact (the wall loop, tests): the lane form below on T = Real.
  [[gnu::always_inline]] inline ContactOutput force(const Pair& p, const ContactInput& c,
                                                    Real* history) const {
    const ContactLanes<Real> lanes{
        from_eigen(c.normal), c.overlap,        c.r_eff, c.m_eff, from_eigen(c.v_rel), c.dt,
        from_eigen(c.w_rel),  c.rolling_inertia};
    const ContactLanesOutput<Real> out = force_lanes(Param<Pair, Real>(p), lanes, history);
    return {to_eigen(out.force), to_eigen(out.rolling_torque)};
  }

  // The law on one contact or a pack of contacts (T: core/simd_pack.hpp); history[s] is value s
  // of the history of each lane, updated in place.
  template <class T>
  [[gnu::always_inline]] inline ContactLanesOutput<T> force_lanes(const Param<Pair, T>& p,
                                                                  const ContactLanes<T>& c,
                                                                  T* history) const {
    // The stored springs follow the contact's rotation.
    LaneVec<T> tangential_spring{history[kTangentialOffset], history[kTangentialOffset + 1],
                                 history[kTangentialOffset + 2]};
    follow_normal(settings_.spring_rotation, tangential_spring, c.normal);
    LaneVec<T> rolling_spring = LaneVec<T>::zero();
    if constexpr (Rolling::kSpring) {
      rolling_spring = {history[kRollingOffset], history[kRollingOffset + 1],
                        history[kRollingOffset + 2]};
      follow_normal(settings_.spring_rotation, rolling_spring, c.normal);
    }
    const NormalState<T> ns = Normal::evaluate(p.sub(&Pair::normal), c, history);
    const T damping = p.get(&Pair::damping);
    const T vn = dot(c.v_rel, c.normal);
    const T gn = damping * sqrt_lanes(ns.damping_stiffness * c.m_eff);
    T fn = ns.spring - gn * vn;
    if (settings_.limit_force) fn = select(fn < 0.0, splat<T>(0), fn);
    const LaneVec<T> vt = c.v_rel - vn * c.normal;
    T gt = splat<T>(0);
    if (settings_.tangential_damping) {
      if constexpr (Normal::kFixedTangentialRatio)
        gt = gn * ns.tangential_root_ratio;  // = damping sqrt(k_t m*)
      else
        gt = damping * sqrt_lanes(ns.tangential_stiffness * c.m_eff);
    }
    const T fn_plus = select(fn < 0.0, splat<T>(0), fn);  // std::max(fn, 0)
    const LaneVec<T> ft =
        MindlinTangential::evaluate(settings_.history, ns.tangential_stiffness, gt,
                                    p.get(&Pair::friction) * fn_plus, c, vt, tangential_spring);
    history[kTangentialOffset] = tangential_spring.x;
    history[kTangentialOffset + 1] = tangential_spring.y;
    history[kTangentialOffset + 2] = tangential_spring.z;
    ContactLanesOutput<T> out{fn * c.normal + ft, LaneVec<T>::zero()};
    if constexpr (kRolling) {
      out.rolling_torque = Rolling::evaluate(
          p.sub(&Pair::rolling), RollingContext<T>{fn, ns.stiffness, ns.tangential_stiffness}, c,
          rolling_spring);
      if constexpr (Rolling::kSpring) {
        history[kRollingOffset] = rolling_spring.x;
        history[kRollingOffset + 1] = rolling_spring.y;
        history[kRollingOffset + 2] = rolling_spring.z;
      }
    }
    return out;
  }

 private:
  ContactSettings settings_;
  std::vector<Pair> pairs_;
  int stride_ = 0;
};

}  // namespace grainscale
