"""Side-by-side 'hopper' benchmark: grainscale against LIGGGHTS 3.8 on one core.

The case (identical physics in both codes, see hopper_case.py for the exact definition): a
conical hopper read from the same binary STL by both codes (3840 triangles: a 48-sided cylinder,
R = 40 mm, on a 30-degree cone to an open outlet of radius 10 mm), N spheres (d = 2 mm,
rho = 2500 kg/m^3) on a seeded jittered lattice inside it, outlet open from the start: the
packing collapses under gravity and discharges; particles are deleted when they cross the box
floor 3 mm below the outlet. Hertz-Mindlin with tangential history (E = 1e7 Pa, nu = 0.3,
e = 0.5, mu = 0.5; the mesh of the particle material), dt = 1e-5 s, skin 0.2 mm; the tangential
spring projected onto the new tangent plane each step as in LIGGGHTS (``--spring-rotation
rescale``: grainscale's default law, which also keeps the spring's length).

The STL and the initial state are generated once per size and fed to both codes (LIGGGHTS:
data file + ``fix mesh/surface`` + ``fix wall/gran ... mesh``; grainscale: .npz +
``Mesh.from_stl`` + ``add_wall``). Each code runs in its own subprocess (peak RSS from
``os.wait4``); the two codes alternate for ``--repeats`` rounds because the machine is noisy.
Cost = wall-clock of the run only (LIGGGHTS' "Loop time"; the sum of grainscale's
``Simulation.run`` calls, made in chunks of ``sample_every`` steps to sample the state like the
LIGGGHTS thermo output) divided by steps x the time-averaged particle count (trapezoid rule over
the samples, the same estimator for both codes). Because the machine is shared, the same ratio
is also given with CPU time (grainscale: process time of the run calls; LIGGGHTS: process CPU
time minus that of a 0-step run of the same input). The table shows medians, the median of the
per-round ratio grainscale/LIGGGHTS, peak RSS and, as a cross-check of the physics, particles
remaining, discharged mass, mean height and kinetic energy at the end and along the run.
Raw numbers go to bench/results/hopper.json (entries of other sizes already there are kept).

Usage: python bench/python/hopper.py [--sizes 50000] [--steps 20000] [--repeats 2]
                                     [--quick] [--only grainscale|liggghts]
                                     [--deletion domain|outlet[:every]]
  --quick: 10k particles, 8000 steps, 1 round (a smoke test of the whole pipeline).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from bench_common import (
    CODES,
    BenchmarkError,
    add_spring_rotation_option,
    build_label,
    failure,
    grainscale_build,
    per_round,
    prepare_codes,
    print_warnings,
    ratio_summary,
    run_grainscale_worker,
    run_liggghts_log,
    run_measured,
    run_rounds,
    single_thread_env,
    write_results,
)
from hopper_case import (
    HopperCase,
    hopper_mesh,
    initial_state,
    liggghts_input,
    mean_count,
    write_binary_stl,
    write_liggghts_data,
)

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]
WORKER = HERE / "hopper_grainscale_worker.py"
DEFAULT_OUTPUT = REPO / "bench" / "results" / "hopper.json"
THERMO_KEYS = ("Step", "atoms", "ke", "rke", "zmean")
BREAKDOWN_RE = re.compile(r"^(Pair|Neigh|Comm|Outpt|Other)\s+time \(%\) = ([0-9.eE+-]+)", re.M)


@dataclass
class RunResult:
    """One run of one code on one case."""

    code: str
    round: int
    ns_per_particle_step: float
    run_seconds: float
    cpu_ns_per_particle_step: float
    cpu_seconds: float
    mean_particles: float
    maxrss_kib: int
    n_final: int
    ke_trans_final: float
    ke_rot_final: float
    mean_z_final: float
    neighbor_builds: int
    loadavg_1min: float
    samples: list[dict[str, float]]
    warnings: list[str] = field(default_factory=list)
    extra: dict[str, Any] = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
# set-up


def prepare_inputs(case: HopperCase, workdir: Path) -> None:
    """Generate the hopper STL and the initial state once and write them for both codes."""
    vertices, triangles = hopper_mesh(case)
    write_binary_stl(workdir / "hopper.stl", vertices, triangles, f"N = {case.n_particles}")
    pos, vel = initial_state(case)
    write_liggghts_data(workdir / "data.hopper", case, pos, vel)
    script = liggghts_input(case, "../data.hopper", "../hopper.stl")
    (workdir / "in.hopper").write_text(script)
    setup_only = script.replace(f"run             {case.steps}", "run             0")
    if setup_only == script:
        raise BenchmarkError("could not derive the 0-step LIGGGHTS input from the run input")
    (workdir / "in.hopper_setup").write_text(setup_only)
    np.savez(workdir / "state.npz", position=pos, velocity=vel)
    (workdir / "case.json").write_text(json.dumps(dataclasses.asdict(case)))


def liggghts_setup_cpu(exe: str, workdir: Path) -> float:
    """CPU seconds of a LIGGGHTS process that sets the case up and runs 0 steps (read_data,
    mesh import, first neighbour lists): subtracted from the CPU time of the real runs."""
    rundir = Path(tempfile.mkdtemp(prefix="liggghts_setup_", dir=workdir))
    try:
        cmd = [exe, "-in", "../in.hopper_setup", "-log", "log.hopper"]
        rc, _, cpu = run_measured(cmd, rundir, single_thread_env())
        if rc != 0:
            raise failure("liggghts (setup only)", rc, rundir, "log.hopper", "stdout.txt")
    finally:
        shutil.rmtree(rundir, ignore_errors=True)
    return cpu


# ---------------------------------------------------------------------------------------------
# running one code


def run_liggghts(
    exe: str, case: HopperCase, workdir: Path, rnd: int, setup_cpu: float
) -> RunResult:
    log = run_liggghts_log(exe, workdir, "in.hopper", "log.hopper")
    cpu = float(log["cpu_seconds"])
    if log["procs"] != 1 or log["steps"] != case.steps:
        raise BenchmarkError(f"unexpected LIGGGHTS loop line: {log}")
    samples = [
        {"Step": r["Step"], "atoms": r["Atoms"], "ke": r["KinEng"], "rke": r["rke"],
         "zmean": r["zmean"]}
        for r in log["thermo"]
    ]  # fmt: skip
    if samples[-1]["Step"] != case.steps:
        raise BenchmarkError(f"LIGGGHTS thermo output ends at step {samples[-1]['Step']}")
    loop = float(log["loop_seconds"])
    n_mean = mean_count([s["Step"] for s in samples], [s["atoms"] for s in samples])
    last = samples[-1]
    return RunResult(
        code="liggghts",
        round=rnd,
        ns_per_particle_step=loop / (case.steps * n_mean) * 1e9,
        run_seconds=loop,
        cpu_ns_per_particle_step=(cpu - setup_cpu) / (case.steps * n_mean) * 1e9,
        cpu_seconds=cpu - setup_cpu,
        mean_particles=n_mean,
        maxrss_kib=log["maxrss_kib"],
        n_final=int(last["atoms"]),
        ke_trans_final=float(last["ke"]),
        ke_rot_final=float(last["rke"]),
        mean_z_final=float(last["zmean"]),
        neighbor_builds=int(log["neighbor_builds"] or -1),
        loadavg_1min=log["loadavg_1min"],
        samples=samples,
        warnings=log["warnings"],
        extra={
            "version": log["version"],
            "memory_per_proc_mbytes": log["memory_mbytes"],
            "dangerous_builds": log["dangerous_builds"],
            "time_breakdown_seconds": {  # Other: fixes (mesh wall, integration, gravity)
                m.group(1).lower(): float(m.group(2)) for m in BREAKDOWN_RE.finditer(log["text"])
            },
        },
    )


def run_grainscale(case: HopperCase, workdir: Path, rnd: int, deletion: str) -> RunResult:
    options = [
        "--case",
        str(workdir / "case.json"),
        "--state",
        str(workdir / "state.npz"),
        "--stl",
        str(workdir / "hopper.stl"),
        "--deletion",
        deletion,
    ]
    res, rss, load, warnings = run_grainscale_worker(WORKER, workdir, options)
    seconds = float(res.pop("run_seconds"))
    cpu = float(res.pop("cpu_seconds"))
    samples = res.pop("samples")
    n_mean = mean_count([s["Step"] for s in samples], [s["atoms"] for s in samples])
    return RunResult(
        code="grainscale",
        round=rnd,
        ns_per_particle_step=seconds / (case.steps * n_mean) * 1e9,
        run_seconds=seconds,
        cpu_ns_per_particle_step=cpu / (case.steps * n_mean) * 1e9,
        cpu_seconds=cpu,
        mean_particles=n_mean,
        maxrss_kib=rss,
        n_final=int(res.pop("n_final")),
        ke_trans_final=float(res.pop("ke_trans_final")),
        ke_rot_final=float(res.pop("ke_rot_final")),
        mean_z_final=float(res.pop("mean_z_final")),
        neighbor_builds=int(res.pop("neighbor_builds")),
        loadavg_1min=load,
        samples=samples,
        warnings=warnings,
        extra=res | {"deletion": deletion},
    )


# ---------------------------------------------------------------------------------------------
# benchmark driver and report


def bench_size(
    case: HopperCase,
    codes: list[str],
    repeats: int,
    liggghts_exe: str | None,
    deletion: str,
    keep: bool,
) -> dict[str, Any]:
    setup_cpu = 0.0

    def prepare(workdir: Path) -> None:
        nonlocal setup_cpu
        prepare_inputs(case, workdir)
        setup_cpu = liggghts_setup_cpu(liggghts_exe, workdir) if liggghts_exe else 0.0

    def run(code: str, workdir: Path, rnd: int) -> RunResult:
        if code == "liggghts":
            assert liggghts_exe is not None
            return run_liggghts(liggghts_exe, case, workdir, rnd, setup_cpu)
        return run_grainscale(case, workdir, rnd, deletion)

    def describe(res: Any) -> str:
        return (
            f" (CPU {res.cpu_ns_per_particle_step:.1f}), {case.n_particles - res.n_final} "
            f"discharged, load {res.loadavg_1min:.1f}"
        )

    runs, stamp = run_rounds(
        "hopper", case.n_particles, codes, repeats, keep, prepare, run, describe
    )
    mine: list[RunResult] = [r for r in runs if isinstance(r, RunResult)]
    return {
        "timestamp": stamp,
        "case": case.to_dict(),
        "repeats": repeats,
        "grainscale_build": grainscale_build() if "grainscale" in codes else None,
        "liggghts_setup_cpu_seconds": setup_cpu,
        "grainscale_deletion": deletion,
        "runs": [dataclasses.asdict(r) for r in mine],
        "summary": summarize(case, mine),
    }


def summarize(case: HopperCase, runs: list[RunResult]) -> dict[str, Any]:
    summary: dict[str, Any] = {}
    m = case.particle_mass
    for code in CODES:
        mine = [r for r in runs if r.code == code]
        if not mine:
            continue
        ns = [r.ns_per_particle_step for r in mine]
        first = mine[0]  # both codes are deterministic on one core: the physics of run 1
        summary[code] = {
            "median_ns_per_particle_step": statistics.median(ns),
            "min_ns_per_particle_step": min(ns),
            "max_ns_per_particle_step": max(ns),
            "median_cpu_ns_per_particle_step": statistics.median(
                r.cpu_ns_per_particle_step for r in mine
            ),
            "median_run_seconds": statistics.median(r.run_seconds for r in mine),
            "mean_particles": first.mean_particles,
            "peak_rss_mib": max(r.maxrss_kib for r in mine) / 1024.0,
            "n_final": first.n_final,
            "discharged": case.n_particles - first.n_final,
            "discharged_mass_kg": (case.n_particles - first.n_final) * m,
            "ke_trans_final": first.ke_trans_final,
            "ke_rot_final": first.ke_rot_final,
            "mean_z_final": first.mean_z_final,
            "neighbor_builds": first.neighbor_builds,
            "deterministic": all(r.samples == first.samples for r in mine),
            "neighbor_fraction": statistics.median(_neighbor_fraction(r) for r in mine),
        }
        baseline = [r.extra["rss_before_sim_kib"] for r in mine if "rss_before_sim_kib" in r.extra]
        if baseline:  # grainscale: interpreter, imports, initial state
            summary[code]["rss_before_sim_mib"] = max(baseline) / 1024.0
    ratio = ratio_summary(runs, "ns_per_particle_step")
    if ratio:
        gs_sum, lig_sum = summary["grainscale"], summary["liggghts"]
        summary["ratio_grainscale_over_liggghts"] = {**ratio, "target": 0.5}
        summary["cpu_time_ratio_grainscale_over_liggghts"] = ratio_summary(
            runs, "cpu_ns_per_particle_step"
        )
        gs_first = next(r for r in runs if r.code == "grainscale")
        lig_first = next(r for r in runs if r.code == "liggghts")
        summary["cross_check"] = {
            "discharged_rel_diff": _rel(gs_sum["discharged"], lig_sum["discharged"]),
            "mean_particles_rel_diff": _rel(gs_sum["mean_particles"], lig_sum["mean_particles"]),
            "mean_z_final_diff_m": gs_sum["mean_z_final"] - lig_sum["mean_z_final"],
            "ke_trans_final_rel_diff": _rel(gs_sum["ke_trans_final"], lig_sum["ke_trans_final"]),
            "ke_rot_final_rel_diff": _rel(gs_sum["ke_rot_final"], lig_sum["ke_rot_final"]),
            "history": compare_histories(gs_first.samples, lig_first.samples),
        }
    return summary


def _neighbor_fraction(r: RunResult) -> float:
    """Share of the run time spent building neighbour lists (grainscale: whole rebuilds with
    sorting and wall lists; LIGGGHTS: 'Neigh time', the mesh neighbour lists are in 'Other')."""
    if r.code == "grainscale":
        seconds = float(r.extra.get("rebuild_seconds", float("nan")))
    else:
        seconds = float(r.extra.get("time_breakdown_seconds", {}).get("neigh", float("nan")))
    return seconds / r.run_seconds


def _rel(a: float, b: float) -> float:
    return a / b - 1.0 if b else float("nan")


def compare_histories(
    gs_samples: list[dict[str, float]], lig_samples: list[dict[str, float]]
) -> list[dict[str, float]]:
    """Side-by-side samples at the steps both codes recorded."""
    lig = {int(s["Step"]): s for s in lig_samples}
    rows = []
    for g in gs_samples:
        step = int(g["Step"])
        if step not in lig:
            continue
        row = {"Step": step}
        for key in THERMO_KEYS[1:]:
            row[f"grainscale_{key}"] = g[key]
            row[f"liggghts_{key}"] = lig[step][key]
        rows.append(row)
    return rows


def print_table(entry: dict[str, Any]) -> None:
    case, s = entry["case"], entry["summary"]
    print(
        f"\nN = {case['n_particles']}  ({case['n_triangles']} triangles, {case['steps']} steps, "
        f"{entry['repeats']} round(s), grainscale deletion: {entry['grainscale_deletion']})"
    )
    if entry.get("grainscale_build"):
        print(f"  grainscale build: {build_label(entry['grainscale_build'])}")
    print(
        f"  {'code':<11s} {'ns/p-step':>10s} {'min':>8s} {'max':>8s} {'peak RSS':>10s} "
        f"{'mean N':>9s} {'left':>7s} {'disch. g':>9s} {'mean z mm':>10s} {'KE J':>10s} "
        f"{'rot KE J':>10s} {'nbuilds':>8s}"
    )
    for code in CODES:
        if code not in s:
            continue
        c = s[code]
        print(
            f"  {code:<11s} {c['median_ns_per_particle_step']:10.1f} "
            f"{c['min_ns_per_particle_step']:8.1f} {c['max_ns_per_particle_step']:8.1f} "
            f"{c['peak_rss_mib']:6.1f} MiB {c['mean_particles']:9.1f} {c['n_final']:7d} "
            f"{c['discharged_mass_kg'] * 1e3:9.3f} {c['mean_z_final'] * 1e3:10.4f} "
            f"{c['ke_trans_final']:10.4e} {c['ke_rot_final']:10.3e} {c['neighbor_builds']:8d}"
        )
    shares = ", ".join(f"{code} {s[code]['neighbor_fraction']:.0%}" for code in CODES if code in s)
    print(f"  share of run time in neighbour-list builds: {shares}")
    if "rss_before_sim_mib" in s.get("grainscale", {}):
        print(
            f"  (grainscale peak RSS includes {s['grainscale']['rss_before_sim_mib']:.1f} MiB of "
            "Python, numpy, grainscale and the initial-state arrays before the Simulation is built)"
        )
    if "ratio_grainscale_over_liggghts" in s:
        r, x = s["ratio_grainscale_over_liggghts"], s["cross_check"]
        print(
            f"  grainscale/liggghts time ratio: median {r['median']:.3f}  ({per_round(r)}); "
            f"target <= {r['target']}"
        )
        c = s["cpu_time_ratio_grainscale_over_liggghts"]
        print(
            f"  same with CPU time instead of wall clock: median {c['median']:.3f}  "
            f"({per_round(c)}); "
            f"CPU ns/p-step gs {s['grainscale']['median_cpu_ns_per_particle_step']:.1f}, "
            f"lig {s['liggghts']['median_cpu_ns_per_particle_step']:.1f}"
        )
        print(
            f"  cross-check: discharged {x['discharged_rel_diff']:+.2%}, "
            f"mean N {x['mean_particles_rel_diff']:+.3%}, "
            f"mean z diff {x['mean_z_final_diff_m'] * 1e6:+.1f} um, "
            f"KE {x['ke_trans_final_rel_diff']:+.2%}, rot KE {x['ke_rot_final_rel_diff']:+.2%}"
        )
        hist = x["history"]
        picks = {hist[round(f * (len(hist) - 1))]["Step"] for f in (0, 0.25, 0.5, 0.75, 1)}
        print(f"  {'step':>8s} {'left gs/lig':>15s} {'mean z mm gs/lig':>21s} {'KE J gs/lig':>23s}")
        for row in hist:
            if row["Step"] in picks:
                print(
                    f"  {row['Step']:8d} "
                    f"{row['grainscale_atoms']:7.0f}/{row['liggghts_atoms']:<7.0f} "
                    f"{row['grainscale_zmean'] * 1e3:10.4f}/{row['liggghts_zmean'] * 1e3:<10.4f} "
                    f"{row['grainscale_ke']:11.4e}/{row['liggghts_ke']:<11.4e}"
                )
    for code in CODES:
        if code in s and not s[code]["deterministic"]:
            print(f"  note: {code} runs of this size did not reproduce each other exactly")
    builds = {
        r["extra"].get("core_module_mtime") for r in entry["runs"] if r["code"] == "grainscale"
    }
    if len(builds) > 1:
        print(f"  note: grainscale was reinstalled between rounds ({len(builds)} different builds)")
    print_warnings(entry)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", type=int, nargs="+", default=None, help="default: 50000")
    parser.add_argument("--steps", type=int, default=None, help="default: 20000")
    parser.add_argument("--repeats", type=int, default=None, help="default: 2")
    parser.add_argument("--quick", action="store_true", help="10k particles, 8000 steps, 1 round")
    parser.add_argument("--only", choices=CODES, default=None, help="run only one code")
    parser.add_argument(
        "--deletion",
        default="domain",
        help="how grainscale deletes discharged particles: 'domain' (lost at the box floor at "
        "the next list rebuild, as LIGGGHTS) or 'outlet[:every]' (a gs.insert.Outlet slab at "
        "the floor, checked every 'every' steps)",
    )
    parser.add_argument("--seed", type=int, default=HopperCase.seed)
    add_spring_rotation_option(parser, HopperCase.spring_rotation)
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT, help="JSON results file")
    parser.add_argument("--keep", action="store_true", help="keep the generated input files")
    args = parser.parse_args(argv)
    quick = args.quick
    args.sizes = args.sizes or ([10_000] if quick else [50_000])
    args.steps = args.steps or (8000 if quick else 20_000)
    args.repeats = args.repeats or (1 if quick else 2)
    if min(args.sizes) < 1 or args.steps < 1 or args.repeats < 1:
        parser.error("--sizes, --steps and --repeats must be positive")
    if not (args.deletion == "domain" or args.deletion.startswith("outlet")):
        parser.error(f"--deletion must be 'domain' or 'outlet[:every]', got {args.deletion!r}")

    try:
        codes, liggghts_exe = prepare_codes(args.only, CODES)
        entries: dict[str, dict[str, Any]] = {}
        for n in args.sizes:
            case = HopperCase(
                n_particles=n,
                steps=args.steps,
                seed=args.seed,
                spring_rotation=args.spring_rotation,
            )
            print(
                f"hopper N = {n}: {case.n_triangles} triangles, R = {case.hopper_radius * 1e3:g} "
                f"mm, outlet r = {case.outlet_radius * 1e3:g} mm, {case.steps} steps, "
                f"grainscale springs: {case.spring_rotation}",
                flush=True,
            )
            try:
                entry = bench_size(
                    case, codes, args.repeats, liggghts_exe, args.deletion, args.keep
                )
            except ValueError as exc:  # e.g. more particles than the hopper holds
                raise BenchmarkError(str(exc)) from exc
            entries[str(n)] = entry
            command = {
                "sizes": args.sizes,
                "steps": args.steps,
                "repeats": args.repeats,
                "quick": args.quick,
                "deletion": args.deletion,
            }
            write_results(args.output, "hopper", entries, command)  # partial results survive
    except BenchmarkError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except subprocess.CalledProcessError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    for entry in entries.values():
        print_table(entry)
    print(f"\nraw numbers: {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
