"""Pour and settle: glass beads fall into a closed box and come to rest as a packed bed.

Run it with ``python -m grainscale.examples.pour_and_settle --output out/demo`` (``make demo``,
``grainscale demo``). By default 8000 spheres (d = 2 mm +/- 10 %, uniform) are placed at random,
without overlaps, in the upper part of a closed box, fall under gravity and settle on the floor.
Particles and the six walls share one glass-like material with a reduced Young's modulus
(E = 1e7 Pa, as is usual in DEM to allow a larger time step) and one Hertz–Mindlin law
(restitution 0.5, friction 0.5).

Written to the output directory:
    particles.pvd + particles_<step>.vtp  particle snapshots every 0.01 s (open the .pvd in
                                          ParaView, Glyph: Sphere, scale by radius, factor 2)
    box.vtp                               the container (show it as Outline or Wireframe)
    history.csv                           time, kinetic energy, contacts, bed height, packing
    settle.png                            kinetic energy (log) and packing fraction vs time
    summary.md                            what ran, how fast, how it settled

Packing fraction (solid fraction of the bed): phi = V_p / (A H), with V_p the total particle
volume, A the box cross-section and H the bed height, the mean over a grid of columns of width
about one mean diameter of the highest sphere top (z + r) in each column. While particles are
still falling H is the top of the falling cloud, so phi starts low and rises to the packing
fraction of the settled bed.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

import grainscale as gs

DEFAULT_PARTICLES = 8000
DEFAULT_DURATION = 0.5  # s
QUICK_PARTICLES = 400
QUICK_DURATION = 0.2  # s


@dataclass(frozen=True)
class DemoCase:
    """Parameters of the pour-and-settle case (SI units).

    The box is sized from the particle count: a square cross-section whose side is about the
    height of the settled bed (at least 8 diameters), and a fill region above 0.5 side lengths
    holding the particles at a solid fraction of about 0.25.
    """

    particles: int = DEFAULT_PARTICLES
    duration: float = DEFAULT_DURATION  # simulated time, s
    seed: int = 1
    diameter: float = 2e-3  # mean diameter, m
    diameter_spread: float = 0.1  # diameters uniform in diameter * (1 +/- spread)
    density: float = 2500.0  # kg/m^3
    youngs_modulus: float = 1e7  # Pa (reduced from glass's ~6e10 Pa)
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    vtk_every: float = 0.01  # s between particle snapshots
    sample_every: float = 0.0025  # s between history samples
    thermo_every: float = 0.025  # s between thermo lines

    def __post_init__(self) -> None:
        if isinstance(self.particles, bool) or int(self.particles) != self.particles:
            raise ValueError(f"DemoCase.particles must be an integer, got {self.particles!r}")
        if self.particles < 10:
            raise ValueError(f"DemoCase.particles must be at least 10, got {self.particles}")
        for name in ("duration", "diameter", "vtk_every", "sample_every", "thermo_every"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"DemoCase.{name} must be positive, got {value!r}")
        if not 0 <= self.diameter_spread < 1:
            raise ValueError(
                f"DemoCase.diameter_spread must be in [0, 1), got {self.diameter_spread!r}"
            )


@dataclass(frozen=True)
class DemoResult:
    """What a run produced and measured (SI units, paths to the files written)."""

    output: Path
    pvd: Path
    plot: Path
    summary: Path
    history: Path
    particles: int
    steps: int
    time_step: float  # s
    wall_clock: float  # s spent in Simulation.run
    particle_steps_per_second: float
    peak_kinetic_energy: float  # J
    peak_time: float  # s
    final_kinetic_energy: float  # J
    bed_height: float  # m
    packing_fraction: float
    snapshots: int
    summary_text: str


# ------------------------------------------------------------------------------------------
# bed measurements
# ------------------------------------------------------------------------------------------


def bed_height(position: np.ndarray, radius: np.ndarray, box: gs.Box, column: float) -> float:
    """Bed height above the floor (m): mean over columns of the highest sphere top (z + r).

    The cross-section of ``box`` is split into square-ish columns of width about ``column``
    (m); a sphere belongs to the column holding its centre; an empty column counts as zero.
    """
    lo = np.asarray(box.lo)
    length = box.length
    nx, ny = (max(1, int(length[a] / column + 1e-9)) for a in (0, 1))
    ix = np.clip(((position[:, 0] - lo[0]) / length[0] * nx).astype(int), 0, nx - 1)
    iy = np.clip(((position[:, 1] - lo[1]) / length[1] * ny).astype(int), 0, ny - 1)
    top = np.zeros(nx * ny)
    np.maximum.at(top, ix * ny + iy, position[:, 2] + radius - lo[2])
    return float(top.mean())


def packing_fraction(total_volume: float, box: gs.Box, height: float) -> float:
    """Solid fraction V_p / (A H) of a bed of height ``height`` (m) in ``box``."""
    area = float(box.length[0] * box.length[1])
    return total_volume / (area * height) if height > 0 else math.nan


class BedProbe:
    """Output operation recording the bed every ``every`` s of simulated time.

    Register with ``sim.output(probe)``; after the run ``probe.rows`` holds one tuple
    (time s, kinetic energy J, contacts, bed height m, packing fraction) per sample. With
    ``print_every`` = k it also prints a thermo line every k samples, through ``tqdm.write`` so
    that the lines and the progress bar do not overwrite each other.
    """

    columns = ("time", "kinetic_energy", "contacts", "bed_height", "packing_fraction")

    def __init__(
        self,
        box: gs.Box,
        column: float,
        total_volume: float,
        every: float,
        print_every: int | None = None,
    ) -> None:
        self.box = box
        self.column = column
        self.total_volume = total_volume
        self.every = every
        self.print_every = print_every
        self.rows: list[tuple[float, float, int, float, float]] = []
        self._last_step: int | None = None
        self._next_time = 0.0
        self._clock: tuple[float, int] | None = None  # (wall-clock, step) of the last line

    def next_step(self, step: int, time: float, time_step: float) -> int:
        if self._last_step is None:
            return step
        ahead = math.ceil((self._next_time - time) / time_step - 1e-6)
        return max(step + ahead, self._last_step + 1, step)

    def write(self, sim: gs.Simulation) -> None:
        with sim.particles(writable=False) as p:
            h = bed_height(p.position, p.radius, self.box, self.column)
        phi = packing_fraction(self.total_volume, self.box, h)
        self.rows.append((sim.time, sim.kinetic_energy(), sim.num_contacts(), h, phi))
        self._last_step = sim.step
        self._next_time = (math.floor(sim.time / self.every + 1e-6) + 1) * self.every
        if self.print_every and (len(self.rows) - 1) % self.print_every == 0:
            self._print_line(sim)

    def _print_line(self, sim: gs.Simulation) -> None:
        now = time.perf_counter()
        if self._clock is None:
            tqdm.write(
                f"{'step':>8} {'time/s':>8} {'kinetic_energy/J':>16} {'contacts':>8} "
                f"{'max_overlap/r':>13} {'bed_height/mm':>13} {'phi':>6} "
                f"{'particle_steps/s':>16}"
            )
            rate = "-"
        else:
            t0, s0 = self._clock
            rate = f"{(sim.step - s0) * sim.num_particles / (now - t0):.3g}" if now > t0 else "-"
        self._clock = (now, sim.step)
        t, ke, contacts, h, phi = self.rows[-1]
        overlap = float(sim.thermo()["max_overlap_ratio"])
        tqdm.write(
            f"{sim.step:>8d} {t:>8.4f} {ke:>16.4e} {contacts:>8d} {overlap:>13.2e} "
            f"{h * 1e3:>13.2f} {phi:>6.3f} {rate:>16}"
        )

    def array(self) -> np.ndarray:
        """(samples, 5) array of the rows."""
        return np.array(self.rows, dtype=float).reshape(-1, len(self.columns))


# ------------------------------------------------------------------------------------------
# the case
# ------------------------------------------------------------------------------------------


def _container(case: DemoCase, total_volume: float) -> tuple[gs.Box, gs.Box]:
    """The closed box and the fill region in its upper part (both m)."""
    d = case.diameter
    side = max(8 * d, math.ceil((total_volume / 0.6) ** (1 / 3) / d) * d)
    area = side * side
    fill_bottom = 0.5 * side
    fill_height = max(total_volume / (0.25 * area), 4 * d)
    top = fill_bottom + fill_height
    box = gs.Box(lo=(0.0, 0.0, 0.0), hi=(side, side, top))
    fill = gs.Box(lo=(0.0, 0.0, fill_bottom), hi=(side, side, top))
    return box, fill


def _write_box(path: Path, box: gs.Box) -> None:
    """The box surface as 12 triangles (ParaView: show as Outline or Wireframe)."""
    lo, hi = np.asarray(box.lo), np.asarray(box.hi)
    corners = np.array([[(hi if (k >> a) & 1 else lo)[a] for a in range(3)] for k in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = [t for a, b, c, e in quads for t in ((a, b, c), (a, c, e))]
    gs.io.write_vtp_mesh(path, corners, np.array(triangles, dtype=np.int64))


def run(
    output: str | Path,
    case: DemoCase | None = None,
    progress: bool | None = None,
    verbose: bool = True,
) -> DemoResult:
    """Run the case, write its files into ``output`` and return what was measured.

    Args:
        output: output directory (created if needed).
        case: the parameters (default ``DemoCase()``).
        progress: progress bar (None: only on an interactive terminal).
        verbose: print the set-up, thermo lines and the summary.
    """
    case = case if case is not None else DemoCase()
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    say = print if verbose else (lambda *args, **kwargs: None)
    t_start = time.perf_counter()

    rng = np.random.default_rng(case.seed)
    d_lo = case.diameter * (1 - case.diameter_spread)
    d_hi = case.diameter * (1 + case.diameter_spread)
    radius = 0.5 * rng.uniform(d_lo, d_hi, case.particles)
    total_volume = float(np.sum(4.0 / 3.0 * math.pi * radius**3))
    box, fill = _container(case, total_volume)
    position = gs.insert.random_in_box(fill, radius, seed=case.seed)

    glass = gs.Material(
        density=case.density,
        youngs_modulus=case.youngs_modulus,
        poisson_ratio=case.poisson_ratio,
        name="glass",
    )
    dt = 0.2 * gs.timestep.rayleigh_time(glass, float(radius.min()))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=case.restitution, friction=case.friction),
        gravity=(0.0, 0.0, -9.81),
        time_step=dt,
        quiet=True,  # thermo lines come from the probe (with the bed's packing fraction)
    )
    sim.add_particles(position=position, radius=radius, material=glass)
    for wall in gs.geometry.box_walls(box, material=glass):
        sim.add_wall(wall)

    vtk = gs.io.VTK(out, every=case.vtk_every)
    sim.output(vtk)
    print_every = max(1, round(case.thermo_every / case.sample_every)) if verbose else None
    probe = BedProbe(box, case.diameter, total_volume, case.sample_every, print_every)
    sim.output(probe)
    _write_box(out / "box.vtp", box)

    mm = 1e3
    steps = math.ceil(case.duration / dt * (1 - 1e-12))
    say(
        f"grainscale pour-and-settle demo: {case.particles} spheres, d = {case.diameter * mm:g} mm"
        f" +/- {case.diameter_spread:.0%} (uniform), E = {case.youngs_modulus:g} Pa, "
        f"e = {case.restitution:g}, mu = {case.friction:g}"
    )
    say(
        f"box {box.length[0] * mm:.0f} x {box.length[1] * mm:.0f} x {box.length[2] * mm:.0f} mm, "
        f"filled above z = {fill.lo[2] * mm:.0f} mm; {case.duration:g} s = {steps} steps of "
        f"{dt:.3e} s; output in {out}"
    )
    t0 = time.perf_counter()
    sim.run(until=case.duration, progress=progress)
    wall_clock = time.perf_counter() - t0

    hist = probe.array()
    np.savetxt(
        out / "history.csv",
        hist,
        delimiter=",",
        header="time_s,kinetic_energy_J,contacts,bed_height_m,packing_fraction",
        comments="",
        fmt=["%.6g", "%.6e", "%d", "%.6e", "%.5f"],
    )
    plot = out / "settle.png"
    _plot(plot, hist, case)

    k_peak = int(np.argmax(hist[:, 1]))
    ke_final = sim.kinetic_energy()
    with sim.particles(writable=False) as p:
        h_final = bed_height(p.position, p.radius, box, case.diameter)
    phi_final = packing_fraction(total_volume, box, h_final)
    rate = case.particles * sim.step / wall_clock
    result_fields: dict[str, Any] = dict(
        output=out,
        pvd=vtk.pvd.path,
        plot=plot,
        summary=out / "summary.md",
        history=out / "history.csv",
        particles=sim.num_particles,
        steps=sim.step,
        time_step=dt,
        wall_clock=wall_clock,
        particle_steps_per_second=rate,
        peak_kinetic_energy=float(hist[k_peak, 1]),
        peak_time=float(hist[k_peak, 0]),
        final_kinetic_energy=ke_final,
        bed_height=h_final,
        packing_fraction=phi_final,
        snapshots=len(vtk.files),
    )
    text = _summary(case, box, result_fields, sim, time.perf_counter() - t_start)
    (out / "summary.md").write_text(text)
    say("")
    say(text, end="")
    say(f"Output directory: {out.resolve()}")
    return DemoResult(summary_text=text, **result_fields)


def _summary(
    case: DemoCase, box: gs.Box, r: dict[str, Any], sim: gs.Simulation, total: float
) -> str:
    mm = 1e3
    length = box.length * mm
    decay = r["final_kinetic_energy"] / r["peak_kinetic_energy"]
    lines = [
        "# grainscale demo: pour and settle",
        "",
        f"- particles: {r['particles']} spheres, d = {case.diameter * mm:g} mm "
        f"+/- {case.diameter_spread:.0%} (uniform), density {case.density:g} kg/m^3, "
        f"E = {case.youngs_modulus:g} Pa, nu = {case.poisson_ratio:g} (lost: "
        f"{sim.lost_particles})",
        f"- contact law: Hertz–Mindlin, restitution {case.restitution:g}, friction "
        f"{case.friction:g}, particles and the six walls of the same material",
        f"- box: {length[0]:.0f} x {length[1]:.0f} x {length[2]:.0f} mm, closed",
        f"- simulated: {sim.time:.4g} s in {r['steps']} steps, time step {r['time_step']:.4e} s "
        "(0.2 x Rayleigh time of the smallest sphere)",
        f"- wall-clock: {r['wall_clock']:.1f} s in Simulation.run ({total:.1f} s with set-up "
        "and output)",
        f"- throughput: {r['particle_steps_per_second']:.3g} particle-steps/s",
        f"- kinetic energy: peak {r['peak_kinetic_energy']:.3g} J at t = {r['peak_time']:.3g} s, "
        f"final {r['final_kinetic_energy']:.3g} J ({decay:.1e} of the peak)",
        f"- settled bed: height {r['bed_height'] * mm:.1f} mm, packing fraction "
        f"{r['packing_fraction']:.3f}",
        f"- contacts at the end: {sim.num_contacts()} (max overlap "
        f"{sim.thermo()['max_overlap_ratio']:.2%} of a radius)",
        f"- ParaView: {r['pvd']} ({r['snapshots']} snapshots), container: "
        f"{r['output'] / 'box.vtp'}",
        f"- plot: {r['plot']}; time series: {r['history']}",
        "",
        "Packing fraction = total particle volume / (box cross-section x bed height); bed height",
        "= mean over columns about one diameter wide of the highest sphere top (z + r).",
        "",
    ]
    return "\n".join(lines)


def _plot(path: Path, hist: np.ndarray, case: DemoCase) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, ke, phi = hist[:, 0], hist[:, 1], hist[:, 4]
    fig, (ax_ke, ax_phi) = plt.subplots(2, 1, sharex=True, figsize=(7.0, 6.0), dpi=150)
    fig.suptitle(
        f"Pour and settle: {case.particles} spheres, d = {case.diameter * 1e3:g} mm "
        f"± {case.diameter_spread:.0%}, e = {case.restitution:g}, μ = {case.friction:g}"
    )
    positive = ke > 0
    ax_ke.semilogy(t[positive], ke[positive], color="tab:red")
    k = int(np.argmax(ke))
    ax_ke.plot([t[k], t[-1]], [ke[k], ke[-1]], "o", color="tab:red", markersize=4)
    ax_ke.text(
        0.98,
        0.95,
        f"peak {ke[k]:.3g} J at t = {t[k]:.3g} s\n"
        f"final {ke[-1]:.2g} J ({ke[-1] / ke[k]:.0e} of peak)",
        transform=ax_ke.transAxes,
        ha="right",
        va="top",
        fontsize=9,
        bbox={"boxstyle": "round", "facecolor": "white", "edgecolor": "0.8"},
    )
    ax_ke.set_ylabel("kinetic energy (J)")
    ax_ke.grid(True, which="major", alpha=0.3)

    ax_phi.plot(t, phi, color="tab:blue")
    ax_phi.axhline(phi[-1], color="tab:blue", linestyle=":", linewidth=1)
    ax_phi.annotate(
        f"settled bed: φ = {phi[-1]:.3f}",
        (t[-1], phi[-1]),
        textcoords="offset points",
        xytext=(-4, -14),
        ha="right",
    )
    ax_phi.set_ylim(0.0, max(0.7, float(np.nanmax(phi)) + 0.05))
    ax_phi.set_ylabel("packing fraction φ")
    ax_phi.set_xlabel("time (s)")
    ax_phi.set_xlim(0.0, float(t[-1]))
    ax_phi.grid(True, alpha=0.3)
    ax_phi.text(
        0.02,
        0.05,
        "φ = particle volume / (cross-section × bed height),\n"
        "bed height = mean highest sphere top per column",
        transform=ax_phi.transAxes,
        fontsize=8,
        color="0.3",
    )
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The demo's options (shared with ``grainscale demo``)."""
    parser.add_argument(
        "--output", default="out/demo", help="output directory (default: %(default)s)"
    )
    parser.add_argument(
        "--particles",
        type=int,
        default=None,
        help=f"number of spheres (default {DEFAULT_PARTICLES}, {QUICK_PARTICLES} with --quick)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help=f"simulated time in s (default {DEFAULT_DURATION}, {QUICK_DURATION} with --quick)",
    )
    parser.add_argument("--seed", type=int, default=1, help="random seed (default: %(default)s)")
    parser.add_argument(
        "--quick", action="store_true", help="a small case that runs in a few seconds"
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar even on a terminal"
    )


def case_from_args(args: argparse.Namespace) -> DemoCase:
    """The DemoCase the parsed options describe."""
    quick = bool(args.quick)
    particles = args.particles
    if particles is None:
        particles = QUICK_PARTICLES if quick else DEFAULT_PARTICLES
    duration = args.duration
    if duration is None:
        duration = QUICK_DURATION if quick else DEFAULT_DURATION
    extra = {"vtk_every": 0.02} if quick else {}
    return DemoCase(particles=particles, duration=duration, seed=args.seed, **extra)


def run_from_args(args: argparse.Namespace) -> DemoResult:
    """Run the demo described by parsed options (see :func:`add_arguments`)."""
    return run(args.output, case_from_args(args), progress=False if args.no_progress else None)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.pour_and_settle",
        description="Pour glass beads into a closed box and let them settle (grainscale demo).",
    )
    add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        run_from_args(args)
    except ValueError as err:
        parser.error(str(err))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
