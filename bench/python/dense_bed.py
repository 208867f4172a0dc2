"""Side-by-side 'dense bed' benchmark: grainscale against LIGGGHTS 3.8 on one core.

The case is the 'settle' case of settle.py (settle_case.py: N spheres of d = 2 mm on a jittered
lattice in a closed box of six walls, Hertz-Mindlin with tangential history, dt = 1e-5 s, the
spring projected as LIGGGHTS does), first settled for ``--settle-time`` (0.15 s: 15 000 steps)
untimed, then run for ``--steps`` (2000) timed steps: the cost of a dense, long-lasting bed,
where every particle has several contacts, rather than of the falling lattice.

Both codes run the same two phases in one process each, in their own temporary directory
(peak RSS from ``os.wait4``), alternating for ``--repeats`` rounds. LIGGGHTS runs two ``run``
commands and its second "Loop time" is the timed part; grainscale's worker
(settle_grainscale_worker.py ``--untimed-steps``) calls ``Simulation.run`` twice and times the
second. Reported per size: the median time per particle-step of the timed part, the median of
the per-round ratio grainscale/LIGGGHTS, the peak RSS of each process (the whole run, settling
included), and the state at the start and at the end of the timed part: contacts per particle
(particle pairs with centre distance <= d, divided by N: the half-list count; the coordination
number is twice that), counted by this script with the same function from the positions both
codes write (LIGGGHTS: write_dump between and after the runs, outside the timed loop;
grainscale: .npy files), total kinetic energy and mean height, with the relative differences
between the codes. The bed is chaotic: the two codes agree on these observables statistically,
not to the last digit (compare with the spread between rounds of one code).

Raw numbers go to bench/results/dense_bed.json (entries of other sizes already there are
kept). The script prints which grainscale build it measured (native or portable,
bench/README.md) and records it; LIGGGHTS is Debian's generic x86-64 build, installed with
apt-get if missing. Counting the contacts needs scipy (a dev dependency).

Usage: python bench/python/dense_bed.py [--sizes 10000 50000 200000] [--repeats 3]
           [--settle-time 0.15] [--steps 2000] [--quick] [--only grainscale|liggghts]
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
from dataclasses import dataclass
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
from settle import WORKER, RunResult, prepare_inputs
from settle_case import SettleCase

REPO = Path(__file__).resolve().parents[2]
DEFAULT_OUTPUT = REPO / "bench" / "results" / "dense_bed.json"
DEFAULTS = {"sizes": [10_000, 50_000, 200_000], "settle_time": 0.15, "steps": 2000, "repeats": 3}
QUICK = {"sizes": [2000], "settle_time": 0.05, "steps": 500, "repeats": 1}
# The observables compared at the start (s) and at the end (e) of the timed part.
OBSERVABLES = ("contacts_per_particle", "ke", "mean_z")


@dataclass
class DenseRun(RunResult):
    """One run: settle.py's fields (of the end of the timed part) and the dense-bed ones."""

    contacts_per_particle_start: float = 0.0
    contacts_per_particle_end: float = 0.0
    ke_start: float = 0.0
    mean_z_start: float = 0.0

    @property
    def contacts_per_particle_final(self) -> float:
        return self.contacts_per_particle_end


def pair_contacts_per_particle(position: np.ndarray, diameter: float) -> float:
    """Particle pairs with centre distance <= diameter (monodisperse), divided by N."""
    from scipy.spatial import cKDTree  # only here: the grainscale worker never imports it

    pairs = cKDTree(position).query_pairs(diameter, output_type="ndarray")
    return len(pairs) / len(position)


def read_dump(path: Path) -> np.ndarray:
    """Positions (N, 3) of a LIGGGHTS custom dump with the columns id x y z."""
    return np.loadtxt(path, skiprows=9, usecols=(1, 2, 3), ndmin=2)


def liggghts_runs(settle_steps: int, steps: int) -> str:
    """The end of the LIGGGHTS input: the untimed and the timed run, positions after each."""
    dump = "write_dump       all custom ../liggghts_{}.dump id x y z"
    return "\n".join(
        [f"run             {settle_steps}", dump.format("start"), f"run             {steps}",
         dump.format("end")]
    )  # fmt: skip


def run_liggghts(
    exe: str, case: SettleCase, settle_steps: int, workdir: Path, rnd: int
) -> DenseRun:
    log = run_liggghts_log(exe, workdir, "in.settle", "log.dense")
    if [s for _, s in log["loops"]] != [settle_steps, case.steps] or log["procs"] != 1:
        raise BenchmarkError(f"unexpected LIGGGHTS loop lines: {log['loops']}")
    start, last = log["thermo"][0], log["thermo"][-1]  # the thermo block of the timed run
    n_final = int(last["Atoms"])
    if n_final != case.n_particles:
        raise BenchmarkError(f"LIGGGHTS lost atoms: {n_final} of {case.n_particles} left")
    loop = log["loops"][-1][0]
    d = case.diameter
    return DenseRun(
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
            "untimed_seconds": log["loops"][0][0],
            "memory_per_proc_mbytes": log["memory_mbytes"],
            "thermo": log["thermo"],
            "neighbor_builds": log["neighbor_builds"],
            "dangerous_builds": log["dangerous_builds"],
        },
        contacts_per_particle_start=pair_contacts_per_particle(
            read_dump(workdir / "liggghts_start.dump"), d
        ),
        contacts_per_particle_end=pair_contacts_per_particle(
            read_dump(workdir / "liggghts_end.dump"), d
        ),
        ke_start=float(start["KinEng"]) + float(start["rke"]),
        mean_z_start=float(start["zmean"]),
    )


def run_grainscale(case: SettleCase, settle_steps: int, workdir: Path, rnd: int) -> DenseRun:
    prefix = workdir / "grainscale"
    options = ["--case", str(workdir / "case.json"), "--state", str(workdir / "state.npz")]
    options += ["--untimed-steps", str(settle_steps), "--positions", str(prefix)]
    res, rss, load, warnings = run_grainscale_worker(WORKER, workdir, options)
    if res["n_final"] != case.n_particles:
        raise BenchmarkError(f"grainscale lost particles: {res['n_final']} of {case.n_particles}")
    seconds = float(res.pop("run_seconds"))
    d = case.diameter
    return DenseRun(
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
        contacts_per_particle_start=pair_contacts_per_particle(np.load(f"{prefix}_start.npy"), d),
        contacts_per_particle_end=pair_contacts_per_particle(np.load(f"{prefix}_end.npy"), d),
        ke_start=float(res["ke_start"]),
        mean_z_start=float(res["mean_z_start"]),
    )


# ---------------------------------------------------------------------------------------------
# driver and report


def bench_size(
    case: SettleCase,
    settle_steps: int,
    codes: list[str],
    repeats: int,
    liggghts_exe: str | None,
    keep: bool,
) -> dict[str, Any]:
    def run(code: str, workdir: Path, rnd: int) -> DenseRun:
        if code == "liggghts":
            assert liggghts_exe is not None
            return run_liggghts(liggghts_exe, case, settle_steps, workdir, rnd)
        return run_grainscale(case, settle_steps, workdir, rnd)

    def prepare(workdir: Path) -> None:
        prepare_inputs(case, workdir, liggghts_runs(settle_steps, case.steps))

    def describe(r: Any) -> str:
        return f", {r.contacts_per_particle_start:.2f} contacts/particle at the start"

    runs, stamp = run_rounds(
        "dense", case.n_particles, codes, repeats, keep, prepare, run, describe
    )
    mine = [r for r in runs if isinstance(r, DenseRun)]
    return {
        "timestamp": stamp,
        "case": case.to_dict() | {"settle_steps": settle_steps},
        "repeats": repeats,
        "grainscale_build": grainscale_build() if "grainscale" in codes else None,
        "runs": [dataclasses.asdict(r) | {"ke_final": r.ke_final} for r in mine],
        "summary": summarize(mine),
    }


def summarize(runs: list[DenseRun]) -> dict[str, Any]:
    summary: dict[str, Any] = {}
    for code in CODES:
        mine = [r for r in runs if r.code == code]
        if not mine:
            continue
        ns = [r.ns_per_particle_step for r in mine]
        s: dict[str, Any] = {
            "median_ns_per_particle_step": statistics.median(ns),
            "min_ns_per_particle_step": min(ns),
            "max_ns_per_particle_step": max(ns),
            "peak_rss_mib": max(r.maxrss_kib for r in mine) / 1024.0,
        }
        for name in OBSERVABLES:
            for when, attr in (("start", f"{name}_start"), ("end", f"{name}_final")):
                s[f"{name}_{when}"] = statistics.median(getattr(r, attr) for r in mine)
        summary[code] = s
    ratio = ratio_summary(runs, "ns_per_particle_step")
    if ratio:
        gs_sum, lig_sum = summary["grainscale"], summary["liggghts"]
        summary["ratio_grainscale_over_liggghts"] = ratio
        summary["peak_rss_ratio"] = gs_sum["peak_rss_mib"] / lig_sum["peak_rss_mib"]
        summary["cross_check_rel_diff"] = {
            f"{name}_{when}": gs_sum[f"{name}_{when}"] / lig_sum[f"{name}_{when}"] - 1.0
            for name in OBSERVABLES
            for when in ("start", "end")
        }
    return summary


def print_table(entry: dict[str, Any]) -> None:
    case, s = entry["case"], entry["summary"]
    print(
        f"\nN = {case['n_particles']}  ({case['settle_steps']} untimed settling steps, then "
        f"{case['steps']} timed steps, {entry['repeats']} round(s))"
    )
    if entry.get("grainscale_build"):
        print(f"  grainscale build: {build_label(entry['grainscale_build'])}")
    print(
        f"  {'code':<11s} {'ns/p-step':>10s} {'min':>8s} {'max':>8s} {'peak RSS':>10s} "
        f"{'c/p start':>9s} {'c/p end':>8s} {'KE end [J]':>11s} {'mean z end [mm]':>15s}"
    )
    for code in CODES:
        if code not in s:
            continue
        c = s[code]
        print(
            f"  {code:<11s} {c['median_ns_per_particle_step']:10.1f} "
            f"{c['min_ns_per_particle_step']:8.1f} {c['max_ns_per_particle_step']:8.1f} "
            f"{c['peak_rss_mib']:7.1f} MiB {c['contacts_per_particle_start']:9.3f} "
            f"{c['contacts_per_particle_end']:8.3f} {c['ke_end']:11.4e} "
            f"{c['mean_z_end'] * 1e3:15.5f}"
        )
    print("  (c/p: particle contacts per particle, d_ij <= d, over N; coordination = 2 c/p)")
    if "ratio_grainscale_over_liggghts" in s:
        r, x = s["ratio_grainscale_over_liggghts"], s["cross_check_rel_diff"]
        print(f"  grainscale/liggghts time ratio: median {r['median']:.3f}  ({per_round(r)})")
        print(f"  grainscale/liggghts peak RSS ratio: {s['peak_rss_ratio']:.3f}")
        for when in ("start", "end"):
            print(
                f"  cross-check at the {when:<5s} of the timed part (rel. diff): contacts/particle "
                f"{x[f'contacts_per_particle_{when}']:+.2%}, KE {x[f'ke_{when}']:+.1%}, "
                f"mean z {x[f'mean_z_{when}']:+.3%}"
            )
    print_warnings(entry)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", type=int, nargs="+", help="default 10000 50000 200000")
    parser.add_argument("--settle-time", type=float, help="untimed settling [s], default 0.15")
    parser.add_argument("--steps", type=int, help="timed steps, default 2000")
    parser.add_argument("--repeats", type=int, help="alternating rounds, default 3")
    parser.add_argument(
        "--quick",
        action="store_true",
        help="a validation run: defaults --sizes 2000 --settle-time 0.05 --steps 500 "
        "--repeats 1 (options given explicitly still apply)",
    )
    parser.add_argument("--only", choices=CODES, default=None, help="run only one code")
    parser.add_argument("--seed", type=int, default=SettleCase.seed)
    add_spring_rotation_option(parser, SettleCase.spring_rotation)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT, help="JSON results file")
    parser.add_argument("--keep", action="store_true", help="keep the generated input files")
    args = parser.parse_args(argv)
    for key, value in (QUICK if args.quick else DEFAULTS).items():
        if getattr(args, key) is None:
            setattr(args, key, value)
    if min(args.sizes) < 1 or args.steps < 1 or args.repeats < 1 or not args.settle_time > 0:
        parser.error("--sizes, --settle-time, --steps and --repeats must be positive")

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
            settle_steps = round(args.settle_time / case.time_step)
            print(
                f"dense bed N = {n}: {case.n_side}^2 x {case.n_layers} lattice, settled for "
                f"{settle_steps} steps untimed, then {case.steps} timed steps; grainscale "
                f"springs: {case.spring_rotation}",
                flush=True,
            )
            entries[str(n)] = bench_size(
                case, settle_steps, codes, args.repeats, liggghts_exe, args.keep
            )
            command = {
                "sizes": args.sizes,
                "settle_time": args.settle_time,
                "steps": args.steps,
                "repeats": args.repeats,
            }
            write_results(args.output, "dense_bed", entries, command)  # partial results survive
    except BenchmarkError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for entry in entries.values():
        print_table(entry)
    print(f"\nraw numbers: {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
