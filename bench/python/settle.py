"""Side-by-side 'settle' benchmark: grainscale against LIGGGHTS 3.8 on one core.

The case (identical physics in both codes, see settle_case.py for the exact definition):
N monodisperse spheres (d = 2 mm, rho = 2500 kg/m^3) start on a jittered simple-cubic lattice
(spacing 2.2 mm, square cross-section of ceil((N/2)^(1/3)) sites, filled bottom-up) with small
seeded random velocities, inside a closed box of six plane walls, and settle under gravity.
Hertz-Mindlin contacts with tangential history (E = 1e7 Pa, nu = 0.3, e = 0.5, mu = 0.5, walls
of the particle material), dt = 1e-5 s, skin 0.2 mm, 4000 steps by default. The tangential
spring is projected onto the new tangent plane each step, as LIGGGHTS does
(``spring_rotation="project"``); ``--spring-rotation rescale`` runs grainscale's default law,
which also keeps the spring's length.

The initial state is generated once per size with numpy and fed to both codes: a LIGGGHTS data
file (atom_style granular, Atoms + Velocities) and an .npz file for ``sim.add_particles``.
Each code runs in its own subprocess in a temporary directory, so that its peak RSS
(``ru_maxrss`` from ``os.wait4``) is measured alone; the two codes alternate for ``--repeats``
rounds because the machine is noisy. Reported cost is wall-clock per particle-step of the run
only: LIGGGHTS' "Loop time" line (one process, no mpirun) and the duration of grainscale's
``Simulation.run`` call. The per-size table shows medians, the median of the per-round ratio
grainscale/LIGGGHTS, peak RSS and the final kinetic energy / mean height of both codes as a
cross-check of identical physics. Raw numbers go to bench/results/settle.json (entries of other
sizes already in that file are kept).

LIGGGHTS is installed with apt-get if missing. The Debian build targets generic x86-64 (no AVX);
keep that in mind when comparing with a grainscale build tuned for the machine. The script prints
which grainscale build it measured (native or portable, bench/README.md) and records it.

Usage: python bench/python/settle.py [--sizes 10000 50000 200000] [--steps 4000] [--repeats 3]
                                     [--only grainscale|liggghts]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from bench_common import (
    CODES,
    BenchmarkError,
    add_spring_rotation_option,
    build_label,
    grainscale_build,
    per_round,
    prepare_codes,
    print_warnings,
    ratio_summary,
    run_grainscale_worker,
    run_liggghts_log,
    run_rounds,
    write_results,
)
from settle_case import SettleCase, initial_state, liggghts_input, write_liggghts_data

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
WORKER = HERE / "settle_grainscale_worker.py"
DEFAULT_OUTPUT = REPO / "bench" / "results" / "settle.json"


@dataclass
class RunResult:
    """One run of one code on one case."""

    code: str
    round: int
    ns_per_particle_step: float
    run_seconds: float
    maxrss_kib: int
    n_final: int
    ke_trans_final: float
    ke_rot_final: float
    mean_z_final: float
    loadavg_1min: float
    warnings: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def ke_final(self) -> float:
        return self.ke_trans_final + self.ke_rot_final


# ---------------------------------------------------------------------------------------------
# set-up


def prepare_inputs(case: SettleCase, workdir: Path, runs: str | None = None) -> None:
    """Generate the initial state once and write it for both codes (``runs``: the commands
    that end the LIGGGHTS input, default ``run <case.steps>``)."""
    pos, vel = initial_state(case)
    write_liggghts_data(workdir / "data.settle", case, pos, vel)
    (workdir / "in.settle").write_text(liggghts_input(case, "../data.settle", runs=runs))
    np.savez(workdir / "state.npz", position=pos, velocity=vel)
    (workdir / "case.json").write_text(json.dumps(dataclasses.asdict(case)))


# ---------------------------------------------------------------------------------------------
# running one code


def run_liggghts(exe: str, case: SettleCase, workdir: Path, rnd: int) -> RunResult:
    log = run_liggghts_log(exe, workdir, "in.settle", "log.settle")
    if log["procs"] != 1 or log["steps"] != case.steps:
        raise BenchmarkError(f"unexpected LIGGGHTS loop line: {log}")
    last = log["thermo"][-1]
    n_final = int(last["Atoms"])
    if n_final != case.n_particles:
        raise BenchmarkError(f"LIGGGHTS lost atoms: {n_final} of {case.n_particles} left")
    loop = float(log["loop_seconds"])
    return RunResult(
        code="liggghts",
        round=rnd,
        ns_per_particle_step=loop / (case.steps * case.n_particles) * 1e9,
        run_seconds=loop,
        maxrss_kib=log["maxrss_kib"],
        n_final=n_final,
        ke_trans_final=float(last["KinEng"]),
        ke_rot_final=float(last["rke"]),
        mean_z_final=float(last["zmean"]),
        loadavg_1min=log["loadavg_1min"],
        warnings=log["warnings"],
        extra={
            "version": log["version"],
            "memory_per_proc_mbytes": log["memory_mbytes"],
            "thermo": log["thermo"],
            "neighbor_builds": log["neighbor_builds"],
            "dangerous_builds": log["dangerous_builds"],
        },
    )


def run_grainscale(case: SettleCase, workdir: Path, rnd: int) -> RunResult:
    options = ["--case", str(workdir / "case.json"), "--state", str(workdir / "state.npz")]
    res, rss, load, warnings = run_grainscale_worker(WORKER, workdir, options)
    if res["n_final"] != case.n_particles:
        raise BenchmarkError(f"grainscale lost particles: {res['n_final']} of {case.n_particles}")
    seconds = float(res.pop("run_seconds"))
    return RunResult(
        code="grainscale",
        round=rnd,
        ns_per_particle_step=seconds / (case.steps * case.n_particles) * 1e9,
        run_seconds=seconds,
        maxrss_kib=rss,
        n_final=int(res.pop("n_final")),
        ke_trans_final=float(res.pop("ke_trans_final")),
        ke_rot_final=float(res.pop("ke_rot_final")),
        mean_z_final=float(res.pop("mean_z_final")),
        loadavg_1min=load,
        warnings=warnings,
        extra=res,
    )


# ---------------------------------------------------------------------------------------------
# benchmark driver and report


def bench_size(
    case: SettleCase, codes: list[str], repeats: int, liggghts_exe: str | None, keep: bool
) -> dict[str, Any]:
    def run(code: str, workdir: Path, rnd: int) -> RunResult:
        if code == "liggghts":
            assert liggghts_exe is not None
            return run_liggghts(liggghts_exe, case, workdir, rnd)
        return run_grainscale(case, workdir, rnd)

    runs, stamp = run_rounds(
        "settle", case.n_particles, codes, repeats, keep, lambda w: prepare_inputs(case, w), run
    )
    mine: list[RunResult] = [r for r in runs if isinstance(r, RunResult)]
    return {
        "timestamp": stamp,
        "case": case.to_dict(),
        "repeats": repeats,
        "grainscale_build": grainscale_build() if "grainscale" in codes else None,
        "runs": [dataclasses.asdict(r) | {"ke_final": r.ke_final} for r in mine],
        "summary": summarize(mine),
    }


def summarize(runs: list[RunResult]) -> dict[str, Any]:
    summary: dict[str, Any] = {}
    for code in CODES:
        mine = [r for r in runs if r.code == code]
        if not mine:
            continue
        ns = [r.ns_per_particle_step for r in mine]
        summary[code] = {
            "median_ns_per_particle_step": statistics.median(ns),
            "min_ns_per_particle_step": min(ns),
            "max_ns_per_particle_step": max(ns),
            "peak_rss_mib": max(r.maxrss_kib for r in mine) / 1024.0,
            "ke_final": statistics.median(r.ke_final for r in mine),
            "ke_trans_final": statistics.median(r.ke_trans_final for r in mine),
            "ke_rot_final": statistics.median(r.ke_rot_final for r in mine),
            "mean_z_final": statistics.median(r.mean_z_final for r in mine),
        }
        baseline = [r.extra["rss_before_sim_kib"] for r in mine if "rss_before_sim_kib" in r.extra]
        if baseline:  # grainscale: interpreter, imports, initial state
            summary[code]["rss_before_sim_mib"] = max(baseline) / 1024.0
    ratio = ratio_summary(runs, "ns_per_particle_step")
    if ratio:
        gs_sum, lig_sum = summary["grainscale"], summary["liggghts"]
        summary["ratio_grainscale_over_liggghts"] = ratio
        summary["cross_check"] = {
            "ke_final_rel_diff": gs_sum["ke_final"] / lig_sum["ke_final"] - 1.0,
            "ke_trans_final_rel_diff": gs_sum["ke_trans_final"] / lig_sum["ke_trans_final"] - 1.0,
            "mean_z_final_diff_m": gs_sum["mean_z_final"] - lig_sum["mean_z_final"],
        }
    return summary


def print_table(entry: dict[str, Any]) -> None:
    case, s = entry["case"], entry["summary"]
    print(
        f"\nN = {case['n_particles']}  (box {case['n_side']} x {case['n_side']} sites, "
        f"{case['n_layers']} layers, {case['steps']} steps, {entry['repeats']} round(s))"
    )
    if entry.get("grainscale_build"):
        print(f"  grainscale build: {build_label(entry['grainscale_build'])}")
    print(
        f"  {'code':<11s} {'ns/p-step':>10s} {'min':>8s} {'max':>8s} {'peak RSS':>10s} "
        f"{'KE final [J]':>13s} {'(rot)':>10s} {'mean z [mm]':>12s}"
    )
    for code in CODES:
        if code not in s:
            continue
        c = s[code]
        print(
            f"  {code:<11s} {c['median_ns_per_particle_step']:10.1f} "
            f"{c['min_ns_per_particle_step']:8.1f} {c['max_ns_per_particle_step']:8.1f} "
            f"{c['peak_rss_mib']:7.1f} MiB {c['ke_final']:13.6e} {c['ke_rot_final']:10.3e} "
            f"{c['mean_z_final'] * 1e3:12.5f}"
        )
    if "rss_before_sim_mib" in s.get("grainscale", {}):
        print(
            f"  (grainscale peak RSS includes {s['grainscale']['rss_before_sim_mib']:.1f} MiB of "
            "Python, numpy, grainscale and the initial-state arrays before the Simulation is built)"
        )
    if "ratio_grainscale_over_liggghts" in s:
        r, x = s["ratio_grainscale_over_liggghts"], s["cross_check"]
        print(f"  grainscale/liggghts time ratio: median {r['median']:.3f}  ({per_round(r)})")
        print(
            f"  cross-check: KE rel. diff {x['ke_final_rel_diff']:+.2%} "
            f"(translational {x['ke_trans_final_rel_diff']:+.2%}), "
            f"mean z diff {x['mean_z_final_diff_m'] * 1e6:+.2f} um"
        )
    print_warnings(entry)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 50_000, 200_000])
    parser.add_argument("--steps", type=int, default=4000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", choices=CODES, default=None, help="run only one code")
    parser.add_argument("--seed", type=int, default=SettleCase.seed)
    add_spring_rotation_option(parser, SettleCase.spring_rotation)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT, help="JSON results file")
    parser.add_argument("--keep", action="store_true", help="keep the generated input files")
    args = parser.parse_args(argv)
    if min(args.sizes) < 1 or args.steps < 1 or args.repeats < 1:
        parser.error("--sizes, --steps and --repeats must be positive")

    try:
        codes, liggghts_exe = prepare_codes(args.only, CODES)
        entries: dict[str, dict[str, Any]] = {}
        for n in args.sizes:
            case = SettleCase(
                n_particles=n,
                steps=args.steps,
                seed=args.seed,
                spring_rotation=args.spring_rotation,
            )
            lx, ly, lz = (1e3 * v for v in case.box_hi)
            print(
                f"settle N = {n}: {case.n_side}^2 x {case.n_layers} lattice, "
                f"box {lx:.1f} x {ly:.1f} x {lz:.1f} mm, grainscale springs: "
                f"{case.spring_rotation}",
                flush=True,
            )
            entries[str(n)] = bench_size(case, codes, args.repeats, liggghts_exe, args.keep)
            command = {"sizes": args.sizes, "steps": args.steps, "repeats": args.repeats}
            write_results(args.output, "settle", entries, command)  # partial results survive
    except BenchmarkError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for entry in entries.values():
        print_table(entry)
    print(f"\nraw numbers: {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
