"""Flat-bottomed silo discharge and the Beverloo correlation (validation/CASES.md D1).

Run it with ``python -m studies.silo_discharge.silo_discharge --output out/silo``. For each orifice
diameter D0 (and each seed) a cylindrical silo with a flat, triangulated floor (an annulus mesh
with a central circular orifice) is filled by pouring spheres through a disc face at the top
while a shutter closes the orifice; the bed settles, the shutter drops away, the grains flow out
into an outlet region below the floor where they are deleted and counted. By default the head
is constant (the usual DEM silo): every 0.02 s as many particles as the outlet removed are
packed into a slab just above the initial free surface and thrown down, so a modest bed flows
steadily and W is the slope of the discharged mass over a steady window after a transient.
``--draining`` measures instead between 20 % and 70 % of a draining inventory. The rates for
several orifices are fitted with Beverloo's law (Beverloo, Leniger & van de Velde 1961)

    W = C rho_b sqrt(g) (D0 - k d)^n,   n free, and n = 2.5,

with rho_b the bulk density of the settled bed (solid fraction in its core, 3 d away from the
wall, the floor and the surface), measured in every run. Material (CASES D1): spheres
d = 4 mm +/- 5 % (uniform), rho_p = 2500 kg/m^3, nu = 0.3, restitution 0.5, friction 0.5
(particle-particle and particle-wall), EPSD rolling resistance mu_r = 0.05, eta_r = 0.3; time
step 0.2 x the Rayleigh time of the smallest sphere; E = 1e7 Pa (reduced from CASES' 1e8 Pa:
D0 = 24 mm in a 60 mm silo gave W = 0.0924 kg/s with 1e8 Pa and 0.0929 kg/s with 1e7 Pa).

Each silo is the smallest with D_s >= 2.5 D0 (Beverloo et al. 1961) and D_s - D0 >= 20 d.
Nedderman et al. (1982, Chem. Eng. Sci. 37:1597) put the silo-independence limit near 30 d;
at D0 = 24 mm (constant head, 60 mm bed, one seed) this code gave W = 0.0926, 0.0913 and
0.0970 kg/s in silos 60, 104 and 144 mm wide (D_s - D0 = 9, 20 and 30 d), differences within
the 4-7 % scatter between runs, so 20 d is used. The bed is max(0.5 D_s, 2 D0) deep.
The default study, D0 = 24, 32, 40, 52 and 64 mm (D0/d = 6-16), two seeds, 7500-44000
particles per silo, is about 6e9 particle-steps (50 minutes on two shared cores).
``--quick``: one 60 mm silo with a 50 mm bed, D0 = 24 and 28 mm, about a minute on two
cores. The runs go to worker processes (``--jobs``, default: one per CPU); ``--first-seed``
adds seeds to a study; ``--reanalyse`` fits, plots and reports a finished study again without
simulating.

Written to the output directory:
    discharge.png             rate history per orifice (draining: discharged fraction and the
                              20-70 % fit), W vs D0 with the Beverloo fits, the linearised form
                              (W / (C rho_b sqrt g))^(2/5) vs D0
    report.md                 set-up, measured rates, fits and what the full study would be
    results.json              every number of the report (per run and fitted)
    history_D<mm>_s<seed>.csv time after opening (s), discharged mass (kg), count
    vtk/D<mm>_s<seed>/        particle snapshots + floor mesh (.pvd) and silo_cylinder.vtp,
                              with --vtk-every only

Lengths on the command line are in mm (orifices, silo diameter, fill height).

This module runs a study (all orifices and seeds) and holds the command line; the parts are
``silo_case`` (the silos and their walls), ``silo_run`` (one silo poured, settled and
discharged), ``silo_beverloo`` (the correlation and its fits) and ``silo_report`` (the study's
results, plot, report and JSON).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from studies.silo_discharge.silo_beverloo import exponent_interval, fit_all
from studies.silo_discharge.silo_case import (
    DEFAULT_ORIFICES,
    DEFAULT_ORIFICES_MM,
    QUICK_CASE,
    QUICK_ORIFICES_MM,
    SiloCase,
)
from studies.silo_discharge.silo_report import StudyResult, plot_study, report_markdown, write_json
from studies.silo_discharge.silo_run import DischargeResult, print_flush, rate_of, run_many


def _aggregate(orifices: list[float], runs: list[DischargeResult]):
    mean, std, rho = [], [], []
    for d0 in orifices:
        mine = [r for r in runs if r.orifice == d0]
        w = [r.rate for r in mine if not r.clogged and math.isfinite(r.rate)]
        mean.append(float(np.mean(w)) if w else math.nan)
        std.append(float(np.std(w, ddof=1)) if len(w) > 1 else math.nan)
        rho.append(float(np.mean([r.core_bulk_density for r in mine])))
    return mean, std, rho


def seed_scatter(orifices: Sequence[float], runs: Sequence[DischargeResult]) -> float:
    """Pooled standard deviation of log W between seeds of the same orifice (NaN without
    repeated seeds): the relative scatter of one run's rate."""
    ss, dof = 0.0, 0
    for d0 in orifices:
        lw = np.log([r.rate for r in runs if r.orifice == d0 and r.rate > 0 and not r.clogged])
        if len(lw) > 1:
            ss += float(np.sum((lw - lw.mean()) ** 2))
            dof += len(lw) - 1
    return math.sqrt(ss / dof) if dof else math.nan


def run_study(
    output: str | Path,
    case: SiloCase | None = None,
    orifices: Sequence[float] = DEFAULT_ORIFICES,
    seeds: Sequence[int] = (1,),
    jobs: int | None = None,
    verbose: bool = True,
) -> StudyResult:
    """Run every (orifice, seed), fit Beverloo, write the plot, report and data.

    Args:
        output: output directory.
        case: the silos (default ``SiloCase()``).
        orifices: D0 values (m).
        seeds: stream seeds; each gives an independent pour.
        jobs: worker processes (default: the number of CPUs, at most the number of runs).
        verbose: print progress lines and the report.
    """
    case = case if case is not None else SiloCase()
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    say = print_flush if verbose else (lambda _s: None)
    orifices = sorted(float(v) for v in orifices)
    seeds = [int(s) for s in seeds]
    if not orifices or not seeds:
        raise ValueError("run_study needs at least one orifice and one seed")
    tasks = []
    for d0 in reversed(orifices):  # the largest silo first: the longest runs start first
        for seed in seeds:
            vtk = str(out / "vtk" / f"D{d0 * 1e3:g}_s{seed}") if case.vtk_every else None
            tasks.append((case, d0, seed, vtk))
    jobs = jobs if jobs is not None else min(len(tasks), os.cpu_count() or 1)
    if jobs < 1:
        raise ValueError(f"run_study.jobs must be at least 1, got {jobs}")
    counts = [case.target_mass(d0) / case.mean_particle_mass for d0 in orifices]
    lo, hi = min(counts), max(counts)
    count = f"{lo:.0f}" if hi - lo < 1 else f"{lo:.0f}-{hi:.0f}"
    say(
        f"grainscale silo discharge (CASES D1): {case.describe()}, "
        f"~{count} particles per silo "
        f"(d = {case.diameter * 1e3:g} mm +/- {case.diameter_spread:.0%}), "
        f"D0 = {', '.join(f'{v * 1e3:g}' for v in orifices)} mm, seeds {seeds}; "
        f"{len(tasks)} runs on {jobs} process(es); output in {out}"
    )
    t0 = time.perf_counter()
    runs = run_many(tasks, jobs, verbose)
    wall = time.perf_counter() - t0
    for r in runs:
        save_history(out / f"history_D{r.orifice * 1e3:g}_s{r.seed}.csv", r)
    return _finish(case, orifices, seeds, runs, wall, out, jobs, verbose)


def _finish(
    case: SiloCase,
    orifices: list[float],
    seeds: list[int],
    runs: list[DischargeResult],
    wall: float,
    out: Path,
    jobs: int,
    verbose: bool,
) -> StudyResult:
    """Fit, plot and report the runs of a study."""
    mean, std, rho = _aggregate(orifices, runs)
    fits = fit_all(orifices, mean, rho, case.diameter)
    scatter = seed_scatter(orifices, runs)
    n_range = None
    if fits[1] is not None and math.isfinite(scatter):
        valid = [(a, w, b) for a, w, b in zip(orifices, mean, rho, strict=True) if w > 0]
        d0, w, b = (list(x) for x in zip(*valid, strict=True))
        n_range = exponent_interval(d0, w, case.diameter, b, scatter / math.sqrt(len(seeds)))
    result = StudyResult(
        case=case,
        orifices=orifices,
        seeds=seeds,
        runs=runs,
        rate_mean=mean,
        rate_std=std,
        bulk_density=rho,
        fit=fits[0],
        fit_free=fits[1],
        fit_exponent=fits[2],
        scatter=scatter,
        exponent_range=n_range,
        wall_clock=wall,
        output=out,
        plot=out / "discharge.png",
        report=out / "report.md",
        jobs=jobs,
    )
    plot_study(result.plot, result)
    result.report_text = report_markdown(result)
    result.report.write_text(result.report_text)
    write_json(out / "results.json", result)
    if verbose:
        print_flush("")
        print_flush(result.report_text)
    return result


def load_run(case: SiloCase, summary: dict[str, Any], history: Path) -> DischargeResult:
    """A run of ``case`` from its results.json summary and its outlet history (CSV), with the
    rate measured again from the history."""
    h = np.loadtxt(history, delimiter=",", skiprows=1, ndmin=2)
    names = {f.name for f in dataclasses.fields(DischargeResult)}
    values: dict[str, Any] = {
        k: math.nan if v is None else v for k, v in summary.items() if k in names
    }
    t, m = h[:, 0], h[:, 1]
    w, w1, w2, r2 = rate_of(case, values["orifice"], t, m, float(values["inventory"]))
    values.update(time=t, mass=m, count=h[:, 2].astype(np.int64))
    values.update(rate=w, rate_first_half=w1, rate_second_half=w2, r_squared=r2)
    return DischargeResult(**values)


def save_history(path: Path, run: DischargeResult) -> None:
    """Write the outlet history of a run (the CSV that load_run reads)."""
    np.savetxt(
        path,
        np.column_stack([run.time, run.mass, run.count]),
        delimiter=",",
        header="time_after_opening_s,discharged_mass_kg,discharged_count",
        comments="",
        fmt=["%.6f", "%.6e", "%d"],
    )


def reanalyse(output: str | Path, verbose: bool = True) -> StudyResult:
    """Fit, plot and report again a finished study from its results.json and outlet histories
    (no simulation; e.g. after a change of the analysis)."""
    out = Path(output)
    data = json.loads((out / "results.json").read_text())
    case = SiloCase(**data["case"])
    runs = [
        load_run(
            case, summary, out / f"history_D{summary['orifice'] * 1e3:g}_s{summary['seed']}.csv"
        )
        for summary in data["runs"]
    ]
    runs.sort(key=lambda r: (r.orifice, r.seed))
    return _finish(
        case,
        sorted({r.orifice for r in runs}),
        sorted({r.seed for r in runs}),
        runs,
        float(data.get("wall_clock_s") or math.nan),
        out,
        int(data.get("jobs") or 1),
        verbose,
    )


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m studies.silo_discharge.silo_discharge",
        description="Flat-bottomed silo discharge vs Beverloo (validation/CASES.md D1, "
        "reduced). Lengths in mm.",
    )
    parser.add_argument(
        "--output", default="out/silo", help="output directory (default: %(default)s)"
    )
    parser.add_argument(
        "--orifices",
        type=float,
        nargs="+",
        default=None,
        metavar="MM",
        help=f"orifice diameters in mm (default {' '.join(f'{v:g}' for v in DEFAULT_ORIFICES_MM)}"
        f"; {' '.join(f'{v:g}' for v in QUICK_ORIFICES_MM)} with --quick)",
    )
    fill = parser.add_mutually_exclusive_group()
    fill.add_argument(
        "--fill-height",
        type=float,
        default=None,
        metavar="MM",
        help="settled bed height in mm for every orifice (default: --height-ratio x D_s)",
    )
    fill.add_argument(
        "--particles", type=int, default=None, help="number of particles poured (every orifice)"
    )
    parser.add_argument(
        "--height-ratio",
        type=float,
        default=None,
        help=f"bed height / silo diameter (default {SiloCase.height_ratio:g})",
    )
    parser.add_argument(
        "--head-ratio",
        type=float,
        default=None,
        help=f"least bed height / D0 (default {SiloCase.head_ratio:g})",
    )
    parser.add_argument(
        "--silo-diameter",
        type=float,
        default=None,
        metavar="MM",
        help="one silo diameter in mm for every orifice (default: max(--silo-ratio x D0, "
        "D0 + --wall-gap x d))",
    )
    parser.add_argument(
        "--silo-ratio",
        type=float,
        default=None,
        help=f"least silo diameter / D0 (default {SiloCase.silo_ratio:g})",
    )
    parser.add_argument(
        "--wall-gap",
        type=float,
        default=None,
        help=f"least (silo diameter - D0) / d (default {SiloCase.wall_gap:g})",
    )
    parser.add_argument(
        "--draining",
        action="store_true",
        help="no re-pouring: measure W between 20 %% and 70 %% of a draining inventory",
    )
    parser.add_argument(
        "--measure-time",
        type=float,
        default=None,
        metavar="S",
        help=f"least length of the steady window, constant head (default "
        f"{SiloCase.measure_time:g} s)",
    )
    material = parser.add_argument_group("material (defaults: the study's)")
    material.add_argument(
        "--youngs-modulus",
        type=float,
        default=None,
        metavar="PA",
        help=f"Young's modulus (default {SiloCase.youngs_modulus:g} Pa)",
    )
    material.add_argument(
        "--friction",
        type=float,
        default=None,
        help=f"sliding friction, particles and walls (default {SiloCase.friction:g})",
    )
    material.add_argument(
        "--rolling-friction",
        type=float,
        default=None,
        help=f"EPSD rolling friction (default {SiloCase.rolling_friction:g})",
    )
    material.add_argument(
        "--time-step",
        type=float,
        default=None,
        metavar="S",
        help="time step (default 0.2 x the Rayleigh time of the smallest sphere)",
    )
    parser.add_argument(
        "--seeds",
        type=int,
        default=None,
        help="number of seeds per orifice (default 2; 1 with --quick)",
    )
    parser.add_argument(
        "--first-seed",
        type=int,
        default=1,
        help="seeds are first-seed, first-seed + 1, ... (default 1; to add seeds to a study)",
    )
    parser.add_argument(
        "--jobs", type=int, default=None, help="worker processes (default: number of CPUs)"
    )
    parser.add_argument(
        "--vtk-every", type=float, default=None, metavar="S", help="write VTK snapshots every S s"
    )
    parser.add_argument(
        "--reanalyse",
        action="store_true",
        help="no simulation: fit, plot and report again the study in --output",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="small version (under a minute on two cores): one 60 mm silo with a 50 mm bed, "
        "D0 = 24 and 28 mm",
    )
    return parser


def case_from_args(args: argparse.Namespace) -> tuple[SiloCase, list[float]]:
    """The SiloCase and orifice diameters (m) the parsed options describe."""
    base: dict[str, Any] = {}
    if args.quick:
        base = dict(QUICK_CASE)
    if args.silo_ratio is not None:
        base["silo_ratio"] = args.silo_ratio
        base.pop("silo_diameter", None)
    if args.wall_gap is not None:
        base["wall_gap"] = args.wall_gap
        base.pop("silo_diameter", None)
    if args.draining:
        base["constant_head"] = False
    if args.measure_time is not None:
        base["measure_time"] = args.measure_time
    if args.height_ratio is not None:
        base["height_ratio"] = args.height_ratio
        base.pop("fill_height", None)
    if args.head_ratio is not None:
        base["head_ratio"] = args.head_ratio
        base.pop("fill_height", None)
    if args.silo_diameter is not None:
        base["silo_diameter"] = args.silo_diameter * 1e-3
    if args.fill_height is not None:
        base["fill_height"] = args.fill_height * 1e-3
    if args.particles is not None:
        base["particles"] = args.particles
        base["fill_height"] = None
    if args.vtk_every is not None:
        base["vtk_every"] = args.vtk_every
    for name in ("youngs_modulus", "friction", "rolling_friction", "time_step"):
        if getattr(args, name) is not None:
            base[name] = getattr(args, name)
    orifices = args.orifices or (QUICK_ORIFICES_MM if args.quick else DEFAULT_ORIFICES_MM)
    if args.seeds is not None and args.seeds < 1:
        raise ValueError(f"--seeds must be at least 1, got {args.seeds}")
    return SiloCase(**base), [v * 1e-3 for v in orifices]


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if args.reanalyse:
            reanalyse(args.output)
            return 0
        case, orifices = case_from_args(args)
        count = args.seeds if args.seeds is not None else (1 if args.quick else 2)
        seeds = range(args.first_seed, args.first_seed + count)
        run_study(args.output, case, orifices, seeds=seeds, jobs=args.jobs)
    except ValueError as err:
        parser.error(str(err))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
