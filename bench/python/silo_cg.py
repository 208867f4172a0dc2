"""Wall-clock of one silo discharge, resolved and coarse-grained (h = 1, 2, 3).

The case is one run of ``studies.silo_discharge.silo_discharge.run_orifice`` with the study's
SiloCase (validation/CASES.md D1: constant-head silo, D_s = max(2.5 D0, D0 + 20 d), bed
max(0.5 D_s, 2 D0) deep, spheres d = 4 mm, fill by pouring, settle, discharge over the
measuring window) at one orifice (default D0 = 40 mm), with ``SiloCase.cg = h``: the parcels'
parameters come from ``grainscale.scaling.scale(..., "cg")``, the silo and the simulated time
are those of the resolved case. A CG run holds about h^3 fewer particles and takes h fewer
steps (time step x h), so the expected speed-up is about h^4 if the cost is proportional to
particle-steps; the fill (same pour time) and the per-chunk Python work (outlet checks, refill
every 0.02 s) do not shrink with h.

Each repeat runs every h in turn (the order rotates between repeats, because the machine is
shared); the table shows medians: particles at opening, steps, simulated time, wall-clock,
wall-clock per simulated second, particle-steps per second and the speed-up against h = 1
next to h^4 and to the particle-step ratio. Raw numbers go to bench/results/silo_cg.json.

Usage: python bench/python/silo_cg.py [--orifice 40] [--cg 1 2 3] [--repeats 3]
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from bench_common import write_results

from studies.silo_discharge import silo_case, silo_run

REPO = Path(__file__).resolve().parents[2]
DEFAULT_OUTPUT = REPO / "bench" / "results" / "silo_cg.json"


def run_once(case: silo_case.SiloCase, orifice: float, seed: int) -> dict[str, Any]:
    """One silo run of ``case``: its size, steps and wall-clock."""
    t0 = time.perf_counter()
    r = silo_run.run_orifice(case, orifice, seed)
    wall = time.perf_counter() - t0
    simulated = r.fill_time + r.discharge_time
    return {
        "cg": case.cg,
        "seed": seed,
        "particles": r.particles,
        "steps": r.steps,
        "time_step": r.time_step,
        "simulated_s": simulated,
        "wall_clock_s": wall,
        "wall_clock_per_simulated_s": wall / simulated,
        "particle_steps": r.particle_steps,
        "particle_steps_per_s": r.particle_steps / wall,
        "rate_kg_s": r.rate,
        "loadavg_1min": os.getloadavg()[0],
    }


def summarise(rows: list[dict[str, Any]], hs: list[float]) -> list[dict[str, Any]]:
    """Medians per h and the speed-up against the smallest h."""
    out = []
    for h in hs:
        mine = [r for r in rows if r["cg"] == h]
        med = {
            key: statistics.median(r[key] for r in mine)
            for key in (
                "particles",
                "steps",
                "simulated_s",
                "wall_clock_s",
                "wall_clock_per_simulated_s",
                "particle_steps",
                "particle_steps_per_s",
            )
        }
        out.append({"cg": h, "repeats": len(mine), **med})
    base = out[0]
    for s in out:
        ratio = s["cg"] / base["cg"]
        s["speed_up"] = base["wall_clock_s"] / s["wall_clock_s"]
        s["expected_h4"] = ratio**4
        s["particle_step_ratio"] = base["particle_steps"] / s["particle_steps"]
        s["particle_ratio"] = base["particles"] / s["particles"]
        s["step_ratio"] = base["steps"] / s["steps"]
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--orifice", type=float, default=40.0, help="D0 in mm (default 40)")
    parser.add_argument("--cg", type=float, nargs="+", default=[1.0, 2.0, 3.0], metavar="H")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT)
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats must be at least 1, got {args.repeats}")
    hs = sorted(args.cg)
    orifice = args.orifice * 1e-3
    rows = []
    for k in range(args.repeats):
        order = hs[k % len(hs) :] + hs[: k % len(hs)]
        for h in order:
            case = silo_case.SiloCase(cg=h)
            row = run_once(case, orifice, args.seed)
            row["repeat"] = k
            rows.append(row)
            print(
                f"repeat {k} h = {h:g}: {row['particles']} particles, {row['steps']} steps, "
                f"{row['wall_clock_s']:.1f} s wall-clock (load {row['loadavg_1min']:.1f})",
                flush=True,
            )
    summary = summarise(rows, hs)
    print(f"\nsilo D0 = {args.orifice:g} mm ({silo_case.SiloCase().describe()}), medians:")
    head = (
        f"{'h':>3} {'particles':>9} {'steps':>7} {'sim (s)':>7} {'wall (s)':>8} "
        f"{'wall/sim s':>10} {'p-steps/s':>9} {'speed-up':>8} {'h^4':>5} {'N*steps ratio':>13}"
    )
    print(head)
    for s in summary:
        print(
            f"{s['cg']:>3g} {s['particles']:>9.0f} {s['steps']:>7.0f} {s['simulated_s']:>7.2f} "
            f"{s['wall_clock_s']:>8.1f} {s['wall_clock_per_simulated_s']:>10.1f} "
            f"{s['particle_steps_per_s']:>9.3g} {s['speed_up']:>8.1f} {s['expected_h4']:>5.0f} "
            f"{s['particle_step_ratio']:>13.1f}"
        )
    entry = {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "orifice_m": orifice,
        "case": dataclasses.asdict(silo_case.SiloCase()),
        "runs": rows,
        "summary": summary,
    }
    # one entry per orifice; entries of other orifices already in the file are kept
    write_results(args.output, "silo_cg", {f"D{args.orifice:g}": entry}, {"argv": sys.argv})
    print(f"\nwritten {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
