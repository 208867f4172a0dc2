// Lanes for the contact laws: each law is written once, as a template over its number type T,
// and evaluated either on one contact (T = Real) or on kPackLanes contacts at once (T = Pack,
// a GCC vector of doubles the compiler maps onto the widest registers the build targets:
// AVX-512 8 lanes, AVX/AVX2 4, SSE2 2). The pair loop gathers touching contacts into packs; the
// wall loop and the tests call the scalar form.
//
// Bit for bit: every lane does the same IEEE operations in the same order as the scalar form
// (no FMA: the core builds with -ffp-contract=off; division and square root are correctly
// rounded in every lane), and a branch of the scalar form becomes a select between both
// results, so a pack gives exactly the scalar results of its contacts (tests/cpp checks it
// for every law). The lane width is a build-time choice: GRAINSCALE_PACK_LANES=1 (CMake
// option GRAINSCALE_SIMD=OFF) gives the scalar loop.
#pragma once

#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/types.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#endif

namespace grainscale {

#if defined(GRAINSCALE_PACK_LANES)
#define GRAINSCALE_LANES GRAINSCALE_PACK_LANES
#elif defined(__AVX512F__)
#define GRAINSCALE_LANES 8
#elif defined(__AVX__)
#define GRAINSCALE_LANES 4
#elif defined(__SSE2__)
#define GRAINSCALE_LANES 2
#else
#define GRAINSCALE_LANES 1
#endif
inline constexpr int kPackLanes = GRAINSCALE_LANES;
static_assert(kPackLanes == 1 || kPackLanes == 2 || kPackLanes == 4 || kPackLanes == 8,
              "GRAINSCALE_PACK_LANES must be 1, 2, 4 or 8");

// Scalar helpers (T = Real); the Pack overloads follow. Masks are bool for Real.
[[gnu::always_inline]] inline Real select(bool m, Real a, Real b) { return m ? a : b; }
[[gnu::always_inline]] inline Real sqrt_lanes(Real x) { return std::sqrt(x); }
[[gnu::always_inline]] inline Real abs_lanes(Real x) { return std::abs(x); }
[[gnu::always_inline]] inline bool any(bool m) { return m; }
[[gnu::always_inline]] inline bool all(bool m) { return m; }
[[gnu::always_inline]] inline bool mask_and(bool a, bool b) { return a && b; }
[[gnu::always_inline]] inline bool mask_or(bool a, bool b) { return a || b; }
[[gnu::always_inline]] inline bool mask_not(bool a) { return !a; }
[[gnu::always_inline]] inline Real lane(Real x, int) { return x; }
template <class T>
[[gnu::always_inline]] inline T splat(Real x);
template <>
[[gnu::always_inline]] inline Real splat<Real>(Real x) {
  return x;
}
// f(args...) on the lanes where m holds, 0 elsewhere (rare paths with no pack form: pow).
template <class F, class... A>
[[gnu::always_inline]] inline Real per_lane(bool m, F f, Real a, A... rest) {
  return m ? f(a, rest...) : Real(0);
}

#if !defined(__SSE2__) && defined(GRAINSCALE_PACK_LANES) && GRAINSCALE_PACK_LANES > 1
#error "packs of more than one lane need SSE2"
#endif

#if defined(__SSE2__)
// The pack types exist for every width the target can hold; kPackLanes picks the one used.
using Pack = Real __attribute__((vector_size(kPackLanes * sizeof(Real))));
using PackMask = std::int64_t __attribute__((vector_size(kPackLanes * sizeof(Real))));

template <>
[[gnu::always_inline]] inline Pack splat<Pack>(Real x) {
  Pack p{};
  for (int l = 0; l < kPackLanes; ++l) p[l] = x;
  return p;
}
[[gnu::always_inline]] inline Pack select(PackMask m, Pack a, Pack b) { return m ? a : b; }
[[gnu::always_inline]] inline Pack sqrt_lanes(Pack x) {
#if GRAINSCALE_LANES == 8 && defined(__AVX512F__)
  // (the masked form: the plain one trips a false -Wmaybe-uninitialized in GCC 12)
  const __m512d v = reinterpret_cast<__m512d>(x);
  return reinterpret_cast<Pack>(_mm512_mask_sqrt_pd(v, 0xFF, v));
#elif GRAINSCALE_LANES == 4 && defined(__AVX__)
  return reinterpret_cast<Pack>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(x)));
#elif GRAINSCALE_LANES == 2
  return reinterpret_cast<Pack>(_mm_sqrt_pd(reinterpret_cast<__m128d>(x)));
#else
  Pack r{};  // a width the instruction set has no single instruction for
  for (int l = 0; l < kPackLanes; ++l) r[l] = std::sqrt(x[l]);
  return r;
#endif
}
// |x| by clearing the sign bit (as std::abs: -0 gives +0, NaN stays NaN).
[[gnu::always_inline]] inline Pack abs_lanes(Pack x) {
  return reinterpret_cast<Pack>(reinterpret_cast<PackMask>(x) & INT64_MAX);
}
// any and all read the lanes' sign bits in one instruction where there is one (a mask lane is
// all ones or zero); GCC turned the loops into a chain of extracts and ORs (about 12
// instructions for 8 lanes), and a law asks several times per pack.
[[gnu::always_inline]] inline unsigned sign_bits(PackMask m) {
#if GRAINSCALE_LANES == 8 && defined(__AVX512F__)
  const __m512i v = reinterpret_cast<__m512i>(m);
  return _mm512_test_epi64_mask(v, v);
#elif GRAINSCALE_LANES == 4 && defined(__AVX__)
  return static_cast<unsigned>(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
#elif GRAINSCALE_LANES == 2
  return static_cast<unsigned>(_mm_movemask_pd(reinterpret_cast<__m128d>(m)));
#else
  unsigned r = 0;
  for (int l = 0; l < kPackLanes; ++l) r |= static_cast<unsigned>(m[l] != 0) << l;
  return r;
#endif
}
[[gnu::always_inline]] inline bool any(PackMask m) { return sign_bits(m) != 0; }
[[gnu::always_inline]] inline bool all(PackMask m) {
  return sign_bits(m) == (1u << kPackLanes) - 1;
}
[[gnu::always_inline]] inline PackMask mask_and(PackMask a, PackMask b) { return a & b; }
[[gnu::always_inline]] inline PackMask mask_or(PackMask a, PackMask b) { return a | b; }
[[gnu::always_inline]] inline PackMask mask_not(PackMask a) { return ~a; }
[[gnu::always_inline]] inline Real lane(Pack x, int l) { return x[l]; }
// Out of line: a call clobbers every vector register, and with the calls inlined into the law
// GCC kept the law's values on the stack for the whole pack, the common path too (EEPA laws:
// several hundred stack accesses per pack).
template <class F, class... A>
[[gnu::noinline, gnu::cold]] Pack per_lane_out_of_line(PackMask m, F f, Pack a, A... rest) {
  Pack r = splat<Pack>(0);
  for (int l = 0; l < kPackLanes; ++l)
    if (m[l]) r[l] = f(a[l], rest[l]...);
  return r;
}
template <class F, class... A>
[[gnu::always_inline]] inline Pack per_lane(PackMask m, F f, Pack a, A... rest) {
  return per_lane_out_of_line(m, f, a, rest...);
}
#endif

// The number type of kPackLanes contacts: Pack, or Real for a one-lane (scalar) build.
#if defined(__SSE2__)
using LaneReal = std::conditional_t<kPackLanes == 1, Real, Pack>;
#else
using LaneReal = Real;
#endif

// kPackLanes consecutive values from memory as lanes (any alignment), and back.
template <class T>
[[gnu::always_inline]] inline T load_lanes(const Real* p) {
  if constexpr (std::is_same_v<T, Real>) {
    return *p;
  } else {
    T v;
    __builtin_memcpy(&v, p, sizeof(T));
    return v;
  }
}
template <class T>
[[gnu::always_inline]] inline void store_lanes(Real* p, T v) {
  if constexpr (std::is_same_v<T, Real>)
    *p = v;
  else
    __builtin_memcpy(p, &v, sizeof(T));
}

// A 3-vector of lanes with the operations the laws use, each in the order Eigen evaluates it
// for a Vec3 (dot products left to right), so that the scalar form matches Eigen's results.
template <class T>
struct LaneVec {
  T x, y, z;
  static LaneVec zero() { return {splat<T>(0), splat<T>(0), splat<T>(0)}; }
};
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator+(const LaneVec<T>& a, const LaneVec<T>& b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator-(const LaneVec<T>& a, const LaneVec<T>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator-(const LaneVec<T>& a) {
  return {-a.x, -a.y, -a.z};
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator*(T s, const LaneVec<T>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator*(const LaneVec<T>& a, T s) {
  return {a.x * s, a.y * s, a.z * s};
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> operator/(const LaneVec<T>& a, T s) {
  return {a.x / s, a.y / s, a.z / s};
}
// A plain double with a vector of packs (broadcast; the same bits as a pack of equal lanes).
template <class T, class = std::enable_if_t<!std::is_same_v<T, Real>>>
[[gnu::always_inline]] inline LaneVec<T> operator*(Real s, const LaneVec<T>& a) {
  return {s * a.x, s * a.y, s * a.z};
}
template <class T, class = std::enable_if_t<!std::is_same_v<T, Real>>>
[[gnu::always_inline]] inline LaneVec<T> operator*(const LaneVec<T>& a, Real s) {
  return {a.x * s, a.y * s, a.z * s};
}
template <class T>
[[gnu::always_inline]] inline T dot(const LaneVec<T>& a, const LaneVec<T>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <class T>
[[gnu::always_inline]] inline T squared_norm(const LaneVec<T>& a) {
  return dot(a, a);
}
template <class T>
[[gnu::always_inline]] inline LaneVec<T> cross(const LaneVec<T>& a, const LaneVec<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T, class M>
[[gnu::always_inline]] inline LaneVec<T> select(M m, const LaneVec<T>& a, const LaneVec<T>& b) {
  return {select(m, a.x, b.x), select(m, a.y, b.y), select(m, a.z, b.z)};
}
[[gnu::always_inline]] inline LaneVec<Real> from_eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
[[gnu::always_inline]] inline Vec3 to_eigen(const LaneVec<Real>& v) { return Vec3(v.x, v.y, v.z); }

// The constants of a law for each lane: one struct P (a material pair's constants) per lane,
// or a single one for the scalar form. get(&P::field) gives the field in every lane (one
// broadcast when all lanes share the pair, as with a single material); sub(&P::part) the
// constants of a sub-model.
template <class P, class T>
class Param;

template <class P>
class Param<P, Real> {
 public:
  explicit Param(const P& p) : p_(&p) {}
  template <class F>
  [[gnu::always_inline]] Real get(F P::* field) const {
    return p_->*field;
  }
  template <class Q>
  [[gnu::always_inline]] Param<Q, Real> sub(Q P::* part) const {
    return Param<Q, Real>(p_->*part);
  }

 private:
  const P* p_;
};

#if defined(__SSE2__)
template <class P>
class Param<P, Pack> {
 public:
  Param() = default;
  // Lane l takes *lanes[l].
  [[gnu::always_inline]] static Param of(const P* const* lanes) {
    Param p;
    p.uniform_ = true;
    for (int l = 0; l < kPackLanes; ++l) {
      p.p_[l] = lanes[l];
      p.uniform_ = p.uniform_ && lanes[l] == lanes[0];
    }
    return p;
  }
  template <class F>
  [[gnu::always_inline]] Pack get(F P::* field) const {
    if (uniform_) return splat<Pack>(p_[0]->*field);
    Pack r{};
    for (int l = 0; l < kPackLanes; ++l) r[l] = p_[l]->*field;
    return r;
  }
  template <class Q>
  [[gnu::always_inline]] Param<Q, Pack> sub(Q P::* part) const {
    const Q* lanes[kPackLanes];
    for (int l = 0; l < kPackLanes; ++l) lanes[l] = &(p_[l]->*part);
    return Param<Q, Pack>::of(lanes);
  }

 private:
  const P* p_[kPackLanes] = {};
  bool uniform_ = true;
};
#endif

}  // namespace grainscale
