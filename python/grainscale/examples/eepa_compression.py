"""EEPA coarse-graining study: uniaxial tests at several particle scales (CASES.md E3).

Thakur, Ooi & Ahmadian (2016, Powder Technol. 293:130) found that with the bilinear
elasto-plastic adhesive (EEPA) contact model the bulk response of a cohesive powder in confined
compression and unconfined compression to failure does not depend on the particle size if the
contact stiffnesses scale with the particle size (k ~ R) and the adhesive force with its square
(f0 ~ R^2). This study repeats that test with grainscale's "cg" scheme
(:func:`grainscale.scaling.scale`): the reference powder (h = 1) and the same powder made of h
times larger particles (h = 1.5, 2 by default), plus a negative control at the largest h with f0
not scaled. Each run (see :mod:`grainscale.examples.eepa_uniaxial`): fill and settle in a
40 mm die, confined compression to sigma_pre = 10 kPa and unloading, die removed, unconfined
compression to failure.

Run it with ``python -m grainscale.examples.eepa_compression --output out/eepa --jobs 2``.
Compared with the reference: the loading curve sigma(eps) (L1-relative difference, CASES.md
section 0), the unloading stiffness (secant over the first 25 % of the unloading) and the
unconfined strength sigma_c; agreement is claimed within 5 %.

Written to the output directory: eepa_compression.png (loading/unloading and unconfined curves
of every run), report.md, results.json (every number, with the binned curves).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import dataclasses
import json
import multiprocessing
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from grainscale.examples import eepa_analysis as ea
from grainscale.examples import eepa_uniaxial as eu

TOLERANCE = 0.05  # agreement claimed by Thakur et al. 2016 and gated by CASES.md E3


@dataclasses.dataclass(frozen=True)
class Job:
    """One run: a size ratio, and whether it is the negative control (f0 not scaled)."""

    h: float
    control: bool = False

    @property
    def label(self) -> str:
        return f"h={self.h:g}" + (" f0 unscaled" if self.control else "")


def _run(case: eu.Case, job: Job, max_unconfined_strain: float) -> eu.RunResult:
    return eu.run_test(case, job.h, job.control, max_unconfined_strain)


def run_jobs(
    case: eu.Case, jobs: Sequence[Job], workers: int, max_unconfined_strain: float = 0.15
) -> list[eu.RunResult]:
    """Run the jobs in worker processes (largest run first), results in job order."""
    if workers < 1:
        raise ValueError(f"run_jobs.workers must be >= 1, got {workers!r}")
    order = sorted(range(len(jobs)), key=lambda k: jobs[k].h)
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = {k: pool.submit(_run, case, jobs[k], max_unconfined_strain) for k in order}
        return [futures[k].result() for k in range(len(jobs))]


def metrics_of(case: eu.Case, run: eu.RunResult) -> ea.Metrics:
    return ea.measure(
        (run.loading.height, run.loading.stress),
        (run.unloading.height, run.unloading.stress),
        (run.unconfined.height, run.unconfined.stress),
        run.unconfined_start,
        case.pre_stress,
    )


def compare(
    case: eu.Case, runs: Sequence[eu.RunResult], metrics: Sequence[ea.Metrics]
) -> list[dict[str, Any]]:
    """Per run: its numbers and its differences from the reference run (h = 1, scaled f0)."""
    ref = next(
        m for r, m in zip(runs, metrics, strict=True) if r.h == 1 and not r.control
    )  # the reference is always part of a study
    rows = []
    for r, m in zip(runs, metrics, strict=True):
        d = 2 * r.mean_radius
        rate = case.platen_speed / m.seating_height
        rows.append(
            {
                "h": r.h,
                "control": r.control,
                "particles": r.particles,
                "mean_diameter": d,
                "time_step": r.time_step,
                "die_to_particle": case.die_diameter / d,
                "seating_height": m.seating_height,
                "solid_fraction_seated": r.solid_volume / (case.area * m.seating_height),
                "core_solid_fraction": r.core_solid_fraction,
                "pre_strain": m.pre_strain,
                "unloading_stiffness": m.unloading_stiffness,
                "strength": m.strength,
                "strength_strain": m.strength_strain,
                "peaked": m.peaked,
                "loading_l1": ea.l1_relative(
                    ref.loading_strain, ref.loading_stress, m.loading_strain, m.loading_stress
                ),
                "stiffness_difference": ea.relative_difference(
                    m.unloading_stiffness, ref.unloading_stiffness
                ),
                "strength_difference": ea.relative_difference(m.strength, ref.strength),
                "inertial_number_pre": ea.inertial_number(rate, d, case.density, case.pre_stress),
                "inertial_number_strength": ea.inertial_number(
                    rate, d, case.density, max(m.strength, 1e-9)
                ),
                "wall_clock": r.wall_clock,
                "broken": r.broken,
                "notes": r.notes,
            }
        )
    return rows


def agrees(row: dict[str, Any], tolerance: float = TOLERANCE) -> dict[str, bool]:
    """Which of the three quantities agree with the reference within ``tolerance``."""
    return {
        "loading": row["loading_l1"] <= tolerance,
        "stiffness": abs(row["stiffness_difference"]) <= tolerance,
        "strength": abs(row["strength_difference"]) <= tolerance,
    }


def plot(rows: Sequence[dict[str, Any]], metrics: Sequence[ea.Metrics], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for row, m in zip(rows, metrics, strict=True):
        style = "--" if row["control"] else "-"
        label = f"h = {row['h']:g}" + (", f0 not scaled" if row["control"] else "")
        a.plot(m.loading_strain, [s / 1e3 for s in m.loading_stress], style, label=label)
        b.plot(m.unconfined_strain, [s / 1e3 for s in m.unconfined_stress], style, label=label)
    a.set(xlabel="axial strain from seating", ylabel="axial stress (kPa)")
    a.set_title("confined loading to sigma_pre")
    b.set(xlabel="axial strain", ylabel="axial stress, area-corrected (kPa)")
    b.set_title("unconfined compression")
    for ax in (a, b):
        ax.grid(alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def report(case: eu.Case, rows: Sequence[dict[str, Any]], wall_clock: float, workers: int) -> str:
    """The Markdown report of a finished study."""
    lines = [
        "# EEPA coarse-graining study (CASES.md E3)",
        "",
        "Thakur, Ooi & Ahmadian 2016 (Powder Technol. 293:130): with k ~ R and f0 ~ R^2 the bulk",
        "response in confined and unconfined uniaxial compression should not depend on the",
        'particle size. Scaled sets from `grainscale.scaling.scale(..., scheme="cg")`.',
        "",
        "## Set-up",
        "",
        f"- die D = {case.die_diameter * 1e3:g} mm, loose fill {case.fill_height * 1e3:g} mm"
        " settled under gravity without cohesion, then the full law;",
        f"- reference radius {case.radius * 1e3:g} mm +/- {case.spread * 100:g} % (uniform),"
        f" density {case.density:g} kg/m^3, E = {case.youngs_modulus:g} Pa (reduced),"
        f" nu = {case.poisson_ratio:g}, e = {case.restitution:g};",
        f"- EEPA n = 1, chi = 1, k1 = 2 E* R*, k2/k1 = {case.unloading_ratio:g},"
        f" k_adh = {case.adhesive_stiffness:g} N/m, f0 = {case.pull_off_force:g} N (h = 1),"
        f" mu = {case.friction:g}, EPSD mu_r = {case.rolling_friction:g};",
        f"- sigma_pre = {case.pre_stress / 1e3:g} kPa; platen speed"
        f" {case.platen_speed * 1e3:g} mm/s at every scale; time step = shortest contact"
        f" duration / {case.steps_per_contact:g};",
        "- values: CASES.md E3 protocol for D, n, chi, k1 ~ R, k2/k1, mu, mu_r and the sigma_pre"
        " range; our choices: reduced E, density, k_adh = k1 of two mean spheres, f0 = -0.5"
        " sigma_pre d^2 (cohesion a clear part of the strength), platen speed from the inertial"
        " number;",
        "- loading strain from the seating stress"
        f" ({ea.SEATING_FRACTION:g} sigma_pre); unloading stiffness: secant over the first"
        f" {ea.UNLOADING_FRACTION:.0%} of the unloading; sigma_c: peak of the area-corrected"
        f" unconfined stress ({ea.UNCONFINED_BIN:g} strain bins), or its maximum up to 15 %"
        " strain (ASTM D2166) when there is no peak.",
        "",
        "## Results (differences against h = 1)",
        "",
        "| run | N | D/d | dt (s) | phi core | phi seated | eps_pre | E_unl (MPa) | sigma_c (kPa) "
        "| eps at sigma_c | L1 sigma(eps) | dE_unl | dsigma_c | I at sigma_pre | I at sigma_c "
        "| wall-clock (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        name = f"h = {r['h']:g}" + (" (f0 not scaled)" if r["control"] else "")
        peak = "" if r["peaked"] else " (no peak)"
        lines.append(
            f"| {name} | {r['particles']} | {r['die_to_particle']:.1f} | {r['time_step']:.2e} "
            f"| {r['core_solid_fraction']:.3f} | {r['solid_fraction_seated']:.3f} "
            f"| {r['pre_strain']:.4f} "
            f"| {r['unloading_stiffness'] / 1e6:.3f} | {r['strength'] / 1e3:.3f}{peak} "
            f"| {r['strength_strain']:.4f} | {r['loading_l1']:.1%} "
            f"| {r['stiffness_difference']:+.1%} | {r['strength_difference']:+.1%} "
            f"| {r['inertial_number_pre']:.1e} | {r['inertial_number_strength']:.1e} "
            f"| {r['wall_clock']:.0f} |"
        )
    lines += ["", f"## Within {TOLERANCE:.0%} of h = 1?", ""]
    for r in rows:
        if r["h"] == 1 and not r["control"]:
            continue
        ok = agrees(r)
        name = f"h = {r['h']:g}" + (" (f0 not scaled)" if r["control"] else "")
        verdict = ", ".join(f"{k}: {'yes' if v else 'NO'}" for k, v in ok.items())
        lines.append(f"- {name}: {verdict}")
    broken = next((r["broken"] for r in rows if r["h"] != 1), [])
    lines += ["", "## Similarity numbers the cg scheme does not preserve", ""]
    for b in broken:
        lines.append(f"- {b['definition']}: x h^{b['exponent']:g}")
    lines += [
        "",
        f"Wall-clock of the study: {wall_clock:.0f} s with {workers} worker processes.",
        "",
    ]
    return "\n".join(lines)


def run_study(
    case: eu.Case,
    scales: Sequence[float],
    control: float | None,
    output: Path,
    workers: int,
    max_unconfined_strain: float = 0.15,
) -> list[dict[str, Any]]:
    """Run, measure, compare and write the plot, report.md and results.json."""
    if 1 not in scales:
        raise ValueError(f"run_study.scales must contain the reference 1, got {list(scales)}")
    jobs = [Job(h) for h in scales] + ([Job(control, True)] if control is not None else [])
    t0 = time.perf_counter()
    runs = run_jobs(case, jobs, workers, max_unconfined_strain)
    wall_clock = time.perf_counter() - t0
    metrics = [metrics_of(case, r) for r in runs]
    rows = compare(case, runs, metrics)
    output.mkdir(parents=True, exist_ok=True)
    plot(rows, metrics, output / "eepa_compression.png")
    (output / "report.md").write_text(report(case, rows, wall_clock, workers))
    results = {
        "case": dataclasses.asdict(case),
        "tolerance": TOLERANCE,
        "wall_clock": wall_clock,
        "workers": workers,
        "runs": [
            dict(row, agrees=agrees(row), curves=dataclasses.asdict(m))
            for row, m in zip(rows, metrics, strict=True)
        ],
    }
    (output / "results.json").write_text(json.dumps(results, indent=1))
    return rows


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path, default=Path("out/eepa_compression"))
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 1.5, 2.0])
    parser.add_argument("--control", type=float, default=2.0, help="h of the f0-unscaled run")
    parser.add_argument("--die-mm", type=float, default=40.0, help="die diameter (mm)")
    parser.add_argument("--fill-mm", type=float, default=60.0, help="loose fill height (mm)")
    args = parser.parse_args(argv)
    case = eu.Case(die_diameter=args.die_mm * 1e-3, fill_height=args.fill_mm * 1e-3)
    rows = run_study(case, args.scales, args.control, args.output, args.jobs)
    for r in rows:
        print(
            f"h={r['h']:g}{' control' if r['control'] else ''}: N={r['particles']} "
            f"L1={r['loading_l1']:.3f} dE={r['stiffness_difference']:+.3f} "
            f"sigma_c={r['strength']:.0f} Pa ({r['strength_difference']:+.3f})"
        )
    print(f"written to {args.output}")


if __name__ == "__main__":
    main()
