// Microbenchmark of the neighbour-list build: CellGrid binning alone and build_pair_list.
//
// Packing: the first N sites of a simple-cubic lattice with seeded uniform jitter of
// +-0.05 d_mean per coordinate (non-periodic, no ghosts), owned particles put into cell order
// first as Level::rebuild does.
//   mono: d = 1, lattice spacing 1.05 d, skin 0.1 d;
//   poly: d uniform in [1, 3] (size ratio 1:3), spacing 1.05 d_mean = 2.1, skin 0.1 d_min.
//     Large neighbours overlap (the list build is purely geometric); what matters is the
//     cell edge set by the largest diameter and the number of candidates per cell.
// Cells of the cut-off = largest diameter + skin (at most 2 N + 64 cells) and, in the same run,
// of half the cut-off (at most 16 N + 64): CellGrid::build_for_pairs picks the first below a
// size ratio of 2 and the second from 2 on. The
// list gets the Hertz-Mindlin history stride (3), so clearing the history is part of the build.
// Figures: median wall-clock time per owned particle and per list entry (plus thread CPU time,
// cpu=, and the fastest repetition, min=).
//
// Usage: bench_neighbor_build [scale]   (N = 50k and 200k times scale)
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "neighbor/cell_grid.hpp"
#include "neighbor/neighbor_list.hpp"
#include "state/particle_store.hpp"

namespace {

using bench::Index;
using bench::Real;
using bench::Vec3;

struct Row {
  std::string name;
  Index n;
  double entries_per_particle;
  double candidates_per_particle;
  bench::Timing bin;
  bench::Timing list;
};

Row run_case(const std::string& name, Index n, bool poly, int reps) {
  const Real d_min = 1.0;
  const Real d_mean = poly ? 2.0 : 1.0;
  const Real skin = 0.1 * d_min;
  std::vector<Vec3> x = bench::lattice(n, 1.05 * d_mean, 1.05 * d_mean, 0.05 * d_mean, 17);
  std::vector<Real> radius(n, 0.5 * d_min);
  if (poly) {
    std::mt19937_64 rng(29);
    std::uniform_real_distribution<Real> u(0.5 * d_min, 1.5 * d_min);
    for (Real& r : radius) r = u(rng);
  }
  grainscale::ParticleStore ps;
  bench::fill_store(ps, x, radius, 2500.0);
  const Real cutoff = 2 * bench::max_radius(ps) + skin;
  bench::spatial_sort(ps, cutoff);

  // Cells of the cut-off (27-cell stencil; Level's binning for size ratios below 2).
  grainscale::CellGrid grid;
  const bench::Timing bin = bench::median_ns(
      reps, [] {},
      [&] {
        grid.build(ps.position.data(), ps.n_local(), cutoff, 2 * static_cast<std::size_t>(n) + 64);
      });

  grainscale::ContactList list;
  list.history_stride = 3;
  grid.build(ps.position.data(), ps.n_local(), cutoff, 2 * static_cast<std::size_t>(n) + 64);
  const bench::Timing list_t = bench::median_ns(
      reps, [] {}, [&] { grainscale::build_pair_list(ps, grid, cutoff, skin, list); });

  // In the same run: cells of half the cut-off (5 x 5 x 5 stencil; Level's for ratios >= 2).
  grainscale::CellGrid fine;
  fine.build(ps.position.data(), ps.n_local(), 0.5 * cutoff, 16 * static_cast<std::size_t>(n) + 64);
  grainscale::ContactList fine_list;
  fine_list.history_stride = 3;
  const bench::Timing fine_t = bench::median_ns(
      reps, [] {}, [&] { grainscale::build_pair_list(ps, fine, cutoff, skin, fine_list); });
  bench::report("build_pair_list_" + name + "_half_cells", fine_t, n, "ns/particle", n, reps);
  std::printf("  half-cut-off cells / cut-off cells time ratio: %.3f (wall), %.3f (cpu)\n",
              fine_t.wall_ns / list_t.wall_ns, fine_t.cpu_ns / list_t.cpu_ns);

  // Candidates examined by the stencil (both orientations of every pair are visited).
  double candidates = 0;
  const auto R = grid.reach(cutoff);
  for (Index i = 0; i < n; ++i) {
    const auto c = grid.coords(grid.cell_of[i]);
    for (int dz = -R[2]; dz <= R[2]; ++dz)
      for (int dy = -R[1]; dy <= R[1]; ++dy)
        for (int dx = -R[0]; dx <= R[0]; ++dx) {
          const int cx = c[0] + dx, cy = c[1] + dy, cz = c[2] + dz;
          if (cx < 0 || cy < 0 || cz < 0 || cx >= grid.dims[0] || cy >= grid.dims[1] ||
              cz >= grid.dims[2])
            continue;
          const int cell = grid.cell_id(cx, cy, cz);
          candidates += grid.cell_start[cell + 1] - grid.cell_start[cell];
        }
  }

  const double entries = static_cast<double>(list.size());
  Row row{name, n, entries / n, candidates / n, bin, list_t};
  char extra[128];
  std::snprintf(extra, sizeof extra, "half-list entries/particle=%.2f, stencil candidates=%.1f",
                row.entries_per_particle, row.candidates_per_particle);
  bench::report("cell_binning_" + name, bin, n, "ns/particle", n, reps);
  bench::report("build_pair_list_" + name, list_t, n, "ns/particle", n, reps, extra);
  bench::report("build_pair_list_" + name + "_per_entry", list_t, entries, "ns/entry", n, reps,
                extra);
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const double scale = bench::scale_from_args(argc, argv);
  const int reps = 15;
  std::vector<Row> rows;
  for (Index n0 : {50000, 200000}) {
    const Index n = bench::scaled(n0, scale);
    rows.push_back(run_case("mono", n, false, reps));
    rows.push_back(run_case("poly1:3", n, true, reps));
  }
  std::printf("\n%-8s %7s %9s %12s %9s %10s %13s | %10s %13s\n", "case", "N", "entries/p",
              "candidates/p", "bin ns/p", "list ns/p", "list ns/entry", "cpu ns/p", "cpu ns/entry");
  for (const Row& r : rows) {
    const double entries = r.entries_per_particle * r.n;
    std::printf("%-8s %7d %9.2f %12.1f %9.2f %10.1f %13.1f | %10.1f %13.1f\n", r.name.c_str(), r.n,
                r.entries_per_particle, r.candidates_per_particle, r.bin.wall_ns / r.n,
                r.list.wall_ns / r.n, r.list.wall_ns / entries, r.list.cpu_ns / r.n,
                r.list.cpu_ns / entries);
  }
  std::printf(
      "(medians of %d repetitions: wall clock, and list build in thread CPU time after the |; "
      "entries = half-list entries; candidates = points in the stencil)\n",
      reps);
  return 0;
}
