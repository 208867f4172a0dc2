"""Silo discharge study (CASES D1): a study's results, their plot, report and JSON."""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from studies.silo_discharge.silo_beverloo import (
    BEVERLOO_C,
    BEVERLOO_K,
    BeverlooFit,
    G,
    beverloo_rate,
)
from studies.silo_discharge.silo_case import WINDOW, SiloCase
from studies.silo_discharge.silo_run import DischargeResult

# ------------------------------------------------------------------------------------------
# the study
# ------------------------------------------------------------------------------------------


@dataclass
class StudyResult:
    """All runs of a study, per-orifice rates and bulk densities, the Beverloo fits."""

    case: SiloCase
    orifices: list[float]  # m
    seeds: list[int]
    runs: list[DischargeResult]
    rate_mean: list[float]  # kg/s per orifice (over the seeds that did not clog)
    rate_std: list[float]  # kg/s, sample standard deviation over the seeds (NaN for one)
    bulk_density: list[float]  # kg/m^3 per orifice, core of the bed (mean over the seeds)
    fit: BeverlooFit | None  # C and k, exponent 2.5
    fit_free: BeverlooFit | None  # C, k and the exponent
    fit_exponent: BeverlooFit | None  # C and the exponent, k = 1.5
    scatter: float  # relative scatter of one run's W between seeds (NaN for one seed)
    exponent_range: tuple[float, float] | None  # 1-sigma profile interval of the free n
    wall_clock: float
    output: Path
    plot: Path
    report: Path
    report_text: str = ""
    jobs: int = 1  # worker processes the runs used

    @property
    def reference_rate(self) -> list[float]:
        """Beverloo with C = 0.58, k = 1.5 and the measured bulk density, kg/s per orifice."""
        d = self.case.diameter
        return [
            float(beverloo_rate(d0, d, rho))
            for d0, rho in zip(self.orifices, self.bulk_density, strict=True)
        ]


def acceptance(r: StudyResult) -> dict[str, bool]:
    """CASES D1 check (i) per item: the free exponent within 2.5 +/- 0.15, and with n = 2.5,
    C in [0.5, 0.7] and k in [1, 2] (empty when there is no fit)."""
    out: dict[str, bool] = {}
    if r.fit_free is not None:
        out["n"] = abs(r.fit_free.exponent - 2.5) <= 0.15 and not r.fit_free.at_bound
    if r.fit is not None:
        out["C"] = 0.5 <= r.fit.c <= 0.7
        out["k"] = 1.0 <= r.fit.k <= 2.0
    return out


def json_ready(v: Any) -> Any:
    """``v`` for json.dumps: NaN and inf -> None, numpy scalars -> Python, recursively."""
    if isinstance(v, float) and not math.isfinite(v):
        return None
    if isinstance(v, dict):
        return {k: json_ready(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [json_ready(x) for x in v]
    if isinstance(v, np.floating | np.integer | np.bool_):
        return json_ready(v.item())
    return v


def write_json(path: Path, r: StudyResult) -> None:
    data = {
        "case": dataclasses.asdict(r.case),
        "orifices_m": r.orifices,
        "seeds": r.seeds,
        "rate_mean_kg_s": r.rate_mean,
        "rate_std_kg_s": r.rate_std,
        "core_bulk_density_kg_m3": r.bulk_density,
        "beverloo_reference_kg_s": r.reference_rate,
        "fit_exponent_2_5": None if r.fit is None else dataclasses.asdict(r.fit),
        "fit_free": None if r.fit_free is None else dataclasses.asdict(r.fit_free),
        "fit_k_1_5": None if r.fit_exponent is None else dataclasses.asdict(r.fit_exponent),
        "acceptance_i": acceptance(r),
        "seed_scatter_log": r.scatter,
        "exponent_1sigma_range": r.exponent_range,
        "runs": [run.summary() for run in r.runs],
        "wall_clock_s": r.wall_clock,
        "jobs": r.jobs,
    }
    path.write_text(json.dumps(json_ready(data), indent=2) + "\n")


def plot_study(path: Path, r: StudyResult) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    case, d = r.case, r.case.diameter
    rho = float(np.mean(r.bulk_density))
    fig, (ax_m, ax_w, ax_lin) = plt.subplots(1, 3, figsize=(15.0, 5.0), dpi=110)
    fig.suptitle(
        f"Flat-bottomed silo discharge (CASES D1): {case.describe()};\n"
        f"d = {d * 1e3:g} mm ± {case.diameter_spread:.0%}, ρ_p = {case.density:g} kg/m³, "
        f"E = {case.youngs_modulus:.0e} Pa, e = {case.restitution:g}, μ = {case.friction:g}, "
        f"μ_r = {case.rolling_friction:g}"
    )
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    if case.constant_head:
        _plot_rate_history(ax_m, r, colors)
    else:
        _plot_drained_mass(ax_m, r, colors)

    d0s = np.asarray(r.orifices)
    w = np.asarray(r.rate_mean)
    err = np.nan_to_num(np.asarray(r.rate_std))
    grid = np.linspace(max(d0s.min() * 0.8, 2.0 * d), d0s.max() * 1.15, 200)
    ax_w.errorbar(
        d0s * 1e3, w, yerr=err, fmt="o", color="k", capsize=3, label="DEM (mean over seeds)"
    )
    ax_w.plot(
        grid * 1e3,
        beverloo_rate(grid, d, rho),
        color="0.5",
        linestyle=":",
        label=f"Beverloo C = {BEVERLOO_C}, k = {BEVERLOO_K}",
    )
    if r.fit is not None:
        ax_w.plot(
            grid * 1e3,
            r.fit.rate(grid, d, rho),
            color="tab:blue",
            label=f"fit, n = 2.5: C = {r.fit.c:.3f}, k = {r.fit.k:.2f}",
        )
    if r.fit_exponent is not None:
        ax_w.plot(
            grid * 1e3,
            r.fit_exponent.rate(grid, d, rho),
            color="tab:green",
            linestyle="-.",
            label=f"fit, k = {BEVERLOO_K}: n = {r.fit_exponent.exponent:.2f}, "
            f"C = {r.fit_exponent.c:.3f}",
        )
    if r.fit_free is not None:
        ax_w.plot(
            grid * 1e3,
            r.fit_free.rate(grid, d, rho),
            color="tab:red",
            linestyle="--",
            label=f"fit, all free: n = {r.fit_free.exponent:.2f}, C = {r.fit_free.c:.3f}, "
            f"k = {r.fit_free.k:.2f}",
        )
    ax_w.set_xlabel("orifice diameter D0 (mm)")
    ax_w.set_ylabel("discharge rate W (kg/s)")
    ax_w.set_title(f"W vs D0 (curves at the mean ρ_b = {rho:.0f} kg/m³)", fontsize=10)
    ax_w.set_ylim(bottom=0.0)
    ax_w.legend(fontsize=8, loc="upper left")
    ax_w.grid(True, alpha=0.3)

    # linearised: (W / (C rho_b sqrt g))^(2/5) = D0 - k d, a line of slope 1 through k d
    c_lin = r.fit.c if r.fit is not None else BEVERLOO_C
    y = (w / (c_lin * np.asarray(r.bulk_density) * math.sqrt(G))) ** 0.4
    ax_lin.plot(d0s * 1e3, y * 1e3, "o", color="k", label="DEM")
    line = np.linspace(0.0, d0s.max() * 1.15, 50)
    if r.fit is not None:
        ax_lin.plot(
            line * 1e3,
            np.clip(line - r.fit.k * d, 0, None) * 1e3,
            color="tab:blue",
            label=f"D0 − k d, fitted k = {r.fit.k:.2f}",
        )
    ax_lin.plot(
        line * 1e3,
        np.clip(line - BEVERLOO_K * d, 0, None) * 1e3,
        color="0.5",
        linestyle=":",
        label=f"D0 − {BEVERLOO_K} d",
    )
    ax_lin.set_xlabel("orifice diameter D0 (mm)")
    ax_lin.set_ylabel(f"(W / (C ρ_b √g))^(2/5) (mm), C = {c_lin:.3f}")
    ax_lin.set_title("linearised Beverloo: slope 1, zero at D0 = k d", fontsize=10)
    ax_lin.set_xlim(0.0, line[-1] * 1e3)
    ax_lin.set_ylim(bottom=0.0)
    ax_lin.legend(fontsize=8, loc="upper left")
    ax_lin.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _plot_rate_history(ax: Any, r: StudyResult, colors: list[str]) -> None:
    """Constant head: the rate in 0.05 s bins over the measured W, per orifice (steady = 1)."""
    case, d, width = r.case, r.case.diameter, 0.05
    for i, d0 in enumerate(r.orifices):
        for j, run in enumerate(x for x in r.runs if x.orifice == d0):
            if not (math.isfinite(run.rate) and run.rate > 0 and len(run.time) > 1):
                continue
            edges = np.arange(0.0, run.time[-1] + 1e-12, width)
            mass = np.interp(edges, run.time, run.mass)
            label = f"D0 = {d0 * 1e3:g} mm ({d0 / d:.3g} d)" if j == 0 else None
            ax.stairs(
                np.diff(mass) / width / run.rate,
                edges,
                baseline=None,
                color=colors[i % len(colors)],
                linewidth=1.1,
                label=label,
            )
    t0 = case.transient
    t1 = max(case.measure_window(d0)[1] for d0 in r.orifices)
    ax.axvspan(t0, t1, color="0.9", zorder=0, label="steady window (from)")
    ax.axhline(1.0, color="k", linewidth=0.8)
    _style_history(
        ax,
        "rate in 0.05 s bins / W",
        "discharge rate over the measured W (window starts at the grey band)",
        1.6,
    )


def _style_history(ax: Any, ylabel: str, title: str, top: float) -> None:
    ax.set_xlabel("time after opening (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.set_xlim(left=0.0)
    ax.set_ylim(0.0, top)
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(True, alpha=0.3)


def _plot_drained_mass(ax: Any, r: StudyResult, colors: list[str]) -> None:
    """Draining silo: discharged fraction of the inventory, with the 20-70 % fit."""
    d = r.case.diameter
    for i, d0 in enumerate(r.orifices):
        color = colors[i % len(colors)]
        for j, run in enumerate(x for x in r.runs if x.orifice == d0):
            label = f"D0 = {d0 * 1e3:g} mm ({d0 / d:.3g} d)" if j == 0 else None
            frac = run.mass / run.inventory
            ax.plot(run.time, frac, color=color, linewidth=1.2, label=label)
            sel = (run.mass >= WINDOW[0] * run.inventory) & (run.mass <= WINDOW[1] * run.inventory)
            if math.isfinite(run.rate) and np.count_nonzero(sel) >= 3:
                t = run.time[sel]
                p = np.polyfit(t, frac[sel], 1)
                ax.plot(t, np.polyval(p, t), "--", color="k", linewidth=0.8)
            if run.clogged:
                ax.plot(run.time[-1], frac[-1], "x", color=color, markersize=8)
    for f in WINDOW:
        ax.axhline(f, color="0.6", linestyle=":", linewidth=1)
    _style_history(
        ax,
        "discharged mass / inventory",
        "discharged mass (dashed: linear fit, 20–70 % window)",
        1.0,
    )


def report_markdown(r: StudyResult) -> str:
    case, d = r.case, r.case.diameter
    mm = 1e3
    rho_mean = float(np.mean(r.bulk_density))
    rho_whole = float(np.mean([x.bulk_density for x in r.runs]))
    if case.constant_head:
        measure = (
            f"- constant head: every {case.refill_every:g} s the particles the outlet removed are "
            f"packed into a slab just above the initial free surface and thrown down at "
            f"{case.refill_speed:g} m/s; W = slope of the discharged mass over the steady window "
            f"from {case.transient:g} s after opening for max({case.measure_time:g} s, "
            f"{case.measure_count:g} particles at Beverloo's rate) (least squares)"
        )
    else:
        measure = (
            f"- W = slope of the discharged mass between {WINDOW[0]:.0%} and {WINDOW[1]:.0%} of "
            "the inventory (outlet removal history, least squares)"
        )
    lines = [
        "# Silo discharge and the Beverloo correlation (CASES.md D1)",
        "",
        "## Set-up",
        "",
        f"- silos: {case.describe()}; cylinder wall, flat floor = triangulated annulus mesh with "
        "a central circular orifice D0, closed by a shutter 0.05 d below the floor that drops "
        f"away at {case.shutter_speed:g} m/s once the bed has settled; particles are deleted "
        "(and counted) 1.5 d below the floor",
        f"- particles: spheres d = {d * mm:g} mm ± {case.diameter_spread:.0%} (uniform), "
        f"ρ_p = {case.density:g} kg/m³, E = {case.youngs_modulus:g} Pa (reduced), "
        f"ν = {case.poisson_ratio:g}",
        f"- contact: Hertz–Mindlin, e = {case.restitution:g}, μ = {case.friction:g} (particles "
        f"and walls), EPSD rolling resistance μ_r = {case.rolling_friction:g}, η_r = "
        f"{case.rolling_damping:g}; time step {r.runs[0].time_step:.3e} s (0.2 t_R)",
        f"- fill: poured through a disc face at the top ({case.pour_speed:g} m/s, stream solid "
        f"fraction {case.pour_fraction:g}), settled until the rms speed < "
        f"{case.settle_speed:g} m/s; bulk density ρ_b = ρ_p × solid fraction of the settled bed "
        "3 d away from the wall, the floor and the surface, measured per run (mean "
        f"{rho_mean:.0f} kg/m³ = {rho_mean / case.density:.3f} ρ_p; whole bed, inventory / "
        f"(cross-section × bed height): {rho_whole:.0f} kg/m³ = {rho_whole / case.density:.3f} "
        "ρ_p)",
        measure,
        f"- seeds {r.seeds}; {len(r.runs)} runs on {r.jobs} process(es), "
        f"{r.wall_clock:.0f} s wall-clock, {sum(x.particle_steps for x in r.runs):.3g} "
        "particle-steps",
        "",
        "## Measured discharge rates",
        "",
        "| D0 (mm) | D0/d | silo (mm) | particles | ρ_b (kg/m³) | W (kg/s) | seed spread (kg/s) | "
        "Beverloo C=0.58, k=1.5 (kg/s) | W / Beverloo | R² | W 2nd half / 1st half |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for i, d0 in enumerate(r.orifices):
        runs = [x for x in r.runs if x.orifice == d0]
        w, s, ref = r.rate_mean[i], r.rate_std[i], r.reference_rate[i]
        r2 = min(x.r_squared for x in runs)
        halves = np.mean([x.rate_second_half / x.rate_first_half for x in runs])
        spread = f"{s:.4f}" if math.isfinite(s) else "– (1 seed)"
        lines.append(
            f"| {d0 * mm:g} | {d0 / d:.2f} | {runs[0].silo_diameter * mm:g} | "
            f"{np.mean([x.particles for x in runs]):.0f} | {r.bulk_density[i]:.0f} | {w:.4f} | "
            f"{spread} | {ref:.4f} | {w / ref:.3f} | {r2:.4f} | {halves:.3f} |"
        )
    lines += ["", "## Beverloo fit (least squares in log W, ρ_b measured per orifice)", ""]

    def fit_line(f: BeverlooFit | None, head: str, values: str, more: str = "") -> None:
        if f is not None:
            edge = " — at the edge of the search range" if f.at_bound else ""
            lines.append(
                f"- {head}: {values} (rms log residual {f.rms_log_residual:.3f}{more}){edge}"
            )

    f = r.fit_free
    if f is not None:
        fit_line(
            f,
            "n, C and k free (k ≥ 0)",
            f"**n = {f.exponent:.2f}**, C = {f.c:.3f} m^(2.5 − n), k = {f.k:.2f}",
            f", {f.points} orifices",
        )
    f = r.fit
    if f is not None:
        fit_line(
            f,
            "n fixed at 2.5, C and k free",
            f"**C = {f.c:.3f}, k = {f.k:.2f}**",
            f"; with ρ_b = 0.6 ρ_p instead of the measured ρ_b: C = "
            f"{f.c * rho_mean / (0.6 * case.density):.3f}; with the whole-bed ρ_b: C = "
            f"{f.c * rho_mean / rho_whole:.3f}",
        )
    f = r.fit_exponent
    if f is not None:
        fit_line(
            f,
            f"k fixed at {BEVERLOO_K}, n and C free",
            f"n = {f.exponent:.2f}, C = {f.c:.3f} m^(2.5 − n)",
        )
    if r.fit is None:
        lines.append("- not enough orifices with a measured rate for a fit")
    if r.exponent_range is not None:
        lo, hi = r.exponent_range
        lines.append(
            f"- one-standard-error range of the free n: {lo:.2f}–{hi:.2f} (profile over n "
            f"with C, k refitted; scatter of one run's W between seeds {r.scatter:.1%}, "
            f"{r.scatter / math.sqrt(len(r.seeds)):.1%} for the mean of {len(r.seeds)} seeds)"
        )
    verdict = acceptance(r)
    lines.append(
        "- CASES D1 check (i): free-fit n = 2.5 ± 0.15, and with n = 2.5: C ∈ [0.5, 0.7], "
        "k ∈ [1.0, 2.0] — "
        + (", ".join(f"{k}: {'pass' if v else 'FAIL'}" for k, v in verdict.items()) or "no fit")
    )
    lines += [
        "",
        "## Runs",
        "",
        "| D0 (mm) | seed | particles | inventory (kg) | bed (mm) | W (kg/s) | clogged | "
        "out / left | inserted − (left + out) (kg) | lost | simulated (s) | wall-clock (s) | "
        "particle-steps/s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for x in r.runs:
        lines.append(
            f"| {x.orifice * mm:g} | {x.seed} | {x.particles} | {x.inventory:.4f} | "
            f"{x.bed_height * mm:.1f} | {x.rate:.4f} | {'yes' if x.clogged else 'no'} | "
            f"{x.discharged_count} / {x.remaining_count} | {x.mass_balance_error:.1e} | "
            f"{x.lost} | {x.fill_time + x.discharge_time:.2f} | {x.wall_clock:.0f} | "
            f"{x.particle_steps / x.wall_clock:.3g} |"
        )
    notes = [f"- D0 = {x.orifice * mm:g} mm, seed {x.seed}: {n}" for x in r.runs for n in x.notes]
    if notes:
        lines += ["", "Notes:", "", *notes]
    lines += [
        "",
        "## Scope",
        "",
        "CASES D1 asks for one silo D_s = 0.20 m filled 0.25 m high (about 140 000 particles), "
        "E = 1e8 Pa, Δt = 0.07 t_R, at least three seeds per orifice and W between 20 % and 70 % "
        "of a draining inventory: about 1e12 particle-steps, days on one core. This study keeps "
        "the material of D1 (d, PSD, ρ_p, ν, e, μ, μ_r, η_r) and reduces the cost by a softer "
        "modulus (E = 1e7 Pa; at D0 = 24 mm W = 0.0929 kg/s against 0.0924 kg/s at 1e8 Pa), "
        "Δt = 0.2 t_R, "
        + (
            "a constant head (a shallow bed that flows steadily instead of a tall one that "
            "drains), "
            if case.constant_head
            else ""
        )
        + f"silos only as wide as the wall distance requires and {len(r.seeds)} seed(s).",
        "",
        f"Files: {r.plot.name} (plot), results.json (every number), history_D<mm>_s<seed>.csv "
        "(outlet histories: time after opening, discharged mass and count).",
        "",
    ]
    return "\n".join(lines)
