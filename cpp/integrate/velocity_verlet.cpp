#include "integrate/velocity_verlet.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "integrate/kick_drift_lanes.hpp"

namespace grainscale {

namespace {

// One half kick of particle i; in 2-D the frozen components are written as zero rather than
// skipped, so a value set from Python cannot leak into the kinetic energy or the drift.
template <bool kPlanar>
inline void half_kick(Vec3& v, Vec3& w, const Vec3& f, const Vec3& t, Real hm, Real hi) {
  if constexpr (kPlanar) {
    v[0] += hm * f[0];
    v[1] += hm * f[1];
    v[2] = 0;
    w[0] = 0;
    w[1] = 0;
    w[2] += hi * t[2];
  } else {
    v += hm * f;
    w += hi * t;
  }
}

}  // namespace

// The pass over the particles `select` yields (kick_drift's body, shared by its variants).
template <bool kPlanar, bool kClosingKick, class Select>
inline Real kick_drift_over(ParticleStore& ps, Real dt, const Vec3& gravity, Index count,
                            Select select) {
  const Real half = 0.5 * dt;
  Vec3* x = ps.position.data();
  Vec3* v = ps.velocity.data();
  Vec3* w = ps.angular_velocity.data();
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  const Real* m = ps.mass.data();
  const Real* im = ps.inv_mass.data();
  const Real* ii = ps.inv_inertia.data();
  Real max_v2 = 0;
  for (Index k = 0; k < count; ++k) {
    const Index i = select(k);
    if (i < 0) continue;
    const Real hm = half * im[i], hi = half * ii[i];
    // On local copies: through the arrays the compiler must assume that they alias, and it
    // stores and reloads v and w between the two half kicks (store-forwarding chains).
    Vec3 vi = v[i], wi = w[i];
    const Vec3 fi = f[i], ti = t[i];
    if constexpr (kClosingKick) half_kick<kPlanar>(vi, wi, fi, ti, hm, hi);
    half_kick<kPlanar>(vi, wi, fi, ti, hm, hi);
    const Vec3 xi = x[i] + dt * vi;  // v_z is exactly 0 in 2-D, so z is unchanged bit for bit
    x[i] = xi;
    v[i] = vi;
    w[i] = wi;
    f[i] = m[i] * gravity;
    t[i].setZero();
    const Real v2 = vi.squaredNorm();
    if (v2 > max_v2 || v2 != v2) max_v2 = v2;  // a NaN sticks, so it forces a (checked) rebuild
  }
  return max_v2;
}

// The pass over the owned particles [0, n) except those with skip[i] != 0 (skip null: none),
// in blocks of kPackLanes particles (kick_drift_lanes.hpp) where no particle of the block is
// skipped, one particle at a time elsewhere and in 2-D.
template <bool kPlanar, bool kClosingKick>
Real kick_drift_blocks(ParticleStore& ps, Real dt, const Vec3& gravity, const std::uint8_t* skip) {
  const Index n = ps.n_owned();
  auto one = [&](Index first, Index end) {
    return kick_drift_over<kPlanar, kClosingKick>(ps, dt, gravity, end - first, [=](Index k) {
      return skip != nullptr && skip[first + k] ? Index(-1) : first + k;
    });
  };
  if constexpr (kPlanar || !detail::kKickDriftLanes) {
    return one(0, n);
  } else {
    constexpr int W = kPackLanes;
    Real* x = ps.position.data()->data();
    Real* v = ps.velocity.data()->data();
    Real* w = ps.angular_velocity.data()->data();
    Real* f = ps.force.data()->data();
    Real* t = ps.torque.data()->data();
    const Pack half = splat<Pack>(0.5 * dt), step = splat<Pack>(dt);
    Pack g[3];
    for (int q = 0; q < 3; ++q)
      for (int l = 0; l < W; ++l) g[q][l] = gravity[(W * q + l) % 3];
    detail::DriftSpeeds speeds;
    Real max_v2 = 0;
    Index i = 0;
    for (; i + W <= n; i += W) {
      static_assert(W <= 8, "a block's skip flags are read as one 64-bit word");
      std::uint64_t skipped = 0;
      if (skip != nullptr) std::memcpy(&skipped, skip + i, W);
      if (skipped == 0)
        detail::kick_drift_block<kClosingKick>(i, x, v, w, f, t, ps.mass.data(), ps.inv_mass.data(),
                                               ps.inv_inertia.data(), half, step, g, speeds);
      else
        max_v2 = larger_or_nan(max_v2, one(i, i + W));
    }
    max_v2 = larger_or_nan(max_v2, one(i, n));
    return speeds.combine(max_v2);
  }
}

Real max_displacement2(const ParticleStore& ps, const std::vector<Vec3>& reference) {
  const Vec3* x = ps.position.data();
  Real max_d2 = 0;
  for (Index i = 0; i < ps.n_owned(); ++i) {
    const Real d2 = (x[i] - reference[i]).squaredNorm();
    if (d2 > max_d2 || d2 != d2) max_d2 = d2;
  }
  return max_d2;
}

template <bool kPlanar, bool kClosingKick>
Real kick_drift(ParticleStore& ps, Real dt, const Vec3& gravity) {
  return kick_drift_blocks<kPlanar, kClosingKick>(ps, dt, gravity, nullptr);
}

template <bool kPlanar>
Real kick_drift_except(ParticleStore& ps, Real dt, const Vec3& gravity,
                       const std::vector<std::uint8_t>& skip) {
  return kick_drift_blocks<kPlanar, true>(ps, dt, gravity, skip.data());
}

template <bool kPlanar>
Real kick_drift_only(ParticleStore& ps, Real dt, const Vec3& gravity,
                     const std::vector<Index>& only) {
  const Index* o = only.data();
  return kick_drift_over<kPlanar, true>(ps, dt, gravity, static_cast<Index>(only.size()),
                                        [o](Index k) { return o[k]; });
}

template <bool kPlanar>
void kick(ParticleStore& ps, Real dt) {
  const Real half = 0.5 * dt;
  const Index n = ps.n_owned();
  Vec3* v = ps.velocity.data();
  Vec3* w = ps.angular_velocity.data();
  const Vec3* f = ps.force.data();
  const Vec3* t = ps.torque.data();
  const Real* im = ps.inv_mass.data();
  const Real* ii = ps.inv_inertia.data();
  for (Index i = 0; i < n; ++i)
    half_kick<kPlanar>(v[i], w[i], f[i], t[i], half * im[i], half * ii[i]);
}

template Real kick_drift<false, false>(ParticleStore&, Real, const Vec3&);
template Real kick_drift<false, true>(ParticleStore&, Real, const Vec3&);
template Real kick_drift<true, false>(ParticleStore&, Real, const Vec3&);
template Real kick_drift<true, true>(ParticleStore&, Real, const Vec3&);
template Real kick_drift_except<false>(ParticleStore&, Real, const Vec3&,
                                       const std::vector<std::uint8_t>&);
template Real kick_drift_except<true>(ParticleStore&, Real, const Vec3&,
                                      const std::vector<std::uint8_t>&);
template Real kick_drift_only<false>(ParticleStore&, Real, const Vec3&, const std::vector<Index>&);
template Real kick_drift_only<true>(ParticleStore&, Real, const Vec3&, const std::vector<Index>&);
template void kick<false>(ParticleStore&, Real);
template void kick<true>(ParticleStore&, Real);

}  // namespace grainscale
