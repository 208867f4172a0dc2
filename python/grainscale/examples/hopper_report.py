"""The hopper demo's report: its summary text and its plot (grainscale.examples.hopper_demo runs
the case)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import grainscale as gs
    from grainscale.examples.hopper_demo import HopperCase, HopperRig
    from grainscale.examples.hopper_geometry import HopperGeometry


def setup_text(case: HopperCase, rig: HopperRig, stl: Path, out: Path) -> str:
    """The two lines the demo prints before it runs: the particles, the hopper and the pour."""
    mm = 1e3
    geo = rig.geo
    return (
        f"grainscale hopper demo: {case.particles} spheres, d = {case.diameter * mm:g} mm "
        f"+/- {case.diameter_spread:.0%} (uniform), E = {case.youngs_modulus:g} Pa, "
        f"e = {case.restitution:g}, mu = {case.friction:g}, mu_r = {case.rolling_friction:g}\n"
        # the hopper wall is the Mesh that build() read from the STL file
        f"hopper {stl.name}: {len(rig.hopper.geometry.triangles)} triangles, outlet "  # type: ignore[union-attr]
        f"{2 * geo.outlet_radius * mm:.1f} mm, top {2 * geo.top_radius * mm:.1f} mm at "
        f"{(geo.top_z - geo.outlet_z) * mm:.1f} mm; poured at {rig.pour_rate:.3g} kg/s for "
        f"{rig.pour_time:.3g} s; {case.duration:g} s in steps of {rig.sim.time_step:.3e} s; "
        f"output in {out}"
    )


def summary(
    case: HopperCase,
    geo: HopperGeometry,
    stl: Path,
    r: dict[str, Any],
    sim: gs.Simulation,
    total: float,
) -> str:
    """The demo's summary.md: what ran, how fast, the discharge rate (r: run()'s result dict,
    total: wall-clock of the whole demo in s)."""
    mm = 1e3
    w = r["discharge_rate"]
    rate_line = (
        f"- discharge rate: {w * 1e3:.1f} g/s (slope of the discharged mass between 20 % and "
        "70 % of the inventory)"
        if math.isfinite(w)
        else "- discharge rate: not measured (the run ended before 70 % of the inventory left)"
    )
    lines = [
        "# grainscale hopper: hopper discharge",
        "",
        f"- hopper: {stl.name} read with gs.geometry.Mesh.from_stl, outlet "
        f"{2 * geo.outlet_radius * mm:.1f} mm, top {2 * geo.top_radius * mm:.1f} mm, height "
        f"{(geo.top_z - geo.outlet_z) * mm:.1f} mm; sliding gate under the outlet; collection "
        "box below",
        f"- particles: {r['inserted']} spheres poured ({r['inserted_mass'] * 1e3:.1f} g), "
        f"d = {case.diameter * mm:g} mm +/- {case.diameter_spread:.0%} (uniform), density "
        f"{case.density:g} kg/m^3, E = {case.youngs_modulus:g} Pa, nu = {case.poisson_ratio:g} "
        f"(lost: {r['lost']})",
        f"- contact law: Hertz–Mindlin, restitution {case.restitution:g}, friction "
        f"{case.friction:g}, EPSD rolling friction {case.rolling_friction:g}",
        f"- simulated: {sim.time:.4g} s in {r['steps']} steps, time step {r['time_step']:.4e} s "
        "(0.2 x Rayleigh time of the smallest sphere); gate opened at t = "
        f"{r['open_time']:.3f} s with {r['inventory'] * 1e3:.1f} g in the hopper",
        rate_line,
        f"- at the end: {r['discharged']} particles ({r['discharged_mass'] * 1e3:.1f} g) "
        f"discharged, {sim.num_particles - r['discharged']} still in the hopper",
        f"- wall-clock: {r['wall_clock']:.1f} s in Simulation.run ({total:.1f} s with set-up "
        f"and output) on {sim.ranks} rank(s); throughput {r['particle_steps_per_second']:.3g} "
        "particle-steps/s",
        f"- ParaView: {r['pvd']} ({r['snapshots']} snapshots), walls: {r['walls_pvd']}, box: "
        f"{r['output'] / 'bin.vtp'}",
        f"- plot: {r['plot']}; time series: {r['history']}",
        "",
    ]
    return "\n".join(lines)


def plot(
    path: Path,
    hist: np.ndarray,
    case: HopperCase,
    t_open: float | None,
    inventory: float,
    rate: float,
) -> None:
    """hopper.png: masses in the hopper and discharged, and the kinetic energy, against time
    (hist: the history rows; rate in kg/s, NaN if not measured)."""
    from .._optional import pyplot

    plt = pyplot()

    t = hist[:, 0]
    fig, (ax_m, ax_ke) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.5), dpi=150)
    fig.suptitle(
        f"Hopper discharge: {case.particles} spheres, d = {case.diameter * 1e3:g} mm "
        f"± {case.diameter_spread:.0%}, e = {case.restitution:g}, μ = {case.friction:g}, "
        f"μ_r = {case.rolling_friction:g}"
    )
    g = 1e3
    ax_m.plot(t, hist[:, 1] * g, color="tab:blue", label="in the hopper")
    ax_m.plot(t, hist[:, 2] * g, color="tab:orange", label="discharged (below the outlet)")
    ax_m.plot(t, (hist[:, 1] + hist[:, 2]) * g, color="0.5", linestyle=":", label="total")
    if t_open is not None:
        for ax in (ax_m, ax_ke):
            ax.axvline(t_open, color="0.3", linestyle="--", linewidth=1)
        ax_m.annotate(
            "gate opens",
            (t_open, 0.97 * inventory * g),
            xytext=(4, 0),
            textcoords="offset points",
            fontsize=8,
        )
    if math.isfinite(rate):
        ax_m.text(
            0.98,
            0.5,
            f"discharge rate {rate * 1e3:.1f} g/s\n(20–70 % of {inventory * 1e3:.0f} g)",
            transform=ax_m.transAxes,
            ha="right",
            va="center",
            fontsize=9,
            bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.8"},
        )
    ax_m.set_ylabel("mass (g)")
    ax_m.set_ylim(bottom=0.0)
    ax_m.legend(fontsize=8, loc="center left")
    ax_m.grid(True, alpha=0.3)
    ke = hist[:, 5]
    positive = ke > 0
    ax_ke.semilogy(t[positive], ke[positive], color="tab:red")
    ax_ke.set_ylabel("kinetic energy (J)")
    ax_ke.set_xlabel("time (s)")
    ax_ke.set_xlim(0.0, float(t[-1]))
    ax_ke.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
