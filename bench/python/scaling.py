"""Strong scaling of the 'settle' case on 1 and 2 ranks, grainscale and LIGGGHTS 3.8 side by side,
and the halo sizes at more ranks (oversubscribed) for bench/SCALING.md.

The case is settle_case.py's (the same input for both codes). Each (code, ranks) runs in its own
process tree under mpirun (one plain process for one rank); the runs alternate for ``--repeats``
rounds. Reported per (code, ranks): median wall-clock ns per particle-step of the run (LIGGGHTS'
"Loop time", grainscale's ``Simulation.run`` between barriers); the parallel efficiency
E(k) = t(1) / (k t(k)) from the per-round pairs, and grainscale / LIGGGHTS at each rank count.

``--halo 2 4 8`` adds short grainscale runs at those rank counts (more ranks than cores: only the
counts are meaningful there, not the times) and records particles and ghosts per rank, for the
model in bench/SCALING.md.

Usage: python bench/python/scaling.py [--size 200000] [--steps 4000] [--ranks 1 2]
                                      [--repeats 3] [--only grainscale|liggghts]
                                      [--halo 2 4 8] [--halo-steps 200]
                                      [--balance-every STEPS]
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path
from typing import Any

from bench_common import (
    CODES,
    BenchmarkError,
    check_grainscale,
    ensure_liggghts,
    run_grainscale_worker,
    run_liggghts_log,
    run_rounds,
    write_results,
)
from settle import WORKER, prepare_inputs
from settle_case import SettleCase

HERE = Path(__file__).resolve().parent
DEFAULT_OUTPUT = HERE.parents[1] / "bench" / "results" / "scaling.json"


class Run:
    def __init__(self, code: str, rnd: int, ranks: int, seconds: float, case: SettleCase) -> None:
        self.code = code
        self.round = rnd
        self.ranks = ranks
        self.run_seconds = seconds
        self.ns_per_particle_step = seconds / (case.steps * case.n_particles) * 1e9
        self.maxrss_kib = 0
        self.warnings: list[str] = []
        self.extra: dict[str, Any] = {}


# grainscale's automatic load-balancing interval (steps) in the runs; None: the engine's default.
BALANCE_EVERY: int | None = None


def run_one(code: str, ranks: int, case: SettleCase, workdir: Path, rnd: int, exe: str) -> Run:
    if code == "liggghts":
        log = run_liggghts_log(exe, workdir, "in.settle", "log.settle", ranks=ranks)
        if log["procs"] != ranks or log["steps"] != case.steps:
            raise BenchmarkError(f"unexpected LIGGGHTS loop line: {log}")
        run = Run(code, rnd, ranks, float(log["loop_seconds"]), case)
        run.maxrss_kib = log["maxrss_kib"]
        run.extra = {"atoms": int(log["thermo"][-1]["Atoms"])}
        return run
    options = ["--case", str(workdir / "case.json"), "--state", str(workdir / "state.npz")]
    if BALANCE_EVERY is not None:
        options += ["--balance-every", str(BALANCE_EVERY)]
    res, rss, _, warnings = run_grainscale_worker(WORKER, workdir, options, ranks=ranks)
    if res["n_final"] != case.n_particles:
        raise BenchmarkError(f"grainscale lost particles: {res['n_final']} of {case.n_particles}")
    run = Run(code, rnd, ranks, float(res["run_seconds"]), case)
    run.maxrss_kib, run.warnings = rss, warnings
    run.extra = {
        k: res[k]
        for k in ("particles_per_rank", "ghosts_per_rank", "halo_seconds_per_rank", "rebuilds")
    }
    return run


def strong_scaling(
    case: SettleCase, codes: list[str], ranks: list[int], repeats: int, exe: str
) -> dict[str, Any]:
    labels = [f"{code}@{k}" for k in ranks for code in codes]

    def run(label: str, workdir: Path, rnd: int) -> Run:
        code, k = label.split("@")
        return run_one(code, int(k), case, workdir, rnd, exe)

    runs, stamp = run_rounds(
        "scaling", case.n_particles, labels, repeats, False, lambda w: prepare_inputs(case, w), run
    )
    table: dict[str, Any] = {}
    for code in codes:
        per_k = {k: [r for r in runs if r.code == code and r.ranks == k] for k in ranks}
        table[code] = {
            str(k): {
                "median_ns_per_particle_step": statistics.median(
                    r.ns_per_particle_step for r in rs
                ),
                "runs_ns_per_particle_step": [r.ns_per_particle_step for r in rs],
                "peak_rss_mib": max(r.maxrss_kib for r in rs) / 1024.0,
                "extra": [r.extra for r in rs],
            }
            for k, rs in per_k.items()
        }
        if 1 in per_k:
            for k in ranks:
                if k == 1:
                    continue
                pairs = [
                    a.run_seconds / (k * b.run_seconds)
                    for a in per_k[1]
                    for b in per_k[k]
                    if a.round == b.round
                ]
                table[code][str(k)]["efficiency_per_round"] = pairs
                table[code][str(k)]["efficiency_median"] = statistics.median(pairs)
    if len(codes) == 2:
        for k in ranks:
            pairs = [
                a.run_seconds / b.run_seconds
                for a in runs
                for b in runs
                if a.code == "grainscale"
                and b.code == "liggghts"
                and a.ranks == b.ranks == k
                and a.round == b.round
            ]
            table[f"ratio_grainscale_over_liggghts@{k}"] = {
                "per_round": pairs,
                "median": statistics.median(pairs),
            }
    return {"timestamp": stamp, "case": case.to_dict(), "repeats": repeats, "summary": table}


def halo_sizes(case: SettleCase, ranks: list[int]) -> dict[str, Any]:
    out: dict[str, Any] = {}

    def run(label: str, workdir: Path, rnd: int) -> Run:
        return run_one("grainscale", int(label), case, workdir, rnd, "")

    runs, _ = run_rounds(
        "halo", case.n_particles, [str(k) for k in ranks], 1, False,
        lambda w: prepare_inputs(case, w), run,
    )  # fmt: skip
    for r in runs:
        out[str(r.ranks)] = r.extra | {"ns_per_particle_step": r.ns_per_particle_step}
    return out


def print_summary(entry: dict[str, Any], codes: list[str], ranks: list[int]) -> None:
    s = entry["summary"]
    print(f"\nN = {entry['case']['n_particles']}, {entry['case']['steps']} steps")
    for code in codes:
        for k in ranks:
            c = s[code][str(k)]
            eff = c.get("efficiency_median")
            ns = c["median_ns_per_particle_step"]
            print(
                f"  {code:<11s} {k} rank(s): {ns:7.1f} ns/particle-step"
                + (f", parallel efficiency {eff:.3f}" if eff is not None else "")
            )
    for k in ranks:
        r = s.get(f"ratio_grainscale_over_liggghts@{k}")
        if r:
            per = ", ".join(f"{v:.3f}" for v in r["per_round"])
            print(f"  grainscale/liggghts at {k} rank(s): median {r['median']:.3f} ({per})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size", type=int, default=200_000)
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", choices=CODES, default=None)
    parser.add_argument("--halo", type=int, nargs="*", default=[], help="rank counts for halos")
    parser.add_argument("--halo-steps", type=int, default=200)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT)
    parser.add_argument(
        "--balance-every", type=int, default=None, help="grainscale's load-balancing interval"
    )
    args = parser.parse_args(argv)
    global BALANCE_EVERY
    BALANCE_EVERY = args.balance_every
    codes = [args.only] if args.only else list(CODES)
    try:
        exe = ensure_liggghts() if "liggghts" in codes else ""
        check_grainscale()
        entries: dict[str, Any] = {}
        if args.ranks and args.repeats > 0:
            case = SettleCase(n_particles=args.size, steps=args.steps)
            entries[f"strong_{args.size}"] = strong_scaling(
                case, codes, args.ranks, args.repeats, exe
            )
            print_summary(entries[f"strong_{args.size}"], codes, args.ranks)
        if args.halo:
            case = SettleCase(n_particles=args.size, steps=args.halo_steps)
            entries[f"halo_{args.size}"] = halo_sizes(case, args.halo)
            for k, h in entries[f"halo_{args.size}"].items():
                print(f"  {k} ranks: particles {h['particles_per_rank']}, "
                      f"ghosts {h['ghosts_per_rank']}")  # fmt: skip
        command = vars(args) | {"output": str(args.output)}
        write_results(args.output, "scaling", entries, command)
    except BenchmarkError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"\nraw numbers: {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
