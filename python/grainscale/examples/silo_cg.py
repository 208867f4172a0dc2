"""Coarse-grained silo discharge against the resolved study (validation/CASES.md D1, check ii).

Run it with ``python -m grainscale.examples.silo_cg --output out/silo_cg``. The resolved study
of ``grainscale.examples.silo_discharge`` (its results.json, ``--reference``) fixes everything:
the SiloCase (silo and bed sizing, material, fill, constant head, measuring window) is read
from it, the CG runs only set ``SiloCase.cg = h``, so the silo, the bed and the window are
those of the resolved runs while the particles are parcels h d across whose parameters come
from ``grainscale.scaling.scale(reference, h, scheme="cg")`` (time step and skin x h, material,
restitution, friction and rolling parameters unchanged). Beverloo's law with k acting on the
parcel diameter predicts the coarse-grain deficit (CASES D1 ii, from W = C rho_b sqrt(g)
(D0 - k d)^(5/2); Beverloo, Leniger & van de Velde 1961)

    W_CG / W_ref = ((D0/d - k h) / (D0/d - k))^(5/2),

with k (and C) fitted to the resolved runs with the exponent 2.5. Pass (CASES D1): for h = 2 at
D0 / (h d) = 5-8 the mean measured ratio over >= 3 seeds is within +/- 0.05 of the prediction.

Default runs: h = 2 at D0 = 40, 52, 64 mm and h = 3 at D0 = 52, 64 mm, seeds 1-3. Each run is
stored in ``<output>/runs/`` (summary JSON and outlet history CSV), so studies can be extended
(``--cg``, ``--orifices``, ``--first-seed``) and analysed again without simulating
(``--reanalyse``); runs made with another SiloCase than the reference's are refused.

Written to the output directory: report.md, ratio.png (measured vs predicted ratio, W vs D0),
results.json (every number) and runs/.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from grainscale.examples import silo_beverloo, silo_case, silo_report, silo_run
from grainscale.examples import silo_discharge as sd

DEFAULT_REFERENCE = Path("docs/studies/silo_discharge/results.json")
#: h -> orifices (mm): D0 / (h d) = 5, 6.5, 8 at h = 2 (the gated range of CASES D1 ii)
DEFAULT_RUNS: dict[float, tuple[float, ...]] = {2.0: (40.0, 52.0, 64.0), 3.0: (52.0, 64.0)}
TOLERANCE = 0.05  # CASES D1 (ii): |measured - predicted ratio| on the mean over seeds
GATED_H = 2.0  # CASES D1 (ii) gates h = 2 only
GATED_RANGE = (5.0, 8.0)  # ... at D0 / (h d) in this range


# ------------------------------------------------------------------------------------------
# the resolved reference
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Reference:
    """The resolved study a CG study is compared with (from its results.json)."""

    path: Path
    case: silo_case.SiloCase
    orifices: list[float]  # m
    seeds: list[int]
    rate_mean: list[float]  # kg/s per orifice
    rate_std: list[float]  # kg/s (NaN for one seed)
    bulk_density: list[float]  # kg/m^3, core of the settled bed
    particles: list[float]  # mean inventory per orifice
    wall_clock: list[float]  # mean s per run per orifice
    c: float  # Beverloo fit with n = 2.5
    k: float
    free_fit: tuple[float, float] | None  # (k, n) of the fit with n free: W_ref(D0) smoothly

    def similar_ratio(self, orifice: float, h: float) -> float:
        """W_CG / W_ref if the CG silo behaves as the resolved one at D0 / h magnified h times:
        h^2.5 W_ref(D0 / h) / W_ref(D0), W_ref from the free fit (NaN without one)."""
        if self.free_fit is None:
            return math.nan
        k, n = self.free_fit
        x = orifice / self.case.diameter
        return h ** (2.5 - n) * max(0.0, (x - k * h) / (x - k)) ** n

    def index(self, orifice: float) -> int:
        """Position of the orifice D0 (m) in the reference; ValueError if it was not run."""
        for i, d0 in enumerate(self.orifices):
            if math.isclose(d0, orifice, rel_tol=1e-9):
                return i
        raise ValueError(
            f"silo_cg: orifice {orifice * 1e3:g} mm is not in the reference {self.path} "
            f"(D0 = {', '.join(f'{v * 1e3:g}' for v in self.orifices)} mm)"
        )


def load_reference(path: str | Path) -> Reference:
    """The resolved study stored in ``path`` (results.json of silo_discharge)."""
    p = Path(path)
    data = json.loads(p.read_text())
    case = silo_case.SiloCase(**data["case"])
    if case.cg != 1:
        raise ValueError(f"silo_cg.reference must be a resolved study (cg = 1), got cg = {case.cg}")
    fit = data.get("fit_exponent_2_5")
    if fit is None:
        raise ValueError(f"silo_cg.reference {p} has no Beverloo fit (fit_exponent_2_5)")
    free = data.get("fit_free")
    orifices = [float(v) for v in data["orifices_m"]]
    runs = data["runs"]

    def mean_of(key: str, d0: float) -> float:
        return float(np.mean([r[key] for r in runs if math.isclose(r["orifice"], d0)]))

    def value(v: Any) -> float:
        return math.nan if v is None else float(v)

    return Reference(
        path=p,
        case=case,
        orifices=orifices,
        seeds=[int(s) for s in data["seeds"]],
        rate_mean=[value(v) for v in data["rate_mean_kg_s"]],
        rate_std=[value(v) for v in data["rate_std_kg_s"]],
        bulk_density=[value(v) for v in data["core_bulk_density_kg_m3"]],
        particles=[mean_of("particles", d0) for d0 in orifices],
        wall_clock=[mean_of("wall_clock", d0) for d0 in orifices],
        c=float(fit["c"]),
        k=float(fit["k"]),
        free_fit=None if free is None else (float(free["k"]), float(free["exponent"])),
    )


def predicted_ratio(d0_over_d: float, h: float, k: float, exponent: float = 2.5) -> float:
    """Beverloo's W_CG / W_ref = ((D0/d - k h) / (D0/d - k))^n (CASES.md D1 ii): k acts on the
    parcel diameter h d; 0 when the parcels cannot pass (D0 <= k h d)."""
    if not d0_over_d > k:
        raise ValueError(f"predicted_ratio.d0_over_d must exceed k = {k:g}, got {d0_over_d!r}")
    return max(0.0, (d0_over_d - k * h) / (d0_over_d - k)) ** exponent


def effective_k(d0_over_d: float, h: float, k: float, ratio: float) -> float:
    """The k' for which ((D0/d - k' h) / (D0/d - k))^2.5 equals the measured ratio: the empty
    annulus of the CG run in parcel diameters (k' = k when Beverloo's scaling holds)."""
    return (d0_over_d - (d0_over_d - k) * ratio**0.4) / h


# ------------------------------------------------------------------------------------------
# runs
# ------------------------------------------------------------------------------------------


def run_name(h: float, orifice: float, seed: int) -> str:
    return f"h{h:g}_D{orifice * 1e3:g}_s{seed}"


def save_run(directory: Path, case: silo_case.SiloCase, run: silo_run.DischargeResult) -> None:
    """runs/<name>.json (the run's SiloCase and summary) and runs/<name>.csv (its history)."""
    directory.mkdir(parents=True, exist_ok=True)
    name = run_name(run.cg, run.orifice, run.seed)
    data = {"case": dataclasses.asdict(case), "run": run.summary()}
    (directory / f"{name}.json").write_text(
        json.dumps(silo_report.json_ready(data), indent=2) + "\n"
    )
    sd.save_history(directory / f"{name}.csv", run)


def load_runs(directory: Path, reference: Reference) -> list[silo_run.DischargeResult]:
    """Every run stored in ``directory``; ValueError for a run whose SiloCase differs from the
    reference's in anything but cg."""
    runs = []
    for path in sorted(directory.glob("*.json")):
        data = json.loads(path.read_text())
        case = silo_case.SiloCase(**data["case"])
        differ = [
            f.name
            for f in dataclasses.fields(silo_case.SiloCase)
            if f.name != "cg" and getattr(case, f.name) != getattr(reference.case, f.name)
        ]
        if differ:
            raise ValueError(
                f"silo_cg: run {path} was made with another SiloCase than the reference "
                f"{reference.path} (differs in {', '.join(differ)}); use another --output"
            )
        runs.append(sd.load_run(case, data["run"], path.with_suffix(".csv")))
    return sorted(runs, key=lambda r: (r.cg, r.orifice, r.seed))


# ------------------------------------------------------------------------------------------
# analysis
# ------------------------------------------------------------------------------------------


@dataclass
class Comparison:
    """The CG runs at one (h, D0) against the resolved ones."""

    h: float
    orifice: float  # m
    d0_over_d: float  # resolved D0 / d
    seeds: list[int]
    rates: list[float]  # kg/s per seed (NaN: clogged or window not reached)
    clogged: int  # runs without a rate (clogged, or no flow in the window)
    rate_mean: float
    rate_std: float
    reference_rate: float
    reference_std: float
    ratio: float  # mean W_CG / mean W_ref
    ratio_spread: float  # sample sd over the seeds of W_CG,i / W_ref
    ratio_error: float  # standard error of the ratio (CG and reference seeds)
    predicted: float  # Beverloo, fitted k
    predicted_k15: float  # Beverloo, k = 1.5
    similar: float  # h^2.5 W_ref(D0 / h) / W_ref(D0) from the resolved free fit
    similar_extrapolated: bool  # D0 / h below the smallest resolved orifice
    effective_k: float
    bulk_density: float  # CG core bulk density, kg/m^3
    reference_bulk_density: float
    particles: float  # mean CG inventory
    reference_particles: float
    time_step: float
    wall_clock: float  # mean s per CG run
    reference_wall_clock: float
    gated: bool
    passed: bool | None  # None when not gated

    @property
    def deviation(self) -> float:
        return self.ratio - self.predicted


def compare(reference: Reference, runs: Sequence[silo_run.DischargeResult]) -> list[Comparison]:
    """One Comparison per (h, D0) of the runs."""
    d = reference.case.diameter
    out = []
    for h, d0 in sorted({(r.cg, r.orifice) for r in runs}):
        mine = [r for r in runs if r.cg == h and r.orifice == d0]
        i = reference.index(d0)
        w_ref, s_ref = reference.rate_mean[i], reference.rate_std[i]
        # a run that clogged, or stopped flowing so that its window holds no discharge, has
        # no Beverloo rate: left out of the mean and counted
        rates = [r.rate if not r.clogged else math.nan for r in mine]
        ok = np.array([w for w in rates if math.isfinite(w)])
        n_ref = len(reference.seeds)
        mean = float(ok.mean()) if len(ok) else math.nan
        std = float(ok.std(ddof=1)) if len(ok) > 1 else math.nan
        ratio = mean / w_ref
        rel = (std / mean) ** 2 / len(ok) if len(ok) > 1 else math.nan
        if math.isfinite(s_ref):
            rel += (s_ref / w_ref) ** 2 / n_ref
        x = d0 / d
        predicted = predicted_ratio(x, h, reference.k)
        gated = h == GATED_H and GATED_RANGE[0] - 1e-9 <= x / h <= GATED_RANGE[1] + 1e-9
        out.append(
            Comparison(
                h=h,
                orifice=d0,
                d0_over_d=x,
                seeds=[r.seed for r in mine],
                rates=rates,
                clogged=sum(not math.isfinite(w) for w in rates),
                rate_mean=mean,
                rate_std=std,
                reference_rate=w_ref,
                reference_std=s_ref,
                ratio=ratio,
                ratio_spread=std / w_ref,
                ratio_error=ratio * math.sqrt(rel),
                predicted=predicted,
                predicted_k15=predicted_ratio(x, h, silo_beverloo.BEVERLOO_K),
                similar=reference.similar_ratio(d0, h),
                similar_extrapolated=d0 / h < min(reference.orifices) * (1 - 1e-9),
                effective_k=effective_k(x, h, reference.k, ratio) if ratio > 0 else math.nan,
                bulk_density=float(np.mean([r.core_bulk_density for r in mine])),
                reference_bulk_density=reference.bulk_density[i],
                particles=float(np.mean([r.particles for r in mine])),
                reference_particles=reference.particles[i],
                time_step=mine[0].time_step,
                wall_clock=float(np.mean([r.wall_clock for r in mine])),
                reference_wall_clock=reference.wall_clock[i],
                gated=gated,
                passed=(abs(ratio - predicted) <= TOLERANCE) if gated else None,
            )
        )
    return out


def fit_cg(
    reference: Reference, comparisons: Sequence[Comparison], h: float
) -> silo_beverloo.BeverlooFit | None:
    """Beverloo (n = 2.5) fitted to the CG runs of ratio h with the parcel diameter h d: C and k
    of the coarse system, from the orifices where at most 1 run in 10 clogged (intermittent
    flow is not Beverloo's); None with fewer than 2 such orifices."""
    mine = [
        c
        for c in comparisons
        if c.h == h and math.isfinite(c.rate_mean) and c.clogged <= 0.1 * len(c.seeds)
    ]
    if len(mine) < 2:
        return None
    return silo_beverloo.fit_beverloo(
        [c.orifice for c in mine],
        [c.rate_mean for c in mine],
        h * reference.case.diameter,
        [c.bulk_density for c in mine],
        exponent=2.5,
    )


def broken_similarities(reference: Reference, h: float, orifice: float) -> list[dict[str, Any]]:
    """The similarity numbers scale(..., "cg") reports broken for the silo at ratio h."""
    setup = silo_run.silo_setup(dataclasses.replace(reference.case, cg=h), orifice)
    assert setup.scaled is not None
    return [dataclasses.asdict(b) for b in setup.scaled.broken]


# ------------------------------------------------------------------------------------------
# the study
# ------------------------------------------------------------------------------------------


def run_study(
    output: str | Path,
    reference: Reference,
    runs: dict[float, Sequence[float]] | None = None,
    seeds: Sequence[int] = (1, 2, 3),
    jobs: int = 1,
    verbose: bool = True,
) -> dict[str, Any]:
    """Run the CG silos ``runs`` (h -> orifices in m; default DEFAULT_RUNS) for every seed,
    store them in ``output``/runs and analyse every run stored there."""
    out = Path(output)
    plan = runs if runs is not None else {h: [v * 1e-3 for v in d] for h, d in DEFAULT_RUNS.items()}
    tasks = []
    for h, orifices in plan.items():
        case = dataclasses.replace(reference.case, cg=float(h))
        for d0 in sorted(orifices, reverse=True):
            reference.index(d0)  # refuse orifices without a resolved rate before running
            tasks += [(case, float(d0), int(s), None) for s in seeds]
    if jobs < 1:
        raise ValueError(f"silo_cg.jobs must be at least 1, got {jobs}")
    say = _print if verbose else (lambda _s: None)
    say(
        f"grainscale CG silo discharge (CASES D1 ii) against {reference.path}: "
        f"{len(tasks)} runs on {jobs} process(es); output in {out}"
    )
    t0 = time.perf_counter()
    done = silo_run.run_many(tasks, jobs, verbose)
    say(f"{len(done)} runs in {time.perf_counter() - t0:.0f} s")
    cases = {c.cg: c for c, *_ in tasks}
    for r in done:
        save_run(out / "runs", cases[r.cg], r)
    return analyse(out, reference, verbose)


def analyse(output: str | Path, reference: Reference, verbose: bool = True) -> dict[str, Any]:
    """Compare every run in ``output``/runs with the reference; write report.md, ratio.png and
    results.json; return the results."""
    out = Path(output)
    runs = load_runs(out / "runs", reference)
    if not runs:
        raise ValueError(f"silo_cg: no runs in {out / 'runs'}")
    comparisons = compare(reference, runs)
    hs = sorted({c.h for c in comparisons})
    fits = {h: fit_cg(reference, comparisons, h) for h in hs}
    broken = {h: broken_similarities(reference, h, comparisons[0].orifice) for h in hs}
    gated = [c for c in comparisons if c.gated]
    result = {
        "reference": str(reference.path),
        "case": dataclasses.asdict(reference.case),
        "reference_fit": {"c": reference.c, "k": reference.k, "exponent": 2.5},
        "tolerance": TOLERANCE,
        "passed": bool(gated) and all(c.passed for c in gated),
        "comparisons": [dataclasses.asdict(c) for c in comparisons],
        "cg_fits": {
            f"{h:g}": None if f is None else dataclasses.asdict(f) for h, f in fits.items()
        },
        "broken_similarities": {f"{h:g}": b for h, b in broken.items()},
        "runs": [dict(r.summary(), name=run_name(r.cg, r.orifice, r.seed)) for r in runs],
    }
    (out / "results.json").write_text(json.dumps(silo_report.json_ready(result), indent=2) + "\n")
    _plot(out / "ratio.png", reference, comparisons)
    text = _report(reference, comparisons, fits, broken, runs, result["passed"])
    (out / "report.md").write_text(text)
    if verbose:
        _print(text)
    return result


def _print(line: str) -> None:
    print(line, flush=True)


# ------------------------------------------------------------------------------------------
# plot and report
# ------------------------------------------------------------------------------------------


def _plot(path: Path, reference: Reference, comparisons: Sequence[Comparison]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d, k = reference.case.diameter, reference.k
    rho = float(np.mean(reference.bulk_density))
    colors = {2.0: "tab:blue", 3.0: "tab:red", 4.0: "tab:green"}
    fig, (ax_r, ax_w) = plt.subplots(1, 2, figsize=(13.0, 5.2), dpi=110)
    fig.suptitle(
        f"Coarse-grained silo discharge (CASES D1 ii) against {reference.path}\n"
        f"{reference.case.describe()}; d = {d * 1e3:g} mm, resolved fit n = 2.5: "
        f"C = {reference.c:.3f}, k = {k:.2f}",
        fontsize=10,
    )
    x_max = max(reference.orifices) / d * 1.1
    for h in sorted({c.h for c in comparisons}):
        color = colors.get(h, "k")
        x = np.linspace(k * h + 0.05, x_max, 200)
        ax_r.plot(
            x,
            [predicted_ratio(v, h, k) for v in x],
            color=color,
            label=f"Beverloo h = {h:g}, fitted k = {k:.2f}",
        )
        ax_r.plot(
            x,
            [predicted_ratio(v, h, silo_beverloo.BEVERLOO_K) for v in x],
            color=color,
            linestyle=":",
            label=f"Beverloo h = {h:g}, k = {silo_beverloo.BEVERLOO_K}",
        )
        if reference.free_fit is not None:
            ax_r.plot(
                x,
                [reference.similar_ratio(v * d, h) for v in x],
                color=color,
                linestyle="--",
                label=f"h^2.5 W_ref(D0/h) / W_ref(D0), h = {h:g} (resolved free fit)",
            )
        if h == GATED_H:
            band = np.array([predicted_ratio(v, h, k) for v in x])
            ax_r.fill_between(
                x, band - TOLERANCE, band + TOLERANCE, color=color, alpha=0.12, label="± 0.05"
            )
        mine = [c for c in comparisons if c.h == h]
        ax_r.errorbar(
            [c.d0_over_d for c in mine],
            [c.ratio for c in mine],
            yerr=[np.nan_to_num(c.ratio_spread) for c in mine],
            fmt="o",
            color=color,
            capsize=3,
            label=f"DEM h = {h:g} (mean, bars: seed sd)",
        )
        for c in mine:
            ax_r.plot(
                [c.d0_over_d] * len(c.rates),
                np.array(c.rates) / c.reference_rate,
                ".",
                color=color,
                alpha=0.5,
            )
        stuck = [c for c in mine if c.clogged]
        if stuck:
            y = 0.04 * h
            ax_r.plot(
                [c.d0_over_d for c in stuck],
                [y] * len(stuck),
                "x",
                color=color,
                markersize=8,
                label=f"h = {h:g}: clogged runs / runs",
            )
            for c in stuck:
                ax_r.annotate(
                    f"{c.clogged}/{len(c.seeds)}",
                    (c.d0_over_d, y),
                    xytext=(5, -3),
                    textcoords="offset points",
                    fontsize=7,
                    color=color,
                )
        ax_w.errorbar(
            [c.orifice * 1e3 for c in mine],
            [c.rate_mean for c in mine],
            yerr=[np.nan_to_num(c.rate_std) for c in mine],
            fmt="s",
            color=color,
            capsize=3,
            label=f"CG h = {h:g}",
        )
        grid = np.linspace(k * h * d + 1e-3, max(reference.orifices) * 1.1, 200)
        ax_w.plot(
            grid * 1e3,
            silo_beverloo.beverloo_rate(grid, h * d, rho, reference.c, k),
            color=color,
            linestyle="--",
            label=f"C ρ_b √g (D0 − k h d)^2.5, h = {h:g}",
        )
    ax_r.set_xlabel("D0 / d (resolved d)")
    ax_r.set_ylabel("W_CG / W_ref")
    ax_r.set_title("measured vs Beverloo-predicted ratio (dots: single seeds)", fontsize=10)
    ax_r.set_xlim(0, x_max)
    ax_r.set_ylim(0, 1.3)
    ax_r.grid(True, alpha=0.3)
    ax_r.legend(fontsize=6.5, loc="upper left", ncol=2)
    d0s = np.array(reference.orifices)
    ax_w.errorbar(
        d0s * 1e3,
        reference.rate_mean,
        yerr=np.nan_to_num(reference.rate_std),
        fmt="o",
        color="k",
        capsize=3,
        label="resolved h = 1",
    )
    grid = np.linspace(reference.k * d + 1e-3, d0s.max() * 1.1, 200)
    ax_w.plot(
        grid * 1e3,
        silo_beverloo.beverloo_rate(grid, d, rho, reference.c, reference.k),
        color="k",
        label="resolved fit",
    )
    ax_w.set_xlabel("orifice diameter D0 (mm)")
    ax_w.set_ylabel("discharge rate W (kg/s)")
    ax_w.set_title(f"W vs D0 (curves: resolved C, k at ρ_b = {rho:.0f} kg/m³)", fontsize=10)
    ax_w.set_ylim(bottom=0)
    ax_w.grid(True, alpha=0.3)
    ax_w.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _report(
    reference: Reference,
    comparisons: Sequence[Comparison],
    fits: dict[float, silo_beverloo.BeverlooFit | None],
    broken: dict[float, list[dict[str, Any]]],
    runs: Sequence[silo_run.DischargeResult],
    passed: bool,
) -> str:
    case, d, mm = reference.case, reference.case.diameter, 1e3
    gated = [c for c in comparisons if c.gated]
    lines = [
        "# Coarse-grained silo discharge (CASES.md D1, check ii)",
        "",
        "## Set-up",
        "",
        f"- reference: the resolved study `{reference.path}` (seeds {reference.seeds}); its "
        f"SiloCase is used unchanged except `cg`: {case.describe()}; spheres d = {d * mm:g} mm "
        f"± {case.diameter_spread:.0%}, ρ_p = {case.density:g} kg/m³, E = "
        f"{case.youngs_modulus:g} Pa, ν = {case.poisson_ratio:g}, e = {case.restitution:g}, "
        f"μ = {case.friction:g}, EPSD μ_r = {case.rolling_friction:g}, η_r = "
        f"{case.rolling_damping:g}",
        "- CG runs: the same silo, bed mass, pour rate, constant-head refill and measuring "
        "window; the parcels (h d across, same ρ_p) and their time step, skin and contact "
        'parameters are `grainscale.scaling.scale(reference, h, scheme="cg")` of the '
        "resolved ParameterSet (time step and skin × h; E, ν, e, μ, μ_r, η_r unchanged; "
        "Hertz stiffness ∝ R and the EPSD rolling stiffness ∝ R³ follow from the law); outlet "
        "depth, shutter gap and drop, pour-face margin and the 3-parcel core margin of ρ_b "
        "are in units of the parcel size h d",
        f"- resolved Beverloo fit (n = 2.5): C = {reference.c:.3f}, k = {reference.k:.2f}; "
        "prediction W_CG / W_ref = ((D0/d − k h) / (D0/d − k))^2.5 (CASES D1 ii: k acts on the "
        "parcel diameter)",
        f"- pass: h = {GATED_H:g} at D0 / (h d) = {GATED_RANGE[0]:g}–{GATED_RANGE[1]:g}, mean "
        f"ratio over the seeds within ± {TOLERANCE} of the prediction",
        "",
        "## Ratios",
        "",
        "| h | D0 (mm) | D0/d | D0/(h d) | seeds | W_CG (kg/s) | seed sd | W_ref (kg/s) | "
        "W_CG / W_ref | seed sd of ratio | s.e. | predicted (fitted k) | predicted (k = 1.5) | "
        "measured − predicted | k' (parcel) | h^2.5 W_ref(D0/h) / W_ref(D0) | ρ_b CG / ref | "
        "CASES |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in comparisons:
        verdict = "–" if c.passed is None else ("pass" if c.passed else "**FAIL**")
        clog = f" ({c.clogged} clogged)" if c.clogged else ""  # not in the mean
        lines.append(
            f"| {c.h:g} | {c.orifice * mm:g} | {c.d0_over_d:.1f} | {c.d0_over_d / c.h:.2f} | "
            f"{len(c.seeds)}{clog} | {c.rate_mean:.4f} | {c.rate_std:.4f} | "
            f"{c.reference_rate:.4f} | **{c.ratio:.3f}** | {c.ratio_spread:.3f} | "
            f"{c.ratio_error:.3f} | {c.predicted:.3f} | {c.predicted_k15:.3f} | "
            f"{c.deviation:+.3f} | {c.effective_k:.2f} | "
            f"{c.similar:.3f}{' (extrapolated)' if c.similar_extrapolated else ''} | "
            f"{c.bulk_density / c.reference_bulk_density:.3f} | {verdict} |"
        )
    lines += [
        "",
        f"**CASES D1 (ii): {'pass' if passed else 'FAIL'}** "
        f"({sum(bool(c.passed) for c in gated)} of {len(gated)} gated (h, D0) within "
        f"± {TOLERANCE}).",
        "",
        "k' is the k for which Beverloo's ratio equals the measured one (k' = k when the "
        "empty annulus is k parcel diameters wide); s.e. combines the seed scatter of the CG "
        "and the resolved means. Runs that clogged (or had no discharge in the window) are "
        "counted, not averaged.",
        "",
        "h^2.5 W_ref(D0/h) / W_ref(D0) is the ratio if the CG silo behaved as the resolved "
        "silo with the orifice D0/h, magnified h times (dimensional analysis: W = ρ_b √g "
        "D0^2.5 F(D0/d, ...), whose Beverloo form with n = 2.5 gives the CASES formula), with "
        "W_ref(D0) interpolated by the resolved fit with n free"
        + (
            f" (n = {reference.free_fit[1]:.2f}, k = {reference.free_fit[0]:.2f}); "
            "'extrapolated' where D0/h is below the smallest resolved orifice."
            if reference.free_fit is not None
            else " (not available: no free fit in the reference)."
        ),
        "",
        "## Beverloo fitted to the CG runs (n = 2.5, parcel diameter h d)",
        "",
    ]
    for h, f in fits.items():
        if f is None:
            lines.append(f"- h = {h:g}: fewer than 2 orifices")
        else:
            lines.append(
                f"- h = {h:g}: C = {f.c:.3f}, k = {f.k:.2f} (rms log residual "
                f"{f.rms_log_residual:.3f}, {f.points} orifices); resolved: C = "
                f"{reference.c:.3f}, k = {reference.k:.2f}"
            )
    lines += ["", "## Similarity numbers the cg scheme breaks (from `scale()`)", ""]
    for h, numbers in broken.items():
        items = "; ".join(
            f"{b['definition']} × {b['factor']:.3g} (h^{b['exponent']:g})" for b in numbers
        )
        lines.append(f"- h = {h:g}: {items}")
    lines += [
        "",
        "## Cost",
        "",
        "| h | D0 (mm) | particles CG | particles ref | ratio × h³ | time step (s) | "
        "wall-clock CG (s) | wall-clock ref (s) | speed-up |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for c in comparisons:
        lines.append(
            f"| {c.h:g} | {c.orifice * mm:g} | {c.particles:.0f} | {c.reference_particles:.0f} | "
            f"{c.particles / c.reference_particles * c.h**3:.3f} | {c.time_step:.3e} | "
            f"{c.wall_clock:.0f} | {c.reference_wall_clock:.0f} | "
            f"{c.reference_wall_clock / c.wall_clock:.1f} |"
        )
    lines += [
        "",
        "Wall-clock times are of single runs on a shared, loaded machine (the resolved ones "
        "from another session): indicative only; `bench/python/silo_cg.py` measures them "
        "side by side.",
        "",
        "## Runs",
        "",
        "| h | D0 (mm) | seed | particles | bed (mm) | ρ_b core (kg/m³) | W (kg/s) | R² | "
        "2nd / 1st half | clogged | lost | steps | wall-clock (s) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append(
            f"| {r.cg:g} | {r.orifice * mm:g} | {r.seed} | {r.particles} | "
            f"{r.bed_height * mm:.1f} | {r.core_bulk_density:.0f} | {r.rate:.4f} | "
            f"{r.r_squared:.4f} | {r.rate_second_half / r.rate_first_half:.3f} | "
            f"{'yes' if r.clogged or not math.isfinite(r.rate) else 'no'} | {r.lost} | "
            f"{r.steps} | {r.wall_clock:.0f} |"
        )
    notes = [
        f"- h = {r.cg:g}, D0 = {r.orifice * mm:g} mm, seed {r.seed}: {n}"
        for r in runs
        for n in r.notes
    ]
    if notes:
        lines += ["", "Notes:", "", *notes]
    lines += ["", "Files: ratio.png, results.json, runs/ (per-run summary and outlet history).", ""]
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.silo_cg",
        description="Coarse-grained silo discharge against a resolved silo_discharge study "
        "(validation/CASES.md D1 ii). Lengths in mm.",
    )
    parser.add_argument(
        "--output", default="out/silo_cg", help="output directory (default: %(default)s)"
    )
    parser.add_argument(
        "--reference",
        default=str(DEFAULT_REFERENCE),
        help="results.json of the resolved study (default: %(default)s)",
    )
    parser.add_argument(
        "--cg",
        type=float,
        nargs="+",
        default=None,
        metavar="H",
        help="coarse-graining ratios (default: "
        + ", ".join(
            f"{h:g} at D0 = {' '.join(f'{v:g}' for v in d)}" for h, d in DEFAULT_RUNS.items()
        )
        + ")",
    )
    parser.add_argument(
        "--orifices",
        type=float,
        nargs="+",
        default=None,
        metavar="MM",
        help="orifice diameters in mm for every --cg (default: as above; each must be in the "
        "reference)",
    )
    parser.add_argument("--seeds", type=int, default=3, help="seeds per run (default 3)")
    parser.add_argument(
        "--first-seed", type=int, default=1, help="seeds are first-seed, ... (default 1)"
    )
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument(
        "--reanalyse",
        action="store_true",
        help="no simulation: compare the runs stored in --output with the reference again",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        reference = load_reference(args.reference)
        if args.reanalyse:
            analyse(args.output, reference)
            return 0
        if args.seeds < 1:
            raise ValueError(f"--seeds must be at least 1, got {args.seeds}")
        hs = args.cg if args.cg is not None else list(DEFAULT_RUNS)
        plan: dict[float, Sequence[float]] = {}
        for h in hs:
            mm = args.orifices if args.orifices is not None else DEFAULT_RUNS.get(h)
            if mm is None:
                raise ValueError(f"--orifices must be given for --cg {h:g} (no default)")
            plan[h] = [v * 1e-3 for v in mm]
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        run_study(args.output, reference, plan, seeds=seeds, jobs=args.jobs)
    except ValueError as err:
        parser.error(str(err))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
