"""Wall-clock of the MLCG silo, fully resolved against multi-level (issue 7's performance target).

The case is ``studies.mlcg_silo.mlcg_silo``'s SiloCase (CASES.md F1/D1: square silo, orifice
D0 = 10 d, filled by a stream, settled, discharged): the resolved run (h = 1 everywhere) and the
hierarchies (h = 2 everywhere, h = 1 in a box around the orifice; with ``--levels 4 2 1`` the
three-level chain). The target: the speed-up in wall-clock per simulated second of the
hierarchy against the resolved run is at least 0.7 x the ratio of their (peak) particle counts.

Each repeat runs every configuration in turn (the order rotates between repeats: the machine is
shared); the table shows medians of wall-clock, wall-clock per simulated second, peak particles
and discharge rate, and per hierarchy the speed-up next to 0.7 x the particle ratio. Raw
numbers go to bench/results/mlcg_speedup.json.

Usage: python bench/python/mlcg_speedup.py [--repeats 3] [--quick] [--levels 2 1] [--levels 4 2 1]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import os
import statistics
import sys
from pathlib import Path
from typing import Any

from bench_common import write_results

from studies.mlcg_silo import mlcg_silo

REPO = Path(__file__).resolve().parents[2]
DEFAULT_OUTPUT = REPO / "bench" / "results" / "mlcg_speedup.json"


def run_once(case: mlcg_silo.SiloCase, levels: tuple[float, ...]) -> dict[str, Any]:
    if levels == (1.0,):
        run = mlcg_silo.run_single(case, 1, None, None)
    else:
        run = mlcg_silo.run_mlcg(case, levels, None)
    return {
        "levels": list(levels),
        "particles": run.particles,
        "wall_clock_s": run.wall_clock,
        "wall_clock_per_simulated_s": run.wall_clock / case.end_time,
        "rate_kg_s": run.rate,
        "loadavg_1min": os.getloadavg()[0],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true", help="the small silo of the tests")
    parser.add_argument(
        "--levels", type=float, nargs="+", action="append", default=None, metavar="H",
        help="one hierarchy, coarsest first (repeatable; default 2 1)",
    )  # fmt: skip
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT)
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    hierarchies = [tuple(h) for h in (args.levels or [[2.0, 1.0]])]
    for h in hierarchies:
        if len(h) < 2 or h[-1] != 1.0 or list(h) != sorted(h, reverse=True):
            parser.error(f"--levels must be decreasing ratios ending at 1, got {list(h)}")
    case = mlcg_silo.QUICK if args.quick else mlcg_silo.SiloCase()
    configs: list[tuple[float, ...]] = [(1.0,), *hierarchies]
    rows = []
    for k in range(args.repeats):
        order = configs[k % len(configs) :] + configs[: k % len(configs)]
        for levels in order:
            row = run_once(case, levels)
            row["repeat"] = k
            rows.append(row)
            print(
                f"repeat {k} levels {' -> '.join(f'{h:g}' for h in levels)}: "
                f"{row['particles']} particles, {row['wall_clock_s']:.1f} s wall-clock, "
                f"W = {row['rate_kg_s'] * 1e3:.1f} g/s (load {row['loadavg_1min']:.1f})",
                flush=True,
            )
    summary = []
    for levels in configs:
        mine = [r for r in rows if r["levels"] == list(levels)]
        med = {
            key: statistics.median(r[key] for r in mine)
            for key in ("particles", "wall_clock_s", "wall_clock_per_simulated_s", "rate_kg_s")
        }
        summary.append({"levels": list(levels), "repeats": len(mine), **med})
    base = summary[0]
    for s in summary:
        s["speed_up"] = base["wall_clock_per_simulated_s"] / s["wall_clock_per_simulated_s"]
        s["particle_ratio"] = base["particles"] / s["particles"]
        s["target_speed_up"] = 0.7 * s["particle_ratio"]
        s["rate_ratio"] = s["rate_kg_s"] / base["rate_kg_s"]
    print(f"\nMLCG silo ({'quick' if args.quick else 'full'} case), medians:")
    print(
        f"{'levels':>10} {'particles':>9} {'wall (s)':>8} {'wall/sim s':>10} {'W ratio':>7} "
        f"{'speed-up':>8} {'0.7 x N ratio':>13}"
    )
    for s in summary:
        print(
            f"{' -> '.join(f'{h:g}' for h in s['levels']):>10} {s['particles']:>9.0f} "
            f"{s['wall_clock_s']:>8.1f} {s['wall_clock_per_simulated_s']:>10.1f} "
            f"{s['rate_ratio']:>7.3f} {s['speed_up']:>8.2f} {s['target_speed_up']:>13.2f}"
        )
    entry = {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "case": dataclasses.asdict(case),
        "runs": rows,
        "summary": summary,
    }
    key = "quick" if args.quick else "full"
    write_results(args.output, "mlcg_speedup", {key: entry}, {"argv": sys.argv})
    print(f"\nwritten {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
