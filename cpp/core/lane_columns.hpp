// The contact history of a pack as columns. A contact's S history values are contiguous in
// memory (ContactList: value s of entry k at k * S + s); the law wants value s of all kPackLanes
// contacts in one pack (column s). One value of one lane at a time costs a load and a lane
// insert per value, and the write-back a lane extract and a store per value: for the laws with
// rolling springs (S = 6 or 7) a large part of their cost in bench_pair_loop.
//   - AVX-512 (8 lanes): the write-back transposes the columns in registers (8 x 8 doubles) and
//     stores each lane's S values with one masked store. The load stays one value at a time:
//     masked vector loads with the same transpose, and hardware gathers, were both slower
//     (bench/README.md).
//   - SSE2 (2 lanes): two values of a lane per load and per store, paired by unpacks.
//   - Other widths: one value at a time.
// Only bits are moved: the values, and so the results, are the same either way.
#pragma once

#include <cstddef>
#include <type_traits>

#include "core/simd_pack.hpp"

namespace grainscale {

namespace detail {

#if GRAINSCALE_LANES == 8 && defined(__AVX512F__)
// rows[0..7] becomes its transpose: value s of row l goes to value l of row s. Generic shuffles
// (GCC picks vunpcklpd/vunpckhpd and vpermt2pd); the intrinsics' undefined first operands trip
// a false -Wmaybe-uninitialized in GCC 12.
[[gnu::always_inline]] inline void transpose8(Pack* rows) {
  // Pairs of rows: values 0, 2, 4, 6 (even) and 1, 3, 5, 7 (odd) of both, interleaved.
  Pack t[8];
  for (int p = 0; p < 4; ++p) {
    t[2 * p] = __builtin_shuffle(rows[2 * p], rows[2 * p + 1], PackMask{0, 8, 2, 10, 4, 12, 6, 14});
    t[2 * p + 1] =
        __builtin_shuffle(rows[2 * p], rows[2 * p + 1], PackMask{1, 9, 3, 11, 5, 13, 7, 15});
  }
  // Quads of rows: each 128-bit block holds one value of two rows.
  Pack u[8];
  for (int h = 0; h < 2; ++h) {  // rows 0-3, rows 4-7
    const Pack* a = t + 4 * h;
    const PackMask low{0, 1, 8, 9, 4, 5, 12, 13}, high{2, 3, 10, 11, 6, 7, 14, 15};
    u[4 * h + 0] = __builtin_shuffle(a[0], a[2], low);   // values 0 and 4
    u[4 * h + 1] = __builtin_shuffle(a[1], a[3], low);   // 1 and 5
    u[4 * h + 2] = __builtin_shuffle(a[0], a[2], high);  // 2 and 6
    u[4 * h + 3] = __builtin_shuffle(a[1], a[3], high);  // 3 and 7
  }
  // Halves: rows 0-3 and 4-7 of one value side by side.
  const PackMask low{0, 1, 2, 3, 8, 9, 10, 11}, high{4, 5, 6, 7, 12, 13, 14, 15};
  for (int s = 0; s < 4; ++s) {
    rows[s] = __builtin_shuffle(u[s], u[4 + s], low);
    rows[4 + s] = __builtin_shuffle(u[s], u[4 + s], high);
  }
}
#endif

}  // namespace detail

// h[s] = value s of the history at base + at[l], lane by lane.
template <int S, class T>
[[gnu::always_inline]] inline void load_columns(const Real* base, const std::size_t* at, T* h) {
#if GRAINSCALE_LANES == 2
  if constexpr (!std::is_same_v<T, Real>) {
    int s = 0;
    for (; s + 1 < S; s += 2) {
      const __m128d a = _mm_loadu_pd(base + at[0] + s), b = _mm_loadu_pd(base + at[1] + s);
      h[s] = reinterpret_cast<T>(_mm_unpacklo_pd(a, b));
      h[s + 1] = reinterpret_cast<T>(_mm_unpackhi_pd(a, b));
    }
    if constexpr (S % 2 == 1)
      h[s] = reinterpret_cast<T>(_mm_set_pd(base[at[1] + s], base[at[0] + s]));
    return;
  }
#endif
  alignas(64) Real columns[S > 0 ? S : 1][kPackLanes];
  for (int l = 0; l < kPackLanes; ++l)
    for (int s = 0; s < S; ++s) columns[s][l] = base[at[l] + s];
  for (int s = 0; s < S; ++s) h[s] = load_lanes<T>(columns[s]);
}

// The inverse for lanes [0, valid): value s of lane l back to base + at[l] + s.
template <int S, class T>
[[gnu::always_inline]] inline void store_columns(Real* base, const std::size_t* at, int valid,
                                                 const T* h) {
#if GRAINSCALE_LANES == 8 && defined(__AVX512F__)
  if constexpr (!std::is_same_v<T, Real> && S <= 8) {
    constexpr __mmask8 kValues = static_cast<__mmask8>((1u << S) - 1);
    Pack rows[8] = {};
    for (int s = 0; s < S; ++s) rows[s] = h[s];
    detail::transpose8(rows);
    for (int l = 0; l < valid; ++l)
      _mm512_mask_storeu_pd(base + at[l], kValues, reinterpret_cast<__m512d>(rows[l]));
    return;
  }
#elif GRAINSCALE_LANES == 2
  if constexpr (!std::is_same_v<T, Real>) {
    int s = 0;
    for (; s + 1 < S; s += 2) {
      const __m128d a = reinterpret_cast<__m128d>(h[s]), b = reinterpret_cast<__m128d>(h[s + 1]);
      _mm_storeu_pd(base + at[0] + s, _mm_unpacklo_pd(a, b));
      if (valid > 1) _mm_storeu_pd(base + at[1] + s, _mm_unpackhi_pd(a, b));
    }
    if constexpr (S % 2 == 1) {
      base[at[0] + s] = h[s][0];
      if (valid > 1) base[at[1] + s] = h[s][1];
    }
    return;
  }
#endif
  for (int l = 0; l < valid; ++l)
    for (int s = 0; s < S; ++s) base[at[l] + s] = lane(h[s], l);
}

}  // namespace grainscale
