"""Pour and settle: glass beads fall into a closed box and come to rest as a packed bed.

Run it with ``python -m grainscale.examples.pour_and_settle --output out/settle``. By default
8000 spheres (d = 2 mm +/- 10 %, uniform) are placed at random, without overlaps, in the upper
part of a closed box, fall under gravity and settle on the floor. Particles and the six walls
share one glass-like material with a reduced Young's modulus (E = 1e7 Pa, as is usual in DEM to
allow a larger time step) and one Hertz–Mindlin law (restitution 0.5, friction 0.5).

It shows the API in the order a case is built: material, domain, contact law, time step,
particles, walls, output operations (VTK snapshots and a user probe), run. Written to the output
directory:

    particles.pvd + particles_<step>.vtp  particle snapshots every 0.01 s (open the .pvd in
                                          ParaView, Glyph: Sphere, scale by radius, factor 2)
    box.vtp                               the container (show it as Outline or Wireframe)
    history.csv                           time, kinetic energy, contacts, bed height, packing

Packing fraction (solid fraction of the bed): phi = V_p / (A H), with V_p the total particle
volume, A the box cross-section and H the bed height, the mean over a grid of columns of width
about one mean diameter of the highest sphere top (z + r) in each column.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs

DEFAULT_PARTICLES = 8000
DEFAULT_DURATION = 0.5  # s
QUICK_PARTICLES = 400
QUICK_DURATION = 0.2  # s
HISTORY_COLUMNS = "time_s,kinetic_energy_J,contacts,bed_height_m,packing_fraction"


@dataclass(frozen=True)
class DemoCase:
    """Parameters of the pour-and-settle case (SI units)."""

    particles: int = DEFAULT_PARTICLES
    duration: float = DEFAULT_DURATION  # simulated time, s
    seed: int = 1
    diameter: float = 2e-3  # mean diameter, m; diameters uniform in diameter * (1 +/- 0.1)
    density: float = 2500.0  # kg/m^3
    youngs_modulus: float = 1e7  # Pa (reduced from glass's ~6e10 Pa)
    sample_every: float = 0.0025  # s between history samples

    def __post_init__(self) -> None:
        # the material, the particles and the run validate the rest
        n = self.particles
        if isinstance(n, bool) or not isinstance(n, int) or n < 10:
            raise ValueError(f"DemoCase.particles must be an integer of at least 10, got {n!r}")
        if not (math.isfinite(self.duration) and self.duration > 0):
            raise ValueError(f"DemoCase.duration must be positive (s), got {self.duration!r}")


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
    """A user output operation: records the bed every ``every`` s of simulated time.

    Any object with ``next_step(step, time, time_step) -> int`` (the next step it wants) and
    ``write(sim)`` can be registered with ``sim.output``. After the run ``rows`` holds one
    (time s, kinetic energy J, contacts, bed height m, packing fraction) per sample.
    """

    def __init__(self, box: gs.Box, column: float, total_volume: float, every: float) -> None:
        self.box, self.column, self.total_volume, self.every = box, column, total_volume, every
        self.rows: list[tuple[float, float, int, float, float]] = []

    def next_step(self, step: int, time: float, time_step: float) -> int:
        next_time = len(self.rows) * self.every
        return max(step, math.ceil((next_time - time) / time_step - 1e-6) + step)

    def write(self, sim: gs.Simulation) -> None:
        with sim.particles(writable=False) as p:
            h = bed_height(p.position, p.radius, self.box, self.column)
        phi = packing_fraction(self.total_volume, self.box, h)
        self.rows.append((sim.time, sim.kinetic_energy(), sim.num_contacts(), h, phi))


def container(case: DemoCase, total_volume: float) -> tuple[gs.Box, gs.Box]:
    """The closed box (side about the settled bed's height, at least 8 diameters) and the fill
    region in its upper part, holding the particles at a solid fraction of about 0.25 (m)."""
    d = case.diameter
    side = max(8 * d, math.ceil((total_volume / 0.6) ** (1 / 3) / d) * d)
    fill_bottom = 0.5 * side
    top = fill_bottom + max(total_volume / (0.25 * side * side), 4 * d)
    return gs.Box(lo=(0, 0, 0), hi=(side, side, top)), gs.Box(
        lo=(0, 0, fill_bottom), hi=(side, side, top)
    )


def run(
    output: str | Path, case: DemoCase | None = None, progress: bool | None = None
) -> dict[str, Any]:
    """Run the case, write its files into ``output`` (created if needed) and return what was
    measured: ``bed_height`` (m), ``packing_fraction``, ``kinetic_energy`` (J, peak and final),
    ``steps``, ``time_step`` (s), ``pvd`` and ``history`` (paths). ``progress``: a progress bar
    (None: only on an interactive terminal)."""
    case = case if case is not None else DemoCase()
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)

    rng = np.random.default_rng(case.seed)
    radius = 0.5 * case.diameter * rng.uniform(0.9, 1.1, case.particles)
    total_volume = float(np.sum(4.0 / 3.0 * math.pi * radius**3))
    box, fill = container(case, total_volume)

    glass = gs.Material(
        density=case.density, youngs_modulus=case.youngs_modulus, poisson_ratio=0.3, name="glass"
    )
    dt = 0.2 * gs.timestep.rayleigh_time(glass, float(radius.min()))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        gravity=(0.0, 0.0, -9.81),
        time_step=dt,
    )
    position = gs.insert.random_in_box(fill, radius, seed=case.seed)
    sim.add_particles(position=position, radius=radius, material=glass)
    for wall in gs.geometry.box_walls(box, material=glass):
        sim.add_wall(wall)

    vtk = gs.io.VTK(out, every=0.01)
    sim.output(vtk)
    probe = BedProbe(box, case.diameter, total_volume, case.sample_every)
    sim.output(probe)
    lo, hi = np.asarray(box.lo), np.asarray(box.hi)
    corners = np.array([[(hi if (k >> a) & 1 else lo)[a] for a in range(3)] for k in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = np.array([t for a, b, c, e in quads for t in ((a, b, c), (a, c, e))])
    gs.io.write_vtp_mesh(out / "box.vtp", corners, triangles)

    print(f"pour and settle: {case.particles} spheres in a {box.length[0] * 1e3:.0f} mm box")
    sim.run(until=case.duration, progress=progress)

    hist = np.array(probe.rows, dtype=float).reshape(-1, 5)
    np.savetxt(
        out / "history.csv",
        hist,
        delimiter=",",
        header=HISTORY_COLUMNS,
        comments="",
        fmt=["%.6g", "%.6e", "%d", "%.6e", "%.5f"],
    )
    result: dict[str, Any] = dict(
        bed_height=float(hist[-1, 3]),
        packing_fraction=float(hist[-1, 4]),
        peak_kinetic_energy=float(hist[:, 1].max()),
        final_kinetic_energy=sim.kinetic_energy(),
        steps=sim.step,
        time_step=dt,
        lost=sim.lost_particles,
        pvd=vtk.pvd.path,
        history=out / "history.csv",
    )
    print(
        f"settled bed: height {result['bed_height'] * 1e3:.1f} mm, packing fraction "
        f"{result['packing_fraction']:.3f}; kinetic energy {result['final_kinetic_energy']:.3g} J "
        f"(peak {result['peak_kinetic_energy']:.3g} J); ParaView: {result['pvd']}"
    )
    return result


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.pour_and_settle",
        description="Glass beads poured into a closed box settle into a bed.",
    )
    parser.add_argument("--output", default="out/settle", help="output directory")
    parser.add_argument("--particles", type=int, default=None, help="number of spheres")
    parser.add_argument("--duration", type=float, default=None, help="simulated time, s")
    parser.add_argument("--seed", type=int, default=1, help="random seed")
    parser.add_argument("--quick", action="store_true", help="a small case of a few seconds")
    args = parser.parse_args(argv)
    quick = (
        (QUICK_PARTICLES, QUICK_DURATION) if args.quick else (DEFAULT_PARTICLES, DEFAULT_DURATION)
    )
    try:
        case = DemoCase(
            particles=quick[0] if args.particles is None else args.particles,
            duration=quick[1] if args.duration is None else args.duration,
            seed=args.seed,
        )
    except ValueError as err:
        parser.error(str(err))
    run(args.output, case)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
