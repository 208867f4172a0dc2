"""Coarse-grained silo discharge (CASES D1 ii): the plot and the Markdown report."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from studies.silo_cg.silo_cg_compare import (
    GATED_H,
    GATED_RANGE,
    TOLERANCE,
    Comparison,
    Reference,
    predicted_ratio,
)
from studies.silo_discharge import silo_beverloo, silo_run

# ------------------------------------------------------------------------------------------
# plot and report
# ------------------------------------------------------------------------------------------


def plot_ratios(path: Path, reference: Reference, comparisons: Sequence[Comparison]) -> None:
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


def report_markdown(
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
