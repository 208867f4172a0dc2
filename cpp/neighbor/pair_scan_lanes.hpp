// The candidate test of build_pair_list on 8 grid slots at once (AVX-512 builds). A point meets
// about 30 candidates in its half stencil, of which one in ten is a neighbour: the scalar test
// spent most of its time in the loads and the mispredicted branch of the hits. Here the
// candidates' coordinates, radii and ids are copied once per build into columns in grid order
// (GridColumns), so the 8 candidates of a pack are plain vector loads; the pairs kept are
// packed by vpcompressq. The same arithmetic as the scalar test (the difference and
// (dx^2 + dy^2) + dz^2 in Vec3::squaredNorm's order, ra + r_b with ra = r_a + skin, NaN kept),
// and the pairs in the same order: the same list, bit for bit.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <utility>

#include "core/page_vector.hpp"
#include "core/types.hpp"
#include "neighbor/cell_grid.hpp"

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__)
#include <immintrin.h>
#define GRAINSCALE_PAIR_SCAN_LANES 1
#endif

namespace grainscale::detail {

// The points of a grid as columns in slot order (slot q holds point grid.particles[q]): x, y,
// z, r and the id's bits, 5 doubles per slot, in `buffer` (any contents, resized as needed).
struct GridColumns {
  const Real *x = nullptr, *y = nullptr, *z = nullptr, *r = nullptr;
  const Real* id = nullptr;      // the ids' bits (read by vector loads of 64-bit integers)
  const Index* point = nullptr;  // grid.particles

  void fill(const CellGrid& grid, const Vec3* pos, const Real* radius, const GlobalId* ids,
            PageVector<Real>& buffer) {
    static_assert(sizeof(GlobalId) == sizeof(Real));
    const std::size_t n = grid.particles.size();
    reserve_growing(buffer, 5 * n);  // when it grows, the old buffer goes first
    if (buffer.size() < 5 * n) buffer.resize(5 * n);
    Real* column = buffer.data();
    Real *cx = column, *cy = column + n, *cz = column + 2 * n, *cr = column + 3 * n;
    Real* cid = column + 4 * n;
    point = grid.particles.data();
    for (std::size_t q = 0; q < n; ++q) {
      const Index p = point[q];
      cx[q] = pos[p][0];
      cy[q] = pos[p][1];
      cz[q] = pos[p][2];
      cr[q] = radius[p];
      std::memcpy(cid + q, ids + p, sizeof(GlobalId));  // bits only: no aliasing through types
    }
    x = cx;
    y = cy;
    z = cz;
    r = cr;
    id = cid;
  }
};

#if defined(GRAINSCALE_PAIR_SCAN_LANES)
// The pairs of point a (at xa, with ra = r_a + skin and id ida) with the slots [begin, end),
// stored at `out` from slot `used` on as (owner, partner), owner the point with the smaller id,
// pairs with a ghost owner left out (n owned points). Writes up to 8 slots past the last pair
// kept; returns the new count.
[[gnu::always_inline]] inline std::size_t scan_lanes(const GridColumns& g, Index begin, Index end,
                                                     Index a, const Vec3& xa, Real ra, GlobalId ida,
                                                     Index n, std::pair<Index, Index>* out,
                                                     std::size_t used) {
  static_assert(sizeof(Index) == 4 && sizeof(std::pair<Index, Index>) == 8);
  const __m512d ax = _mm512_set1_pd(xa[0]), ay = _mm512_set1_pd(xa[1]), az = _mm512_set1_pd(xa[2]),
                reach = _mm512_set1_pd(ra);
  const __m512i aid = _mm512_set1_epi64(ida);
  const __m256i self = _mm256_set1_epi32(a), owned = _mm256_set1_epi32(n);
  for (Index q = begin; q < end; q += 8) {
    const auto valid = static_cast<__mmask8>((1u << std::min<Index>(8, end - q)) - 1);
    const __m512d dx = _mm512_sub_pd(ax, _mm512_maskz_loadu_pd(valid, g.x + q));
    const __m512d dy = _mm512_sub_pd(ay, _mm512_maskz_loadu_pd(valid, g.y + q));
    const __m512d dz = _mm512_sub_pd(az, _mm512_maskz_loadu_pd(valid, g.z + q));
    const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx, dx), _mm512_mul_pd(dy, dy)),
                                     _mm512_mul_pd(dz, dz));
    const __m512d cut = _mm512_add_pd(reach, _mm512_maskz_loadu_pd(valid, g.r + q));
    // Not (d2 >= cut^2): a NaN distance is kept, as in the scalar test.
    const __mmask8 near = _mm512_mask_cmp_pd_mask(valid, d2, _mm512_mul_pd(cut, cut), _CMP_NGE_UQ);
    const __mmask8 a_first =
        _mm512_cmplt_epi64_mask(aid, _mm512_maskz_loadu_epi64(valid, g.id + q));
    const __m256i b = _mm256_maskz_loadu_epi32(valid, g.point + q);
    const __m256i owner = _mm256_mask_blend_epi32(a_first, b, self);
    const __m256i partner = _mm256_mask_blend_epi32(a_first, self, b);
    const __mmask8 keep = near & _mm256_cmplt_epi32_mask(owner, owned);
    // (owner, partner) as one 64-bit lane: owner in the low half, as std::pair lays it out.
    // (The masked forms: the plain ones trip a false -Wmaybe-uninitialized in GCC 12.)
    const __m512i pairs = _mm512_or_si512(
        _mm512_maskz_cvtepu32_epi64(0xFF, owner),
        _mm512_maskz_slli_epi64(0xFF, _mm512_maskz_cvtepu32_epi64(0xFF, partner), 32));
    _mm512_storeu_si512(out + used, _mm512_maskz_compress_epi64(keep, pairs));
    used += static_cast<std::size_t>(__builtin_popcount(keep));
  }
  return used;
}

#endif

}  // namespace grainscale::detail
