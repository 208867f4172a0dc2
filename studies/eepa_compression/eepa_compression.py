"""EEPA coarse-graining study: uniaxial tests at several particle scales (CASES.md E3).

Thakur, Ooi & Ahmadian (2016, Powder Technol. 293:130) found that with the bilinear
elasto-plastic adhesive (EEPA) contact model the bulk response of a cohesive powder in confined
compression and unconfined compression to failure does not depend on the particle size if the
contact stiffnesses scale with the particle size (k ~ R) and the adhesive force with its square
(f0 ~ R^2). This study repeats that test with grainscale's "cg" scheme
(:func:`grainscale.scaling.scale`): the reference powder (h = 1) and the same powder made of h
times larger particles (h = 1.5, 2 by default), each with several packing seeds; the reference
powder also in dies shrunk by 1/h (the die-to-particle ratio D/d of each coarse scale, the one
geometric similarity the cg scheme cannot keep in a fixed die); and a negative control at the
largest h with f0 not scaled. Each run (see :mod:`studies.eepa_compression.eepa_uniaxial`): a
random packing compacted without gravity, friction or cohesion in a 40 mm die, confined
compression to sigma_pre = 10 kPa and unloading, die removed, unconfined compression to
failure. Options: the base powder's radius (``--radius-mm``, default 1 mm, D/d = 20; the
CASES.md base is 0.5 mm), a lubricated die (``--lubricated-die``: frictionless, non-adhesive
wall), fewer seeds for the costly base runs (``--base-seeds``).

Run it with ``python -m studies.eepa_compression.eepa_compression --output out/eepa`` (one process;
every run is saved in ``out/eepa/runs`` as it finishes and reused, so the study can be resumed).
Compared between groups of seeds: the loading curve sigma(eps) (L1-relative difference,
CASES.md section 0, of the seed-mean curves), the unloading stiffness (secant over the first
25 % of the unloading) and the unconfined strength sigma_c; agreement is claimed within 5 %.

Written to the output directory: eepa_compression.png (seed-mean loading curves, unconfined
curves of every run), report.md, results.json (every number, with the binned curves).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from studies.eepa_compression import eepa_analysis as ea
from studies.eepa_compression import eepa_uniaxial as eu

TOLERANCE = 0.05  # agreement claimed by Thakur et al. 2016 and gated by CASES.md E3


@dataclasses.dataclass(frozen=True)
class Job:
    """One run: a size ratio h, whether it is the negative control (f0 not scaled), the packing
    seed, and a factor on the die diameter and fill height. ``geometry`` = 1/h with h = 1 is the
    reference powder in the die shrunk to the die-to-particle ratio D/d of scale h; gravity x h
    keeps the weight stress rho g H, the Froude and the Bond number of the coarse run, and the
    hold and rest times shrink with the lengths (at equal velocities the process time goes with
    the length), so with the same seed it is the coarse run shrunk by h in every dimensionless
    number (inertial number, dt / T included): it separates the contact-law scaling from the
    D/d effect."""

    h: float
    control: bool = False
    seed: int = 1
    geometry: float = 1.0

    @property
    def group(self) -> str:
        """The runs that differ only by their seed."""
        return (
            f"h={self.h:g}"
            + (" f0 unscaled" if self.control else "")
            + (f" D x{self.geometry:g}" if self.geometry != 1 else "")
        )

    @property
    def label(self) -> str:
        return f"{self.group} seed {self.seed}"

    def case(self, case: eu.Case) -> eu.Case:
        return dataclasses.replace(
            case,
            seed=self.seed,
            die_diameter=case.die_diameter * self.geometry,
            fill_height=case.fill_height * self.geometry,
            gravity=case.gravity / self.geometry,
            hold_time=case.hold_time * self.geometry,
            rest_time=case.rest_time * self.geometry,
        )


def _run(case: eu.Case, job: Job, max_unconfined_strain: float) -> eu.RunResult:
    return eu.run_test(job.case(case), job.h, job.control, max_unconfined_strain)


def run_settings(case: eu.Case, job: Job, max_unconfined_strain: float) -> dict[str, Any]:
    """What a run depends on, as stored with it in the cache (JSON-normalised)."""
    settings = {
        "case": dataclasses.asdict(job.case(case)),
        "h": job.h,
        "control": job.control,
        "max_unconfined_strain": max_unconfined_strain,
    }
    return json.loads(json.dumps(settings))


def _flat(settings: dict[str, Any]) -> dict[str, Any]:
    return {**settings["case"], **{k: v for k, v in settings.items() if k != "case"}}


def _load(path: Path, settings: dict[str, Any]) -> eu.RunResult:
    """A cached run, refused unless it was made with ``settings``."""
    d = json.loads(path.read_text())
    stored = d.pop("settings", None)
    if stored != settings:
        changed = "no settings stored (an older version wrote it)"
        if stored is not None:
            old, new = _flat(stored), _flat(settings)
            changed = ", ".join(
                sorted(k for k in old.keys() | new.keys() if old.get(k) != new.get(k))
            )
        raise ValueError(
            f"cached run {path} was made with other settings ({changed}); use another output "
            "directory or delete the file to run it again"
        )
    for stage in ("loading", "unloading", "unconfined"):
        d[stage] = eu.Curve(**d[stage])
    return eu.RunResult(**d)


def run_cached(
    case: eu.Case, jobs: Sequence[Job], cache: Path | None, max_unconfined_strain: float = 0.15
) -> list[eu.RunResult]:
    """Run the jobs one after another in this process; with a ``cache`` directory each run is
    saved there, with its settings, as it finishes and read from there if already done (a long
    study can be stopped and resumed); a cached run made with other settings is refused."""
    out = []
    for job in jobs:
        path = None if cache is None else cache / (job.label.replace(" ", "_") + ".json")
        settings = run_settings(case, job, max_unconfined_strain)
        if path is not None and path.exists():
            out.append(_load(path, settings))
            continue
        run = _run(case, job, max_unconfined_strain)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(dict(dataclasses.asdict(run), settings=settings)))
            print(f"{job.label}: {run.wall_clock:.0f} s", flush=True)
        out.append(run)
    return out


def metrics_of(case: eu.Case, run: eu.RunResult) -> ea.Metrics:
    return ea.measure(
        (run.loading.height, run.loading.stress),
        (run.unloading.height, run.unloading.stress),
        (run.unconfined.height, run.unconfined.stress),
        run.unconfined_start,
        case.pre_stress,
    )


def run_row(case: eu.Case, job: Job, run: eu.RunResult, m: ea.Metrics) -> dict[str, Any]:
    """The numbers of one run (``case``: the study's case; the job scales its die)."""
    c = job.case(case)
    d = 2 * run.mean_radius
    start = run.loading.height[0]
    rate = c.platen_speed / m.seating_height
    return {
        "group": job.group,
        "h": run.h,
        "control": run.control,
        "seed": job.seed,
        "geometry": job.geometry,
        "particles": run.particles,
        "mean_diameter": d,
        "time_step": run.time_step,
        "die_to_particle": c.die_diameter / d,
        "height_to_particle": start / d,
        "prepared_height": run.settled_height,
        "solid_fraction": run.solid_volume / (c.area * run.settled_height),
        "core_solid_fraction": run.core_solid_fraction,
        "seating_strain": (start - m.seating_height) / start,
        "pre_strain": m.pre_strain,
        "unloading_stiffness": m.unloading_stiffness,
        "strength": m.strength,
        "strength_bin": m.strength_bin,
        "strength_strain": m.strength_strain,
        "peaked": m.peaked,
        "inertial_number_pre": ea.inertial_number(rate, d, c.density, c.pre_stress),
        "inertial_number_strength": ea.inertial_number(rate, d, c.density, max(m.strength, 1e-9)),
        "inertial_number_unloading": ea.inertial_number(
            c.unloading_platen_speed / m.seating_height, d, c.density, c.pre_stress
        ),
        "wall_clock": run.wall_clock,
        "broken": run.broken,
        "notes": run.notes,
    }


SUMMED = (
    "particles",
    "die_to_particle",
    "solid_fraction",
    "core_solid_fraction",
    "seating_strain",
    "pre_strain",
    "unloading_stiffness",
    "strength",
    "strength_bin",
    "strength_strain",
    "inertial_number_pre",
    "inertial_number_unloading",
    "wall_clock",
)


def stress_levels(case: eu.Case, count: int = 50) -> np.ndarray:
    """Stress levels (Pa) at which loading curves are averaged: seating stress to sigma_pre."""
    return np.linspace(ea.SEATING_FRACTION * case.pre_stress, case.pre_stress, count)


def summarize(
    rows: Sequence[dict[str, Any]], metrics: Sequence[ea.Metrics], levels: np.ndarray
) -> dict[str, dict[str, Any]]:
    """Per group of seeds: mean and standard deviation of every number, the mean loading curve
    (mean strain at each stress level; strain from the seating stress, and from the start of the
    loading) and the seed scatter of the curve (mean L1 of a seed's curve against the mean)."""
    out: dict[str, dict[str, Any]] = {}
    for group in dict.fromkeys(r["group"] for r in rows):
        idx = [k for k, r in enumerate(rows) if r["group"] == group]
        g: dict[str, Any] = {"seeds": len(idx), "h": rows[idx[0]]["h"]}
        for key in SUMMED:
            v = np.array([rows[k][key] for k in idx], dtype=float)
            g[key] = float(v.mean())
            g[key + "_std"] = float(v.std(ddof=1)) if len(v) > 1 else 0.0
        for name, (xs, ys) in {
            "seating": ("loading_strain", "loading_stress"),
            "start": ("start_strain", "start_stress"),
        }.items():
            curves = np.array(
                [
                    ea.strain_at_stress(getattr(metrics[k], xs), getattr(metrics[k], ys), levels)
                    for k in idx
                ]
            )
            mean = curves.mean(axis=0)
            g[f"curve_{name}"] = mean.tolist()
            g[f"scatter_{name}"] = float(
                np.mean([ea.l1_relative(mean, levels, c, levels) for c in curves])
            )
        out[group] = g
    return out


def compare(
    summary: dict[str, dict[str, Any]], group: str, reference: str, levels: np.ndarray
) -> dict[str, Any]:
    """Differences of one group of seeds from a reference group: L1-relative difference of the
    mean loading curves (both strain origins), relative differences of the mean unloading
    stiffness and strength, each with its standard error from the seed scatter."""
    a, r = summary[group], summary[reference]
    row: dict[str, Any] = {"group": group, "reference": reference}
    for name in ("seating", "start"):
        row[f"l1_{name}"] = ea.l1_relative(r[f"curve_{name}"], levels, a[f"curve_{name}"], levels)
        row[f"scatter_{name}"] = max(a[f"scatter_{name}"], r[f"scatter_{name}"])
    for key in ("unloading_stiffness", "strength", "strength_bin", "solid_fraction", "pre_strain"):
        row[key] = ea.relative_difference(a[key], r[key])
        row[key + "_error"] = (
            math.hypot(
                a[key + "_std"] / math.sqrt(a["seeds"]), r[key + "_std"] / math.sqrt(r["seeds"])
            )
            / r[key]
        )
    return row


def agrees(row: dict[str, Any], tolerance: float = TOLERANCE) -> dict[str, bool]:
    """Which of the three quantities agree with the reference within ``tolerance``."""
    return {
        "loading": row["l1_seating"] <= tolerance,
        "stiffness": abs(row["unloading_stiffness"]) <= tolerance,
        "strength": abs(row["strength"]) <= tolerance,
    }


def plot(
    summary: dict[str, dict[str, Any]],
    rows: Sequence[dict[str, Any]],
    metrics: Sequence[ea.Metrics],
    levels: np.ndarray,
    path: Path,
) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {g: f"C{k}" for k, g in enumerate(summary)}
    for g, s in summary.items():
        a.plot(s["curve_seating"], levels / 1e3, color=colours[g], label=f"{g} ({s['seeds']})")
    for r, m in zip(rows, metrics, strict=True):
        b.plot(
            m.unconfined_strain,
            [x / 1e3 for x in m.unconfined_stress],
            color=colours[r["group"]],
            lw=0.8,
            label=r["group"]
            if r["seed"] == min(x["seed"] for x in rows if x["group"] == r["group"])
            else None,
        )
    a.set(
        xlabel="axial strain from seating (mean of seeds at equal stress)",
        ylabel="axial stress (kPa)",
    )
    a.set_title("confined loading to sigma_pre")
    b.set(xlabel="axial strain", ylabel="axial stress, area-corrected (kPa)")
    b.set_title("unconfined compression (every seed)")
    for ax in (a, b):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _pm(mean: float, std: float, fmt: str, scale: float = 1.0) -> str:
    return f"{mean * scale:{fmt}} +/- {std * scale:{fmt}}"


def report(
    case: eu.Case,
    summary: dict[str, dict[str, Any]],
    comparisons: Sequence[dict[str, Any]],
    broken: Sequence[dict[str, Any]],
    wall_clock: float,
) -> str:
    """The Markdown report of a finished study (numbers only; notes are added by hand)."""
    lines = [
        "# EEPA coarse-graining study (CASES.md E3)",
        "",
        "Thakur, Ooi & Ahmadian 2016 (Powder Technol. 293:130): with k ~ R and f0 ~ R^2 the bulk",
        "response in confined and unconfined uniaxial compression should not depend on the",
        'particle size. Scaled sets from `grainscale.scaling.scale(..., scheme="cg")`.',
        "",
        "## Set-up",
        "",
        f"- die D = {case.die_diameter * 1e3:g} mm; random packing (volume fraction"
        f" {case.loose_fraction:g}) {case.fill_height * 1e3:g} mm high, prepared by"
        f" '{case.preparation}': compacted by the platen without gravity, friction, rolling"
        f" resistance or cohesion to {case.preparation_stress:g} Pa (fast at"
        f" {case.preparation_speed * 1e3:g} mm/s up to solid fraction {case.fast_fraction:g},"
        f" then at {2 * case.platen_speed * 1e3:g} mm/s, then held at the stress for"
        f" {case.hold_time:g} s); then the full law and gravity, platen in place;",
        f"- reference radius {case.radius * 1e3:g} mm +/- {case.spread * 100:g} % (uniform),"
        f" density {case.density:g} kg/m^3, E = {case.youngs_modulus:g} Pa (reduced),"
        f" nu = {case.poisson_ratio:g}, e = {case.restitution:g};",
        f"- EEPA n = 1, chi = 1, k1 = 2 E* R*, k2/k1 = {case.unloading_ratio:g},"
        f" k_adh = {case.adhesive_stiffness:g} N/m, f0 = {case.pull_off_force:g} N (h = 1),"
        f" mu = {case.friction:g}, EPSD mu_r = {case.rolling_friction:g}; platens with the"
        " powder's law; die wall "
        + (
            "lubricated (frictionless, non-adhesive, no rolling resistance);"
            if case.lubricated_die
            else "with the powder's law (rough);"
        ),
        f"- sigma_pre = {case.pre_stress / 1e3:g} kPa; platen speed"
        f" {case.platen_speed * 1e3:g} mm/s at every scale (unloading at"
        f" {case.unloading_platen_speed * 1e3:g} mm/s); time step = shortest contact"
        f" duration / {case.steps_per_contact:g};",
        "- loading strain from the seating stress"
        f" ({ea.SEATING_FRACTION:g} sigma_pre), and (column 'from start') from the height at"
        " which the loading started; loading curves of the seeds averaged as the mean strain at"
        " 50 stress levels from the seating stress to sigma_pre; unloading stiffness: secant"
        f" over the first {ea.UNLOADING_FRACTION:.0%} of the unloading; sigma_c: maximum up to"
        " 15 % strain (ASTM D2166) of the area-corrected unconfined stress averaged over"
        f" {ea.STRENGTH_WINDOW:g} strain (column 'bin': over {ea.UNCONFINED_BIN:g} strain, as in"
        " the first version of the study); 'I unloading': inertial number"
        " (d / T) sqrt(rho / sigma_pre) of the unloading strain rate 1 / T.",
        "",
        "## Per group of seeds (mean +/- standard deviation over the seeds)",
        "",
        "| group | seeds | N | D/d | phi (whole) | phi core | seating strain | eps_pre "
        "| I unloading | E_unl (MPa) | sigma_c (kPa) | sigma_c bin (kPa) | eps at sigma_c "
        "| L1 seed scatter | wall-clock/run (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for g, s in summary.items():
        lines.append(
            f"| {g} | {s['seeds']} | {s['particles']:.0f} | {s['die_to_particle']:.1f} "
            f"| {_pm(s['solid_fraction'], s['solid_fraction_std'], '.3f')} "
            f"| {_pm(s['core_solid_fraction'], s['core_solid_fraction_std'], '.3f')} "
            f"| {_pm(s['seating_strain'], s['seating_strain_std'], '.4f')} "
            f"| {_pm(s['pre_strain'], s['pre_strain_std'], '.4f')} "
            f"| {s['inertial_number_unloading']:.1e} "
            f"| {_pm(s['unloading_stiffness'], s['unloading_stiffness_std'], '.2f', 1e-6)} "
            f"| {_pm(s['strength'], s['strength_std'], '.2f', 1e-3)} "
            f"| {_pm(s['strength_bin'], s['strength_bin_std'], '.2f', 1e-3)} "
            f"| {s['strength_strain']:.3f} | {s['scatter_seating']:.1%} "
            f"| {s['wall_clock']:.0f} |"
        )
    lines += [
        "",
        "## Differences (mean of seeds against mean of seeds; +/- standard error from the"
        " seed scatter)",
        "",
        "| group | against | L1 sigma(eps) | L1 from start | L1 seed scatter | d phi "
        "| d eps_pre | dE_unl | dsigma_c | dsigma_c bin | within 5 %: loading, stiffness,"
        " strength |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in comparisons:
        ok = agrees(c)
        lines.append(
            f"| {c['group']} | {c['reference']} | {c['l1_seating']:.1%} | {c['l1_start']:.1%} "
            f"| {c['scatter_seating']:.1%} "
            f"| {c['solid_fraction']:+.1%} +/- {c['solid_fraction_error']:.1%} "
            f"| {c['pre_strain']:+.1%} +/- {c['pre_strain_error']:.1%} "
            f"| {c['unloading_stiffness']:+.1%} +/- {c['unloading_stiffness_error']:.1%} "
            f"| {c['strength']:+.1%} +/- {c['strength_error']:.1%} "
            f"| {c['strength_bin']:+.1%} +/- {c['strength_bin_error']:.1%} "
            f"| {', '.join('yes' if v else 'NO' for v in ok.values())} |"
        )
    lines += ["", "## Similarity numbers the cg scheme does not preserve", ""]
    for b in broken:
        lines.append(f"- {b['definition']}: x h^{b['exponent']:g}")
    lines += ["", f"Run time of the study: {wall_clock:.0f} s (sum over the runs).", ""]
    return "\n".join(lines)


def default_jobs(
    scales: Sequence[float],
    seeds: Sequence[int],
    control: float | None,
    base_seeds: Sequence[int] | None = None,
) -> list[Job]:
    """The study's runs: every scale and seed (the reference powder in the full die with
    ``base_seeds`` if given: its runs cost the most and scatter the least); the reference powder
    in dies scaled to the die-to-particle ratio of every coarser scale; the negative control (f0
    not scaled)."""
    base = seeds if base_seeds is None else base_seeds
    jobs = [Job(h, seed=s) for h in scales for s in (base if h == 1 else seeds)]
    jobs += [Job(1.0, seed=s, geometry=1 / h) for h in scales if h != 1 for s in seeds]
    if control is not None:
        jobs += [Job(control, True, seed=s) for s in seeds]
    return jobs


def default_comparisons(jobs: Sequence[Job]) -> list[tuple[str, str]]:
    """(group, reference): every group against the reference powder in the same die, and every
    coarse group against the reference powder at the same die-to-particle ratio."""
    groups = list(dict.fromkeys(j.group for j in jobs))
    ref = Job(1.0).group
    pairs = [(g, ref) for g in groups if g != ref]
    for j in jobs:
        if j.h != 1 and not j.control:
            matched = Job(1.0, geometry=1 / j.h).group
            if matched in groups and (j.group, matched) not in pairs:
                pairs.append((j.group, matched))
    return pairs


def run_study(
    case: eu.Case,
    jobs: Sequence[Job],
    output: Path,
    max_unconfined_strain: float = 0.15,
) -> tuple[dict[str, dict[str, Any]], list[dict[str, Any]]]:
    """Run (cached in output/runs), measure, compare and write the plot, report.md and
    results.json."""
    if Job(1.0).group not in {j.group for j in jobs}:
        raise ValueError("run_study.jobs must contain the reference powder h = 1 in the full die")
    t0 = time.perf_counter()
    runs = run_cached(case, jobs, output / "runs", max_unconfined_strain)
    wall_clock = time.perf_counter() - t0
    metrics = [metrics_of(j.case(case), r) for j, r in zip(jobs, runs, strict=True)]
    rows = [run_row(case, j, r, m) for j, r, m in zip(jobs, runs, metrics, strict=True)]
    levels = stress_levels(case)
    summary = summarize(rows, metrics, levels)
    comparisons = [compare(summary, g, r, levels) for g, r in default_comparisons(jobs)]
    broken = next((r["broken"] for r in rows if r["h"] != 1), [])
    output.mkdir(parents=True, exist_ok=True)
    plot(summary, rows, metrics, levels, output / "eepa_compression.png")
    total = sum(r["wall_clock"] for r in rows)
    (output / "report.md").write_text(report(case, summary, comparisons, broken, total))
    results = {
        "case": dataclasses.asdict(case),
        "tolerance": TOLERANCE,
        "wall_clock": wall_clock,
        "stress_levels": levels.tolist(),
        "groups": summary,
        "comparisons": [dict(c, agrees=agrees(c)) for c in comparisons],
        "runs": [
            dict(row, curves=dataclasses.asdict(m)) for row, m in zip(rows, metrics, strict=True)
        ],
    }
    (output / "results.json").write_text(json.dumps(results, indent=1))
    return summary, comparisons


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--output", type=Path, default=Path("out/eepa_compression"))
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 1.5, 2.0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    parser.add_argument(
        "--base-seeds",
        type=int,
        nargs="+",
        help="seeds of h = 1 in the full die (default: --seeds)",
    )
    parser.add_argument("--control", type=float, default=2.0, help="h of the f0-unscaled run")
    parser.add_argument("--die-mm", type=float, default=40.0, help="die diameter (mm)")
    parser.add_argument("--fill-mm", type=float, default=60.0, help="loose fill height (mm)")
    parser.add_argument("--preparation", choices=eu.PREPARATIONS, default="compact")
    parser.add_argument(
        "--radius-mm",
        type=float,
        help="mean radius of the base powder (mm), cohesion by the rules of Case (default: Case())",
    )
    parser.add_argument(
        "--lubricated-die", action="store_true", help="frictionless, non-adhesive die wall"
    )
    parser.add_argument(
        "--unloading-speed-mm-s",
        type=float,
        help="platen speed of the unloading (mm/s; default: the loading speed, 10 mm/s)",
    )
    args = parser.parse_args(argv)
    if 1.0 not in args.scales:
        parser.error(f"--scales must contain the reference 1, got {args.scales}")
    settings = dict(
        die_diameter=args.die_mm * 1e-3,
        fill_height=args.fill_mm * 1e-3,
        preparation=args.preparation,
        lubricated_die=args.lubricated_die,
        unloading_speed=(
            None if args.unloading_speed_mm_s is None else args.unloading_speed_mm_s * 1e-3
        ),
    )
    case = (
        eu.Case(**settings)
        if args.radius_mm is None
        else eu.powder_of_radius(args.radius_mm * 1e-3, **settings)
    )
    jobs = default_jobs(args.scales, args.seeds, args.control, args.base_seeds)
    _, comparisons = run_study(case, jobs, args.output)
    for c in comparisons:
        print(
            f"{c['group']} vs {c['reference']}: L1={c['l1_seating']:.3f} "
            f"(from start {c['l1_start']:.3f}) dE={c['unloading_stiffness']:+.3f} "
            f"dsigma_c={c['strength']:+.3f}"
        )
    print(f"written to {args.output}")


if __name__ == "__main__":
    main()
