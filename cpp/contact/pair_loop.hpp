// The particle-particle force loop, a template over the contact law (one implementation per law,
// inlined; no virtual calls). Pairs are stored once; forces on ghosts are folded back by the
// GhostExchange. Torque arm: contact radius r - overlap/2 (as LIGGGHTS).
//
// Three passes over batches of up to kBatch touching contacts (core/simd_pack.hpp):
//   1. scan the list in order, in chunks of entries that cannot overflow the batch and without
//      a loop per row (rows hold two or three entries: the exit of a loop per row mispredicts
//      at nearly every row): the overlap tests of a chunk, then its slots without branches in
//      a bed (fill_slots; a contact that closes forgets its history), then each touching
//      contact's inputs gathered into the batch, one array per quantity (the accesses to
//      particle j happen here); the velocities, masses (and, for EPSD, rolling inertias) of j
//      and the touching contacts' histories are prefetched on the way, as the hardware cannot
//      guess either address (bench_pair_loop: 5-20 % per law);
//   2. evaluate the law on packs of kPackLanes contacts: plain vector loads, the divisions and
//      square roots of kPackLanes contacts in one instruction each; the histories in and out of
//      columns by core/lane_columns.hpp;
//   3. replay the batch in list order, adding each contact's force and torques to i and j in
//      exactly the sequence of a one-contact-at-a-time loop; a row's sum goes to its particle
//      where the next row starts, without a branch.
// Pass 2 gives the scalar law's bits and pass 3 the scalar loop's summation order, so the
// forces are the same bits for every lane width (tests/cpp/test_contact_lanes.cpp). Builds
// without SIMD packs take one contact at a time (pair_loop_one_by_one.hpp; see
// accumulate_pair_forces at the end).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "contact/contact_input.hpp"
#include "contact/contact_stats.hpp"
#include "contact/pair_loop_one_by_one.hpp"
#include "core/lane_columns.hpp"
#include "core/simd_pack.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace grainscale {

namespace detail {

// The touching contacts of one batch, a structure of arrays (pass 1 writes, pass 2 reads
// packs of it, pass 3 reads the results). Lives on the stack: about 20 kB.
template <bool kRolling, bool kInertia>
struct PairBatch {
  static constexpr int kCapacity = 64;  // a multiple of every lane width
  static_assert(kCapacity % kPackLanes == 0);
  using Column = Real[kCapacity];
  alignas(64) Column dx, dy, dz, rsum, ri, rj, dvx, dvy, dvz, wix, wiy, wiz, wjx, wjy, wjz,
      inv_mass_sum;
  alignas(64) Real rolling[kInertia ? 1 : 0][kCapacity];  // 1 / I_r sum
  // Results: the force on i, the torques a_i n x F and a_j n x F, the rolling torque on i.
  alignas(64) Column fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz;
  alignas(64) Real rolling_torque[kRolling ? 3 : 0][kCapacity];
  alignas(64) Column overlap, nx, ny, nz;  // for the statistics
  // (16 more: pass 1 may write a whole vector of slots from the last one on)
  Index i[kCapacity + 16], j[kCapacity + 16], entry[kCapacity + 16];
  int pair[kCapacity];
  int count = 0;

  // Fills the lanes after the last contact with copies of it (their results are not used).
  void pad(int end) {
    for (Real* column :
         {dx, dy, dz, rsum, ri, rj, dvx, dvy, dvz, wix, wiy, wiz, wjx, wjy, wjz, inv_mass_sum})
      std::fill(column + count, column + end, column[count - 1]);
    if constexpr (kInertia) std::fill(rolling[0] + count, rolling[0] + end, rolling[0][count - 1]);
    std::fill(pair + count, pair + end, pair[count - 1]);
    std::fill(entry + count, entry + end, entry[count - 1]);
  }
};

// Pass 3's running sum of a row (force or torque on i): x and y as a pair of doubles (one SSE2
// register on every x86-64 target) and z, so that a new row resets it by a bitwise AND and the
// finished sum goes to an address picked by bit masks. With selects GCC 12 turned the change of
// row back into a branch, which mispredicts at nearly every row; a vector of four doubles
// would do here with AVX but is split through memory without it (portable build 22 % slower).
using Pair2 = Real __attribute__((vector_size(2 * sizeof(Real))));
using Mask2 = std::int64_t __attribute__((vector_size(2 * sizeof(Real))));
struct RowSum {
  Pair2 xy{};
  Real z = 0;
  // The same operations, component by component, as Vec3's += and -=.
  [[gnu::always_inline]] void add(Real x, Real y, Real zz) {
    xy += Pair2{x, y};
    z += zz;
  }
  [[gnu::always_inline]] void subtract(Real x, Real y, Real zz) {
    xy -= Pair2{x, y};
    z -= zz;
  }
};

// a where mask is all ones, b where it is zero.
[[gnu::always_inline]] inline Real* pick(std::int64_t mask, Real* a, Real* b) {
  const auto m = static_cast<std::uintptr_t>(mask);
  return reinterpret_cast<Real*>((reinterpret_cast<std::uintptr_t>(a) & m) |
                                 (reinterpret_cast<std::uintptr_t>(b) & ~m));
}
// s = +0 where mask is all ones, unchanged where it is zero (exactly +0: s * 0 would keep the
// sign).
[[gnu::always_inline]] inline void zero_if(std::int64_t mask, RowSum& s) {
  s.xy = reinterpret_cast<Pair2>(reinterpret_cast<Mask2>(s.xy) & ~(Mask2{} + mask));
  std::int64_t z;
  std::memcpy(&z, &s.z, sizeof z);
  z &= ~mask;
  std::memcpy(&s.z, &z, sizeof z);
}
// to[0..2] += s, as Vec3's +=.
[[gnu::always_inline]] inline void add_to(Real* to, const RowSum& s) {
  to[0] += s.xy[0];
  to[1] += s.xy[1];
  to[2] += s.z;
}

// Pass 1's slots for the entries [k0, k1): entry k goes to slot q (its row owner[k], its
// partner, k), and q moves on where touches[k - k0] is set; returns the new q. A contact that
// opens or closes (touching[k] differs) goes to on_change(k, touch) first. Without a branch per
// entry: touching or not is unpredictable in a bed. With AVX-512, 16 entries at a time, the
// kept ones packed by vpcompressd (the slots after q may then hold others' values, unused).
template <class Batch, class OnChange>
[[gnu::always_inline]] inline int fill_slots(Batch& batch, int q, Index k0, Index k1,
                                             const Index* owner, const Index* partner,
                                             const std::uint8_t* touches,
                                             const std::uint8_t* touching, OnChange on_change) {
#if defined(__AVX512F__) && defined(__AVX512BW__) && defined(__AVX512VL__)
  static_assert(sizeof(Index) == 4);
  const __m512i iota = _mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
  for (Index k = k0; k < k1; k += 16) {
    const auto valid = static_cast<__mmask16>((1u << std::min<Index>(16, k1 - k)) - 1);
    const std::uint8_t* t = touches + (k - k0);
    const __m128i now = _mm_maskz_loadu_epi8(valid, t);
    const __m128i was = _mm_maskz_loadu_epi8(valid, touching + k);
    // A contact that opens or closes is rare: this loop seldom runs.
    for (unsigned c = _mm_cmpneq_epi8_mask(was, now); c != 0; c &= c - 1) {
      const int l = __builtin_ctz(c);
      on_change(k + l, t[l] != 0);
    }
    const __mmask16 keep = _mm_test_epi8_mask(now, now);
    const __m512i rows = _mm512_maskz_loadu_epi32(valid, owner + k);
    const __m512i partners = _mm512_maskz_loadu_epi32(valid, partner + k);
    const __m512i entries = _mm512_add_epi32(_mm512_set1_epi32(k), iota);
    _mm512_storeu_si512(batch.i + q, _mm512_maskz_compress_epi32(keep, rows));
    _mm512_storeu_si512(batch.j + q, _mm512_maskz_compress_epi32(keep, partners));
    _mm512_storeu_si512(batch.entry + q, _mm512_maskz_compress_epi32(keep, entries));
    q += __builtin_popcount(keep);
  }
#else
  // Every entry is written to the next free slot, which only a touching one keeps.
  for (Index k = k0; k < k1; ++k) {
    const bool touch = touches[k - k0];
    batch.i[q] = owner[k];
    batch.j[q] = partner[k];
    batch.entry[q] = k;
    if (touching[k] != touch) on_change(k, touch);  // rare, hence predictable
    q += touch;
  }
#endif
  return q;
}

// Pass 2 on lanes [b, b + kPackLanes) of the batch.
template <class Law, bool kUpdate, class Batch>
[[gnu::always_inline]] inline void evaluate_pack(const Law& law, Batch& batch, int b, int valid,
                                                 Real* history, Real dt) {
  using T = LaneReal;
  constexpr int S = Law::kHistorySize;
  constexpr int W = kPackLanes;
  const LaneVec<T> d{load_lanes<T>(batch.dx + b), load_lanes<T>(batch.dy + b),
                     load_lanes<T>(batch.dz + b)};
  const T rsum = load_lanes<T>(batch.rsum + b);
  const T ri = load_lanes<T>(batch.ri + b), rj = load_lanes<T>(batch.rj + b);
  const T dist = sqrt_lanes(squared_norm(d));
  const T overlap = rsum - dist;
  const T inv_mass_sum = load_lanes<T>(batch.inv_mass_sum + b);
  PairMeans<T> means;
  if constexpr (Law::kRollingInertia)
    means =
        pair_means<true>(d, dist, ri, rj, rsum, inv_mass_sum, load_lanes<T>(batch.rolling[0] + b));
  else
    means = pair_means<false>(d, dist, ri, rj, rsum, inv_mass_sum);
  const LaneVec<T>& nrm = means.normal;
  const T ai = ri - 0.5 * overlap, aj = rj - 0.5 * overlap;
  const LaneVec<T> wi{load_lanes<T>(batch.wix + b), load_lanes<T>(batch.wiy + b),
                      load_lanes<T>(batch.wiz + b)};
  const LaneVec<T> wj{load_lanes<T>(batch.wjx + b), load_lanes<T>(batch.wjy + b),
                      load_lanes<T>(batch.wjz + b)};
  const LaneVec<T> dv{load_lanes<T>(batch.dvx + b), load_lanes<T>(batch.dvy + b),
                      load_lanes<T>(batch.dvz + b)};
  ContactLanes<T> c{nrm,
                    overlap,
                    means.r_eff,
                    means.m_eff,
                    dv - cross(ai * wi + aj * wj, nrm),
                    dt,
                    LaneVec<T>::zero(),
                    splat<T>(0)};
  if constexpr (Law::kRolling) {
    c.w_rel = wi - wj;  // the subtraction a scalar loop does, lane by lane
  }
  if constexpr (Law::kRollingInertia) c.rolling_inertia = means.rolling_inertia;
  // The history of each lane, as one value per lane and history slot.
  const typename Law::Pair* pairs[W];
  std::size_t at[W];  // where each lane's history starts
  for (int l = 0; l < W; ++l) {
    pairs[l] = &law.pair_at(batch.pair[b + l]);
    at[l] = static_cast<std::size_t>(batch.entry[b + l]) * S;
  }
  T h[S];
  load_columns<S>(history, at, h);
  ContactLanesOutput<T> out;
  if constexpr (std::is_same_v<T, Real>)
    out = law.force_lanes(Param<typename Law::Pair, Real>(*pairs[0]), c, h);
  else
    out = law.force_lanes(Param<typename Law::Pair, T>::of(pairs), c, h);
  if constexpr (kUpdate) store_columns<S>(history, at, valid, h);
  const LaneVec<T>& F = out.force;
  const LaneVec<T> nxf = cross(nrm, F);
  const LaneVec<T> ti = ai * nxf, tj = aj * nxf;
  store_lanes(batch.fx + b, F.x);
  store_lanes(batch.fy + b, F.y);
  store_lanes(batch.fz + b, F.z);
  store_lanes(batch.tix + b, ti.x);
  store_lanes(batch.tiy + b, ti.y);
  store_lanes(batch.tiz + b, ti.z);
  store_lanes(batch.tjx + b, tj.x);
  store_lanes(batch.tjy + b, tj.y);
  store_lanes(batch.tjz + b, tj.z);
  if constexpr (Law::kRolling) {
    store_lanes(batch.rolling_torque[0] + b, out.rolling_torque.x);
    store_lanes(batch.rolling_torque[1] + b, out.rolling_torque.y);
    store_lanes(batch.rolling_torque[2] + b, out.rolling_torque.z);
  }
  store_lanes(batch.overlap + b, overlap);
  store_lanes(batch.nx + b, nrm.x);
  store_lanes(batch.ny + b, nrm.y);
  store_lanes(batch.nz + b, nrm.z);
}

}  // namespace detail

// kUpdate = false evaluates forces without advancing the history (set-up evaluations must
// not advance the tangential springs). kStats fills `stats`.
// flatten: everything the law calls is inlined.
template <class Law, bool kUpdate, bool kStats>
[[gnu::flatten]] void accumulate_pair_forces_batched(const Law& law, ParticleStore& ps,
                                                     ContactList& list, Real dt,
                                                     ContactStats& stats) {
  constexpr int S = Law::kHistorySize;
  constexpr int W = kPackLanes;
  using Batch = detail::PairBatch<Law::kRolling, Law::kRollingInertia>;
  constexpr int kMinChunk = 16;  // fewer free slots: the batch is evaluated first
  const Index n = ps.n_owned();
  const Vec3* x = ps.position.data();
  const Vec3* v = ps.velocity.data();
  const Vec3* w = ps.angular_velocity.data();
  const Real* r = ps.radius.data();
  const Real* im = ps.inv_mass.data();
  const Real* irl = ps.inv_rolling_inertia.data();
  const std::int32_t* mat = ps.material.data();
  Vec3* f = ps.force.data();
  Vec3* t = ps.torque.data();
  const Index* partner = list.partner.data();
  Real* hist = list.history.data();
  Batch batch;

  // Pass 3 state: the row being summed, its force and torque so far, and where they go when
  // the row ends (f[i] += fi, as in a scalar loop). Rows change every two or three contacts,
  // unpredictably: the sum is passed on without a branch, to the row's particle when the next
  // row starts and to a scratch slot while the row goes on. Rows without touching contacts are
  // skipped: the scalar loop adds a zero sum to them, which changes no force (forces are never
  // -0: they start at m g, Level::set_gravity, and sums and differences of values that are not
  // -0 are not -0).
  Index open = -1;
  using detail::RowSum;
  RowSum fi, ti;
  Real scratch_f[3] = {}, scratch_t[3] = {};
  Real *row_f = scratch_f, *row_t = scratch_t;
  auto flush = [&]() {
    const int count = batch.count;
    if (count == 0) return;
    const int end = (count + W - 1) / W * W;
    if (end > count) batch.pad(end);
    for (int b = 0; b < end; b += W)
      detail::evaluate_pack<Law, kUpdate>(law, batch, b, std::min(W, count - b), hist, dt);
    for (int q = 0; q < count; ++q) {
      const Index i = batch.i[q], j = batch.j[q];
      const std::int64_t new_row = -static_cast<std::int64_t>(i != open);  // all ones or zero
      detail::add_to(detail::pick(new_row, row_f, scratch_f), fi);
      detail::add_to(detail::pick(new_row, row_t, scratch_t), ti);
      detail::zero_if(new_row, fi);  // a new row starts from +0, as fi.setZero()
      detail::zero_if(new_row, ti);
      open = i;
      row_f = f[i].data();
      row_t = t[i].data();
      const Vec3 F(batch.fx[q], batch.fy[q], batch.fz[q]);
      const Vec3 tq_j(batch.tjx[q], batch.tjy[q], batch.tjz[q]);
      fi.add(F[0], F[1], F[2]);
      ti.subtract(batch.tix[q], batch.tiy[q], batch.tiz[q]);
      f[j] -= F;
      t[j] -= tq_j;
      if constexpr (Law::kRolling) {
        const Vec3 M(batch.rolling_torque[0][q], batch.rolling_torque[1][q],
                     batch.rolling_torque[2][q]);
        ti.add(M[0], M[1], M[2]);
        t[j] -= M;
      }
      if constexpr (kStats) {
        const Real overlap = batch.overlap[q];
        ++stats.contacts;
        stats.max_overlap_ratio = std::max(stats.max_overlap_ratio, overlap / std::min(r[i], r[j]));
        if (stats.record)
          stats.records.push_back(
              {ps.id[i], ps.id[j], overlap, Vec3(batch.nx[q], batch.ny[q], batch.nz[q]), F, i, j});
      }
    }
    batch.count = 0;
  };

  std::uint8_t* touching = list.touching.data();
  const bool one_material = law.single_material();
  const Index total = list.first[n];
  const Index* owner = list.owner.data();
  if (list.owner.size() != static_cast<std::size_t>(total))
    throw std::logic_error("accumulate_pair_forces: the contact list's rows are not indexed");
  // Pass 1 runs over the list in chunks that cannot overflow the batch, one entry at a time
  // without a loop per row: rows hold two or three entries, and a loop per row would
  // mispredict its exit at nearly every row. owner[k] is the row of entry k (the list's
  // index, made at the build).
  for (Index k0 = 0; k0 < total;) {
    if (Batch::kCapacity - batch.count < kMinChunk) flush();
    const Index k1 = std::min<Index>(total, k0 + (Batch::kCapacity - batch.count));
    // The overlap test of every entry of the chunk. Nothing carries from one entry to the next,
    // so the loads of many entries are in flight at once (with the slot count below in the
    // same loop, every store waited for the test of the entry before).
    std::uint8_t touches[Batch::kCapacity];
    for (Index k = k0; k < k1; ++k) {
      const Index i = owner[k];
      const Index j = partner[k];
      const Vec3 d = x[i] - x[j];
      const Real ri = r[i], rj = r[j];
      const Real rsum = ri + rj;
      touches[k - k0] = d.squaredNorm() < rsum * rsum;
      __builtin_prefetch(v + j);
      __builtin_prefetch(w + j);
      __builtin_prefetch(im + j);
      if constexpr (Law::kRollingInertia) __builtin_prefetch(irl + j);
    }
    // The slots. A contact that opens or closes: a closed one forgets its history, as a new
    // contact starts from zero (set-up evaluations change neither).
    const int q = detail::fill_slots(
        batch, batch.count, k0, k1, owner, partner, touches, touching, [&](Index k, bool touch) {
          if constexpr (kUpdate) {
            if (!touch)
              std::fill(hist + static_cast<std::size_t>(k) * S,
                        hist + static_cast<std::size_t>(k + 1) * S, Real(0));
            touching[k] = touch;
          }
        });
    // Each touching contact's inputs (the geometry again: cheaper than storing it for every
    // entry, the data is still in L1).
    for (int c = batch.count; c < q; ++c) {
      const Index i = batch.i[c], j = batch.j[c];
      {
        const Real* h = hist + static_cast<std::size_t>(batch.entry[c]) * S;
        __builtin_prefetch(h, 1);
        __builtin_prefetch(h + S - 1, 1);
      }
      const Vec3 d = x[i] - x[j];
      const Real ri = r[i], rj = r[j];
      batch.ri[c] = ri;
      batch.rj[c] = rj;
      batch.dx[c] = d[0];
      batch.dy[c] = d[1];
      batch.dz[c] = d[2];
      batch.rsum[c] = ri + rj;
      batch.pair[c] = one_material ? 0 : law.pair_index(mat[i], mat[j]);
      const Vec3 dv = v[i] - v[j];
      batch.dvx[c] = dv[0];
      batch.dvy[c] = dv[1];
      batch.dvz[c] = dv[2];
      batch.wix[c] = w[i][0];
      batch.wiy[c] = w[i][1];
      batch.wiz[c] = w[i][2];
      batch.wjx[c] = w[j][0];
      batch.wjy[c] = w[j][1];
      batch.wjz[c] = w[j][2];
      batch.inv_mass_sum[c] = im[i] + im[j];
      if constexpr (Law::kRollingInertia) batch.rolling[0][c] = irl[i] + irl[j];
    }
    batch.count = q;
    k0 = k1;
  }
  flush();
  detail::add_to(row_f, fi);
  detail::add_to(row_t, ti);
}

// The pair forces of the owned particles. SIMD builds batch in packs, in beds and loose systems
// alike: with pass 1 free of branches per entry and per row, batching costs less than the
// one-contact loop's branches even where few entries touch (bench/README.md). Scalar builds
// (GRAINSCALE_SIMD=OFF) take one contact at a time: with one lane per pack the batch is only a
// detour. Both give the same bits.
template <class Law, bool kUpdate, bool kStats>
void accumulate_pair_forces(const Law& law, ParticleStore& ps, ContactList& list, Real dt,
                            ContactStats& stats) {
  if constexpr (kPackLanes > 1)
    accumulate_pair_forces_batched<Law, kUpdate, kStats>(law, ps, list, dt, stats);
  else
    accumulate_pair_forces_one_by_one<Law, kUpdate, kStats>(law, ps, list, dt, stats);
}

}  // namespace grainscale
