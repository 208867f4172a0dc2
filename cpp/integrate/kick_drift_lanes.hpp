// kick_drift on kPackLanes consecutive particles at once (velocity_verlet.cpp). The per-particle
// pass is short and has no loads it could wait on, so the scalar form is bound by its
// instruction count (about 50 per particle): at 200k particles it took a quarter of the 'settle'
// benchmark's time. Here the x, v, w, f and tau of W particles are 3W consecutive doubles each,
// three packs; the per-particle factors (dt/2 / m, dt/2 / I, m) are spread over the three packs
// by shuffles, and for |v|^2 the squares are shuffled back into one pack per component.
//
// Bit for bit the scalar pass: every lane does the scalar operations in the same order (no FMA:
// the core builds with -ffp-contract=off), |v|^2 is (x^2 + y^2) + z^2 as Vec3::squaredNorm, and
// the largest |v|^2 does not depend on the order of the comparisons (NaN if any is NaN).
#pragma once

#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

#include "core/simd_pack.hpp"
#include "core/types.hpp"

namespace grainscale::detail {

#if defined(__SSE2__)
inline constexpr bool kKickDriftLanes = kPackLanes > 1;

namespace kick_lanes {

constexpr int W = kPackLanes;

template <class F, std::size_t... L>
constexpr PackMask make_mask(F f, std::index_sequence<L...>) {
  return PackMask{f(static_cast<int>(L))...};
}
// Lane l of pack q holds component (W q + l) % 3 of particle (W q + l) / 3 of the block.
template <int Q>
constexpr PackMask spread_mask() {
  return make_mask([](int l) -> std::int64_t { return (W * Q + l) / 3; },
                   std::make_index_sequence<W>{});
}
// Component C of the block's particles from packs (a, b, c): first from a and b, then c.
template <int C>
constexpr PackMask component_from_ab() {
  return make_mask(
      [](int p) -> std::int64_t {
        const int flat = 3 * p + C;
        return flat < 2 * W ? flat : 0;
      },
      std::make_index_sequence<W>{});
}
template <int C>
constexpr PackMask component_then_c() {
  return make_mask(
      [](int p) -> std::int64_t {
        const int flat = 3 * p + C;
        return flat < 2 * W ? p : W + (flat - 2 * W);
      },
      std::make_index_sequence<W>{});
}

[[gnu::always_inline]] inline Pack load(const Real* p) {
  Pack v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
[[gnu::always_inline]] inline void store(Real* p, Pack v) { std::memcpy(p, &v, sizeof v); }

template <int Q>
[[gnu::always_inline]] inline Pack spread(Pack per_particle) {
  return __builtin_shuffle(per_particle, spread_mask<Q>());
}
template <int C>
[[gnu::always_inline]] inline Pack component(const Pack (&s)[3]) {
  return __builtin_shuffle(__builtin_shuffle(s[0], s[1], component_from_ab<C>()), s[2],
                           component_then_c<C>());
}

}  // namespace kick_lanes

// The largest |v|^2 of the blocks so far, and whether one was NaN.
struct DriftSpeeds {
  Pack largest{};  // +0 in every lane
  PackMask nan{};

  // The scalar result folded in: NaN if any lane or `scalar` is NaN, else the largest.
  Real combine(Real scalar) const {
    Real most = scalar;
    bool any_nan = scalar != scalar;
    for (int l = 0; l < kPackLanes; ++l) {
      any_nan |= nan[l] != 0;
      if (largest[l] > most) most = largest[l];
    }
    return any_nan ? std::numeric_limits<Real>::quiet_NaN() : most;
  }
};

// Particles [i, i + kPackLanes): the closing half kick when kClosingKick, the opening one and
// the drift; then f = m g, tau = 0 (velocity_verlet.cpp's kick_drift_over, 3-D only).
template <bool kClosingKick>
[[gnu::always_inline]] inline void kick_drift_block(Index i, Real* x, Real* v, Real* w, Real* f,
                                                    Real* t, const Real* m, const Real* im,
                                                    const Real* ii, Pack half, Pack dt,
                                                    const Pack (&gravity)[3], DriftSpeeds& speeds) {
  using namespace kick_lanes;
  const Pack hm = half * load(im + i), hi = half * load(ii + i), mass = load(m + i);
  const Pack hm3[3] = {spread<0>(hm), spread<1>(hm), spread<2>(hm)};
  const Pack hi3[3] = {spread<0>(hi), spread<1>(hi), spread<2>(hi)};
  const Pack m3[3] = {spread<0>(mass), spread<1>(mass), spread<2>(mass)};
  const std::size_t at = 3 * static_cast<std::size_t>(i);
  Pack squares[3];
  for (int q = 0; q < 3; ++q) {
    const std::size_t o = at + static_cast<std::size_t>(q) * W;
    const Pack fq = load(f + o), tq = load(t + o);
    Pack vq = load(v + o), wq = load(w + o);
    if constexpr (kClosingKick) {
      vq += hm3[q] * fq;
      wq += hi3[q] * tq;
    }
    vq += hm3[q] * fq;
    wq += hi3[q] * tq;
    store(x + o, load(x + o) + dt * vq);
    store(v + o, vq);
    store(w + o, wq);
    store(f + o, m3[q] * gravity[q]);
    store(t + o, Pack{});
    squares[q] = vq * vq;
  }
  const Pack v2 = (component<0>(squares) + component<1>(squares)) + component<2>(squares);
  speeds.nan |= v2 != v2;
  speeds.largest = v2 > speeds.largest ? v2 : speeds.largest;
}
#else
inline constexpr bool kKickDriftLanes = false;
#endif

}  // namespace grainscale::detail
