"""Hopper discharge: a conical hopper read from an STL file, filled by a poured stream, emptied.

Run it with ``grainscale hopper --output out/hopper`` (the same as ``python -m
grainscale.examples.hopper_demo``). The hopper — a cylindrical bin on a 30-degree
(half-angle) cone with a 21 mm outlet — is a triangle mesh stored in
``grainscale/examples/data/hopper.stl`` (written by ``hopper_geometry`` / ``--write-stl``) and
read back with ``gs.geometry.Mesh.from_stl``. A sliding gate (a small mesh square) closes the
outlet while a stream of glass beads (d = 3 mm +/- 10 %, uniform) is poured in through a disc
face at the top; once the bed has settled the gate slides away and the hopper discharges into
a collection box below. Hertz–Mindlin (restitution 0.5, friction 0.5) with EPSD rolling
resistance (mu_r = 0.05), Young's modulus reduced to 1e7 Pa.

Written to the output directory:
    particles.pvd + particles_<step>.vtp   particle snapshots every 0.02 s
    particles_walls.pvd + ..._walls_*.vtp  the hopper and the gate (moving while it opens)
    bin.vtp                                the collection box (show it as Wireframe)
    hopper.stl                             the STL the hopper was read from (a copy)
    history.csv                            time, mass in the hopper, discharged mass, kinetic
                                           energy, contacts, vertical load on the hopper wall
    hopper.png                             masses and kinetic energy vs time
    summary.md                             what ran, how fast, the discharge rate
"""

from __future__ import annotations

import argparse
import math
import shutil
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

import grainscale as gs
from grainscale.examples import hopper_report
from grainscale.examples.hopper_geometry import (
    PACKAGED_STL,
    HopperGeometry,
    write_hopper_stl,
)

DEFAULT_PARTICLES = 3500
QUICK_PARTICLES = 600
DEFAULT_DURATION = 1.8  # s
QUICK_DURATION = 0.8  # s
WINDOW = (0.2, 0.7)  # fractions of the hopper inventory for the discharge rate


# ------------------------------------------------------------------------------------------
# the case
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HopperCase:
    """Parameters of the hopper demo (SI units)."""

    particles: int = DEFAULT_PARTICLES
    duration: float = DEFAULT_DURATION  # simulated time, s
    seed: int = 1
    diameter: float = 3e-3  # mean diameter, m
    diameter_spread: float = 0.1  # diameters uniform in diameter * (1 +/- spread)
    density: float = 2500.0  # kg/m^3
    youngs_modulus: float = 1e7  # Pa (reduced from glass's ~6e10 Pa)
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    rolling_friction: float = 0.05
    pour_speed: float = 1.0  # m/s through the top face
    pour_fraction: float = 0.15  # solid fraction of the poured stream
    settle: float = 0.1  # s between the end of the pour (all particles in) and the opening
    gate_speed: float = 1.0  # m/s, sliding in +x
    vtk_every: float = 0.02  # s between particle snapshots
    sample_every: float = 0.005  # s between history samples
    thermo_every: float = 0.1  # s between printed lines

    def __post_init__(self) -> None:
        if isinstance(self.particles, bool) or int(self.particles) != self.particles:
            raise ValueError(f"HopperCase.particles must be an integer, got {self.particles!r}")
        if self.particles < 10:
            raise ValueError(f"HopperCase.particles must be at least 10, got {self.particles}")
        for name in (
            "duration",
            "diameter",
            "pour_speed",
            "pour_fraction",
            "settle",
            "gate_speed",
            "vtk_every",
            "sample_every",
            "thermo_every",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"HopperCase.{name} must be positive, got {value!r}")
        if not 0 <= self.diameter_spread < 1:
            raise ValueError(
                f"HopperCase.diameter_spread must be in [0, 1), got {self.diameter_spread!r}"
            )

    @property
    def radius_distribution(self) -> gs.dist.Uniform:
        r = 0.5 * self.diameter
        return gs.dist.Uniform(r * (1 - self.diameter_spread), r * (1 + self.diameter_spread))

    @property
    def mean_particle_mass(self) -> float:
        a, b = self.radius_distribution.min, self.radius_distribution.max
        r3 = (b**4 - a**4) / (4 * (b - a)) if b > a else a**3
        return self.density * 4.0 / 3.0 * math.pi * r3


@dataclass(frozen=True)
class HopperResult:
    """What a run produced and measured (SI units, paths of the files written)."""

    output: Path
    pvd: Path
    walls_pvd: Path
    plot: Path
    summary: Path
    history: Path
    stl: Path
    inserted: int
    inserted_mass: float  # kg
    inventory: float  # kg in the hopper when the gate opened
    discharged_mass: float  # kg below the outlet at the end
    discharged: int  # particles below the outlet at the end
    open_time: float  # s
    discharge_rate: float  # kg/s (NaN if the 20-70 % window was not covered)
    lost: int
    steps: int
    time_step: float
    wall_clock: float
    particle_steps_per_second: float
    snapshots: int
    summary_text: str


class HopperProbe:
    """Output operation sampling the hopper every ``every`` s (register with sim.output).

    ``rows`` holds (time s, mass in the hopper kg, discharged mass kg, particles in the hopper,
    discharged particles, kinetic energy J, contacts, vertical load on the hopper wall N).
    """

    columns = (
        "time_s",
        "hopper_mass_kg",
        "discharged_mass_kg",
        "hopper_count",
        "discharged_count",
        "kinetic_energy_J",
        "contacts",
        "hopper_wall_load_N",
    )

    def __init__(
        self,
        outlet_z: float,
        hopper_wall: gs.WallHandle,
        every: float,
        print_every: int | None = None,
    ) -> None:
        self.outlet_z = outlet_z
        self.hopper_wall = hopper_wall
        self.every = every
        self.print_every = print_every
        self.rows: list[tuple[float, ...]] = []
        self._last_step: int | None = None
        self._next_time = 0.0

    def next_step(self, step: int, time: float, time_step: float) -> int:
        if self._last_step is None:
            return step
        ahead = math.ceil((self._next_time - time) / time_step - 1e-6)
        return max(step + ahead, self._last_step + 1, step)

    def write(self, sim: gs.Simulation) -> None:
        with sim.particles(writable=False) as p:
            below = p.position[:, 2] < self.outlet_z
            local = np.array([p.mass[below].sum(), p.mass[~below].sum(), np.count_nonzero(below)])
        m_out, m_in, n_out = sim.sum_over_ranks(local)  # this rank's particles, then all
        n_out = int(n_out)
        load = -float(self.hopper_wall.force[2])  # particles push the wall down
        self.rows.append(
            (
                sim.time,
                m_in,
                m_out,
                sim.num_particles - n_out,
                n_out,
                sim.kinetic_energy(),
                sim.num_contacts(),
                load,
            )
        )
        self._last_step = sim.step
        self._next_time = (math.floor(sim.time / self.every + 1e-6) + 1) * self.every
        if self.print_every and (len(self.rows) - 1) % self.print_every == 0 and sim.rank == 0:
            if len(self.rows) == 1:
                tqdm.write(
                    f"{'step':>8} {'time/s':>7} {'in hopper/g':>11} {'discharged/g':>12} "
                    f"{'kinetic_energy/J':>16} {'contacts':>8} {'wall load/N':>11}"
                )
            t, m_in, m_out, _, _, ke, contacts, load = self.rows[-1]
            tqdm.write(
                f"{sim.step:>8d} {t:>7.3f} {m_in * 1e3:>11.2f} {m_out * 1e3:>12.2f} "
                f"{ke:>16.4e} {contacts:>8d} {load:>11.4f}"
            )

    def array(self) -> np.ndarray:
        return np.array(self.rows, dtype=float).reshape(-1, len(self.columns))


def _box_surface(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[(hi if (k >> a) & 1 else lo)[a] for a in range(3)] for k in range(8)])
    quads = [(0, 2, 3, 1), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]  # open top
    triangles = [t for a, b, c, e in quads for t in ((a, b, c), (a, c, e))]
    return corners, np.array(triangles, dtype=np.int64)


def discharge_rate(
    time_: np.ndarray,
    discharged: np.ndarray,
    inventory: float,
    window: tuple[float, float] = WINDOW,
) -> float:
    """Slope (kg/s) of the discharged mass between window[0] and window[1] of ``inventory``."""
    sel = (discharged >= window[0] * inventory) & (discharged <= window[1] * inventory)
    if np.count_nonzero(sel) < 3:
        return math.nan
    return float(np.polyfit(time_[sel], discharged[sel], 1)[0])


@dataclass
class HopperRig:
    """The demo's simulation with what the run needs of it (SI units)."""

    sim: gs.Simulation
    geo: HopperGeometry
    hopper: gs.WallHandle
    gate: gs.WallHandle
    gate_half: float  # half the gate's side, m
    stream: gs.insert.StreamHandle
    pour_rate: float  # kg/s
    pour_time: float  # s
    face_z: float  # height of the pouring face, m
    lo: np.ndarray  # the collection box, m
    hi: np.ndarray


def build(case: HopperCase, stl: Path) -> HopperRig:
    """The hopper read from ``stl``, the collection box under it, the gate and the stream."""
    glass = gs.Material(
        density=case.density,
        youngs_modulus=case.youngs_modulus,
        poisson_ratio=case.poisson_ratio,
        name="glass",
    )
    mesh = gs.geometry.Mesh.from_stl(stl, material=glass)
    geo = HopperGeometry.of(mesh)
    d = case.diameter
    dist = case.radius_distribution
    d_max = 2 * dist.max

    # collection box under the hopper: 2.5 top radii wide, as deep as 1.5 top radii
    half = 1.25 * geo.top_radius
    floor_z = geo.outlet_z - 1.5 * geo.top_radius
    face_z = geo.top_z - 2 * d_max  # the stream's slab lies below the face
    lo = np.array([-half, -half, floor_z])
    hi = np.array([half, half, geo.top_z + d])
    box = gs.Box(lo=tuple(lo), hi=tuple(hi))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(
            restitution=case.restitution,
            friction=case.friction,
            rolling=gs.contact.EPSD(case.rolling_friction, 0.3),
        ),
        time_step=0.2 * gs.timestep.rayleigh_time(glass, dist.min),
        quiet=True,
    )
    hopper = sim.add_wall(mesh)
    for plane in gs.geometry.box_walls(box, material=glass):
        if plane.normal[2] >= 0:  # sides and floor; the top stays open
            sim.add_wall(plane)
    g = geo.outlet_radius + 1.5 * d  # gate: a square of side 2 g, 0.1 d under the outlet
    gate_z = geo.outlet_z - 0.1 * d
    gate = sim.add_wall(
        gs.geometry.Mesh(
            vertices=np.array([(-g, -g, gate_z), (g, -g, gate_z), (g, g, gate_z), (-g, g, gate_z)]),
            triangles=np.array([(0, 1, 2), (0, 2, 3)]),
            material=glass,
        )
    )

    face_radius = geo.top_radius - d_max
    rate = case.pour_fraction * case.density * math.pi * face_radius**2 * case.pour_speed
    pour_time = case.particles * case.mean_particle_mass / rate
    stream = sim.insert(
        gs.insert.Stream(
            gs.insert.DiscFace(centre=(0.0, 0.0, face_z), normal=(0, 0, -1), radius=face_radius),
            mass_rate=rate,
            radius=dist,
            material=glass,
            velocity=(0.0, 0.0, -case.pour_speed),
            seed=case.seed,
            stop=pour_time,
        )
    )
    return HopperRig(sim, geo, hopper, gate, g, stream, rate, pour_time, face_z, lo, hi)


def fill_and_discharge(
    rig: HopperRig, case: HopperCase, vtk: gs.io.VTK, progress: bool | None
) -> tuple[float, float, bool, float]:
    """Fill until every particle is in and has fallen, settle, slide the gate away and run to
    the end; (opening time s, inventory kg, whether it opened, particle-steps run)."""
    sim, geo = rig.sim, rig.geo
    particle_steps = 0.0

    def advance(until: float) -> None:
        nonlocal particle_steps
        n, s0 = sim.num_particles, sim.step
        sim.run(until=min(until, case.duration), progress=progress)
        particle_steps += 0.5 * (n + sim.num_particles) * (sim.step - s0)

    fall = math.sqrt(2 * (rig.face_z - geo.outlet_z) / 9.81)
    advance(rig.pour_time + fall)
    while rig.stream.pending_count > 0 and sim.time < case.duration:
        advance(sim.time + 0.01)
    advance(sim.time + case.settle)
    t_open = sim.time
    with sim.particles(writable=False) as p:
        inventory = float(sim.sum_over_ranks(p.mass[p.position[:, 2] >= geo.outlet_z].sum()))
    travel = 2 * rig.gate_half + case.diameter
    opened = sim.time < case.duration
    if opened:
        rig.gate.set_motion(velocity=(case.gate_speed, 0.0, 0.0))
        advance(t_open + travel / case.gate_speed)
        # an extra snapshot: mesh walls are written while they move, so this records the open
        # gate (the one ParaView then shows for the rest of the run)
        vtk.write(sim)
        rig.gate.set_motion(velocity=(0.0, 0.0, 0.0))
    advance(case.duration)
    return t_open, inventory, opened, particle_steps


def run(
    output: str | Path,
    case: HopperCase | None = None,
    stl: str | Path | None = None,
    progress: bool | None = None,
    verbose: bool = True,
) -> HopperResult:
    """Run the demo, write its files into ``output`` and return what was measured.

    Args:
        output: output directory (created if needed).
        case: the parameters (default ``HopperCase()``).
        stl: hopper STL file (m, outlet at its lowest z, axis along z); None: the packaged
            ``examples/data/hopper.stl`` (written by :func:`write_hopper_stl` if missing).
        progress: progress bar (None: only on an interactive terminal).
        verbose: print the set-up, thermo lines and the summary.
    """
    case = case if case is not None else HopperCase()
    out = Path(output)
    out.mkdir(parents=True, exist_ok=True)
    # Under mpirun every rank runs this; rank 0 prints and writes the files.
    lead = gs.parallel.world_rank() == 0
    say = print if verbose and lead else (lambda *args, **kwargs: None)
    t_start = time.perf_counter()

    if stl is None:
        stl = PACKAGED_STL
        if not stl.is_file() and lead:
            stl = write_hopper_stl(out / "hopper.stl")
    stl = Path(stl)
    if lead and stl.resolve() != (out / "hopper.stl").resolve():
        shutil.copyfile(stl, out / "hopper.stl")
    rig = build(case, stl)
    sim, geo = rig.sim, rig.geo

    vtk = gs.io.VTK(out, every=case.vtk_every)
    sim.output(vtk)
    print_every = max(1, round(case.thermo_every / case.sample_every)) if verbose else None
    probe = HopperProbe(geo.outlet_z, rig.hopper, case.sample_every, print_every)
    sim.output(probe)
    if lead:
        gs.io.write_vtp_mesh(out / "bin.vtp", *_box_surface(rig.lo, rig.hi))
    say(hopper_report.setup_text(case, rig, stl, out))

    t_run0 = time.perf_counter()
    t_open, inventory, opened, particle_steps = fill_and_discharge(rig, case, vtk, progress)
    wall_clock = time.perf_counter() - t_run0

    hist = probe.array()
    if lead:
        np.savetxt(
            out / "history.csv",
            hist,
            delimiter=",",
            header=",".join(HopperProbe.columns),
            comments="",
            fmt=["%.6g", "%.6e", "%.6e", "%d", "%d", "%.6e", "%d", "%.6e"],
        )
    after = hist[:, 0] >= t_open
    w = discharge_rate(hist[after, 0], hist[after, 2], inventory) if opened else math.nan
    plot = out / "hopper.png"
    if lead:
        hopper_report.plot(plot, hist, case, t_open if opened else None, inventory, w)

    status = rig.stream.status()
    with sim.particles(writable=False) as p:
        below = p.position[:, 2] < geo.outlet_z
        local = np.array([p.mass[below].sum(), np.count_nonzero(below)])
    m_out, n_out = sim.sum_over_ranks(local)
    result: dict[str, Any] = dict(
        output=out,
        pvd=vtk.pvd.path,
        walls_pvd=out / "particles_walls.pvd",
        plot=plot,
        summary=out / "summary.md",
        history=out / "history.csv",
        stl=out / "hopper.stl",
        inserted=int(status["inserted_count"]),
        inserted_mass=float(status["inserted_mass"]),
        inventory=inventory,
        discharged_mass=float(m_out),
        discharged=int(n_out),
        open_time=t_open,
        discharge_rate=w,
        lost=sim.lost_particles,
        steps=sim.step,
        time_step=sim.time_step,
        wall_clock=wall_clock,
        particle_steps_per_second=particle_steps / wall_clock if wall_clock > 0 else math.nan,
        snapshots=len(vtk.files),
    )
    text = hopper_report.summary(case, geo, stl, result, sim, time.perf_counter() - t_start)
    if lead:
        (out / "summary.md").write_text(text)
    say("")
    say(text, end="")
    say(f"Output directory: {out.resolve()}")
    return HopperResult(summary_text=text, **result)


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--output", default="out/hopper", help="output directory (default: %(default)s)"
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
        "--stl", default=None, help="hopper STL (m; default: the packaged examples/data/hopper.stl)"
    )
    parser.add_argument(
        "--write-stl",
        default=None,
        metavar="PATH",
        help="only write the default hopper STL to PATH and exit",
    )
    parser.add_argument(
        "--quick", action="store_true", help="a small case that runs in a few seconds"
    )
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar even on a terminal"
    )


def case_from_args(args: argparse.Namespace) -> HopperCase:
    quick = bool(args.quick)
    particles = args.particles
    if particles is None:
        particles = QUICK_PARTICLES if quick else DEFAULT_PARTICLES
    duration = args.duration
    if duration is None:
        duration = QUICK_DURATION if quick else DEFAULT_DURATION
    extra = {"vtk_every": 0.05} if quick else {}
    return HopperCase(particles=particles, duration=duration, seed=args.seed, **extra)


DESCRIPTION = "Fill a conical hopper (read from an STL file) and discharge it (grainscale hopper)."


def run_from_args(args: argparse.Namespace) -> HopperResult | None:
    """What the parsed options (see :func:`add_arguments`) ask for: write the STL and stop
    (``--write-stl``, None), or run the demo. Raises ValueError for a bad case."""
    if args.write_stl:
        print(write_hopper_stl(args.write_stl))
        return None
    progress = False if args.no_progress else None
    return run(args.output, case_from_args(args), stl=args.stl, progress=progress)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.hopper_demo", description=DESCRIPTION
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
