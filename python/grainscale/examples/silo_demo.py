"""The demo: a silo whose orifice jams coarse graining, run as pure coarse graining and as a
multi-level hierarchy with a resolved region at the orifice, against a resolved reference.

Run it with ``grainscale demo --output out/demo`` (``make demo``; the same as ``python -m
grainscale.examples.silo_demo``). A 48 x 48 mm flat-bottomed silo with a square orifice of
D0 = 12 mm is filled with 120 g of glass-like spheres (d = 2 mm +/- 5 %, uniform) poured
through its top, the bed settles, a shutter under the orifice slides away and the silo
discharges for 0.8 s. The orifice is 6 particle diameters wide, but only 3 parcels of a
coarse-grained model with h = 2 (parcels twice the size, ``grainscale.scaling`` scheme "cg"):

* **pure CG, h = 2**: an arch of parcels forms over the orifice and the silo stops (grains
  arch over orifices of a few diameters; clogging practically vanishes only above about 5 for
  spheres: Zuriguel et al., Phys. Rev. E 71 (2005) 051303; in studies/silo_cg parcels at
  D0 / (h d) = 3 clogged in 5 runs of 5);
* **MLCG 2 -> 1**: a ``gs.Hierarchy`` of h = 2 everywhere and the resolved particles (h = 1)
  in a box 3 D0 wide and 2 D0 high around the orifice (``gs.Level(cg=1, region=...)``);
  the coarse level follows the fine level's discharge and holds the inventory;
* **resolved** (h = 1 everywhere): the reference, read from the package data
  ``examples/data/silo_reference.json`` (six seeds of studies/mlcg_jam, with its provenance)
  or run live with ``--full``.

It prints, per run, the discharge rate W (the slope of the discharged mass from 0.08 s after
opening), its error against the reference, the particle counts (per level for the hierarchy),
wall-clock and CPU time, the speed-up of the hierarchy over the resolved run, and the
hierarchy's books of the material (``Hierarchy.mass_balance``). Written to the output
directory: ``discharge.png`` (discharged mass against time for the three runs), ``levels.png``
(the section by the vertical plane through the orifice, at the opening and at the end,
particles coloured by level),
``level0.pvd``/``level1.pvd`` (every level's snapshots with a ``level`` point field),
``levels.pvd`` (the material as the hierarchy represents it: each level where it is the
finest, with ``level``), ``cells0.pvd`` (the exchange cells' fields), ``summary.txt`` and
``summary.json``. ``--quick``: a shallower bed and a 0.3 s discharge (about 20 s of CPU; the
tests). The report is in :mod:`grainscale.examples.silo_demo_report`.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import math
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs
from grainscale.examples import silo_demo_report as report
from grainscale.examples import silo_reference

SAMPLE = 0.01  # s between samples of the discharged mass
SHUTTER_SPEED = 2.0  # m/s; the shutter (a rectangle under the orifice) slides for SHUTTER_TIME
SHUTTER_TIME = 0.03  # s
VTK_EVERY = 0.05  # s between snapshots of the hierarchy


@dataclass(frozen=True)
class SiloCase:
    """The silo, its particles and the hierarchy (SI units). The defaults are the case of
    studies/mlcg_jam (``JAM``), whose resolved runs are the shipped reference."""

    width: float = 0.048  # the silo is width x width (m)
    orifice: float = 0.012  # D0: square orifice D0 x D0 in the middle of the floor (m)
    height: float = 0.08  # the pour face is at this height, the domain's top 10 mm above (m)
    below: float = 0.02  # the domain reaches this far below the floor (m)
    diameter: float = 2e-3  # resolved particle diameter d (m)
    spread: float = 0.05  # diameters uniform in d (1 +/- spread)
    density: float = 2500.0  # kg/m^3
    youngs_modulus: float = 1e7  # Pa (reduced, as is usual in DEM)
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    fill_mass: float = 0.12  # kg poured
    fill_rate: float = 0.6  # kg/s
    pour_speed: float = 2.0  # m/s downwards through the pour face
    settle: float = 0.2  # s between the end of the pour and the opening
    discharge: float = 0.8  # s after the shutter starts to open
    transient: float = 0.08  # s after opening before W is measured
    region_width: float = 3.0  # the resolved region: region_width x D0 wide,
    region_top: float = 2.0  # from below the floor to region_top x D0 above it
    coarse: float = 2.0  # h of the coarse level (and of the pure CG run)
    exchange_every: float = 5e-4  # s between exchanges of the hierarchy
    seed: int = 1

    def __post_init__(self) -> None:
        for name in ("width", "orifice", "height", "diameter", "fill_mass", "discharge"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"SiloCase.{name} must be positive, got {value!r}")
        if self.orifice >= self.width:
            raise ValueError(f"SiloCase.orifice must be below the width, got {self.orifice!r}")
        if not 0 <= self.transient < self.discharge:
            raise ValueError(
                f"SiloCase.transient must be in [0, discharge), got {self.transient!r}"
            )

    @property
    def open_time(self) -> float:
        """When the shutter starts to slide away (s)."""
        return self.fill_mass / self.fill_rate + self.settle

    @property
    def end_time(self) -> float:
        """End of the run (s)."""
        return self.open_time + self.discharge

    @property
    def material(self) -> gs.Material:
        """The spheres' (and the walls') material."""
        return gs.Material(
            density=self.density,
            youngs_modulus=self.youngs_modulus,
            poisson_ratio=self.poisson_ratio,
            name="glass",
        )

    def comparable(self) -> dict[str, Any]:
        """The fields a resolved reference must match: all but the seed and the hierarchy's."""
        d = dataclasses.asdict(self)
        for name in ("seed", "region_width", "region_top", "coarse", "exchange_every"):
            d.pop(name)
        return d


JAM = SiloCase()
# A shallower bed (90 g) and a 0.3 s discharge; its region is smaller so that its top stays
# below the bed (the reduced test of studies/mlcg_jam).
QUICK = dataclasses.replace(
    JAM,
    fill_mass=0.09,
    settle=0.15,
    discharge=0.3,
    transient=0.06,
    region_width=2.5,
    region_top=1.25,
)
SHUTTER = 8  # index of the shutter among the walls of reference_parameters()


def reference_parameters(case: SiloCase) -> gs.scaling.ParameterSet:
    """The resolved system (h = 1) as a parameter set: the silo's walls (four side planes, the
    floor as four rectangles around the orifice, the shutter just below it, wall SHUTTER), the
    pour stream through a face at the top and an outlet below the floor."""
    glass = case.material
    w, d0 = case.width, case.orifice
    lo, hi = 0.5 * (w - d0), 0.5 * (w + d0)
    rect = gs.Rectangle
    walls: list[Any] = [
        gs.Plane(point=(0, 0, 0), normal=(1, 0, 0), material=glass),
        gs.Plane(point=(w, 0, 0), normal=(-1, 0, 0), material=glass),
        gs.Plane(point=(0, 0, 0), normal=(0, 1, 0), material=glass),
        gs.Plane(point=(0, w, 0), normal=(0, -1, 0), material=glass),
        rect(corner=(0, 0, 0), edge1=(lo, 0, 0), edge2=(0, w, 0), material=glass),
        rect(corner=(hi, 0, 0), edge1=(w - hi, 0, 0), edge2=(0, w, 0), material=glass),
        rect(corner=(lo, 0, 0), edge1=(d0, 0, 0), edge2=(0, lo, 0), material=glass),
        rect(corner=(lo, hi, 0), edge1=(d0, 0, 0), edge2=(0, w - hi, 0), material=glass),
    ]
    d = case.diameter
    walls.append(  # the shutter: 0.05 d below the floor, overlapping the orifice by d each side
        rect(
            corner=(lo - d, lo - d, -0.05 * d),
            edge1=(d0 + 2 * d, 0, 0),
            edge2=(0, d0 + 2 * d, 0),
            material=glass,
        )
    )
    size = gs.dist.Uniform(0.5 * d * (1 - case.spread), 0.5 * d * (1 + case.spread))
    # The pour face keeps 16 mm (2 parcel diameters at h = 4) from the walls, as in
    # studies/mlcg_jam, whose resolved runs are the reference: the stream is dense (solid
    # fraction 0.47).
    margin = 8 * d
    stream = gs.insert.Stream(
        gs.insert.RectangleFace(
            corner=(margin, margin, case.height),
            edge1=(w - 2 * margin, 0, 0),
            edge2=(0, w - 2 * margin, 0),
        ),
        mass_rate=case.fill_rate,
        radius=size,
        material=glass,
        velocity=(0, 0, -case.pour_speed),
        seed=case.seed,
        stop=case.fill_mass / case.fill_rate,
    )
    outlet = gs.insert.Outlet(region=gs.Box(lo=(0, 0, -case.below), hi=(w, w, -0.5 * case.below)))
    return gs.scaling.ParameterSet(
        domain=gs.Box(lo=(0, 0, -case.below), hi=(w, w, case.height + 0.01)),
        contact=gs.contact.HertzMindlin(restitution=case.restitution, friction=case.friction),
        walls=tuple(walls),
        insertions=(stream,),
        outlets=(outlet,),
        size=size,
    )


def fine_region(case: SiloCase) -> gs.Box:
    """The resolved region: region_width x D0 wide, centred on the orifice, from the bottom of
    the domain to region_top x D0 above the floor (m)."""
    half, c = 0.5 * case.region_width * case.orifice, 0.5 * case.width
    return gs.Box(
        lo=(c - half, c - half, -case.below),
        hi=(c + half, c + half, case.region_top * case.orifice),
    )


def build_hierarchy(case: SiloCase) -> gs.Hierarchy:
    """The hierarchy: h = case.coarse everywhere, h = 1 in fine_region(case)."""
    with _dense_pour():
        return gs.Hierarchy(
            base=reference_parameters(case),
            levels=[gs.Level(cg=case.coarse), gs.Level(cg=1, region=fine_region(case))],
            exchange=gs.Exchange(every=case.exchange_every),
        )


def build_single(case: SiloCase, h: float) -> gs.Simulation:
    """The silo as one Simulation, coarse grained by h (1: resolved)."""
    params = reference_parameters(case)
    if h != 1:
        params = gs.scaling.scale(params, h, "cg").params
    with _dense_pour():
        return gs.scaling.build_simulation(params, quiet=True)


@contextlib.contextmanager
def _dense_pour() -> Iterator[None]:
    """Silences the warning about the dense pour stream (it is the reference's; all of it gets
    in: the demo prints the inserted mass)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Stream volume fraction", category=UserWarning)
        yield


# ------------------------------------------------------------------------------------------
# runs
# ------------------------------------------------------------------------------------------


@dataclass
class Run:
    """One run of the silo, or the reference (SI units)."""

    name: str  # "cg", "mlcg" or "resolved"
    label: str
    history: list[tuple[float, float]] = field(default_factory=list)  # (s after opening, kg)
    rate: float = math.nan  # W, kg/s
    clogged: bool = False
    particles: list[int] = field(default_factory=list)  # per level, when their sum peaked
    wall_clock: float = 0.0  # s, the whole run (pour, settle, discharge)
    cpu_time: float = 0.0  # s
    inserted: float = 0.0  # kg poured
    live: bool = True
    mass_balance: dict[str, Any] = field(default_factory=dict)
    max_unaccounted: float = 0.0  # worst |unaccounted| / (initial + inserted) over the samples
    extra: dict[str, Any] = field(default_factory=dict)  # the reference's seeds and provenance
    final: report.Snapshot | None = None  # the particles at the end (single-level runs)


@dataclass
class DemoResult:
    """What the demo ran and measured: the runs ("cg", "mlcg", with --full "resolved"), the
    shipped reference (None if it was not made for this case), the reference compared with,
    each run's relative error of W against it, and the hierarchy's speed-up over it."""

    case: SiloCase
    runs: dict[str, Run]
    shipped: Run | None
    output: Path
    vtk: bool = True
    reference: Run | None = None
    errors: dict[str, float] = field(default_factory=dict)  # W / W_reference - 1
    speed_up: float | None = None
    summary_text: str = ""


def load_reference(name: str, case: SiloCase) -> Run | None:
    """The shipped resolved reference ``name`` ("default" or "quick") as a Run, or None if it
    was not made for ``case``: its rate is the mean over its seeds, its history and particles
    of one seed, its timing as recorded (CPU time of a rerun where there was one)."""
    entry = silo_reference.load(name, case)
    if entry is None:
        return None
    timing = next((t for t in entry["timing"] if t.get("cpu_time")), entry["timing"][0])
    return Run(
        name="resolved",
        label="resolved (reference)",
        history=[(float(t), float(m)) for t, m in entry["history"]],
        rate=float(entry["rate"]),
        particles=[int(entry["particles"])],
        wall_clock=float(timing["wall_clock"]),
        cpu_time=float(timing["cpu_time"]) if timing.get("cpu_time") else math.nan,
        live=False,
        extra={**entry, "timing": [timing]},
    )


def discharge_rate(history: Sequence[tuple[float, float]], start: float) -> tuple[float, bool]:
    """W (kg/s): the least-squares slope of the discharged mass from ``start`` (s after
    opening) on, and whether the silo clogged (fewer than 3 samples or nothing discharged)."""
    t = np.array([h[0] for h in history])
    m = np.array([h[1] for h in history])
    keep = t >= start
    if np.count_nonzero(keep) < 3 or m[keep][-1] <= m[keep][0]:
        return 0.0, True
    return float(np.polyfit(t[keep], m[keep], 1)[0]), False


def _set_shutter(sims: Sequence[gs.Simulation], speed: float) -> None:
    for sim in sims:
        sim.walls[SHUTTER].set_motion(velocity=(speed, 0.0, 0.0))


Say = Callable[[str], None]


def run_single(case: SiloCase, h: float, say: Say) -> Run:
    """Pour, settle and discharge the silo as one Simulation at h (1: resolved)."""
    name, label = ("resolved", "resolved") if h == 1 else ("cg", f"pure CG, h = {h:g}")
    run = Run(name=name, label=label, particles=[0])
    sim = build_single(case, h)
    t0, c0 = time.perf_counter(), time.process_time()
    say(f"{label}: pouring {case.fill_mass * 1e3:g} g, settling, discharging ...")
    sim.run(until=case.open_time, progress=False)
    _set_shutter([sim], SHUTTER_SPEED)
    sim.run(until=case.open_time + SHUTTER_TIME, progress=False)
    _set_shutter([sim], 0.0)
    outlet = sim.outlets[0]
    while sim.time < case.end_time - 1e-9:
        sim.run(until=min(sim.time + SAMPLE, case.end_time), progress=False)
        run.history.append((sim.time - case.open_time, float(outlet.removed_mass)))
        run.particles[0] = max(run.particles[0], sim.num_particles)
    run.wall_clock, run.cpu_time = time.perf_counter() - t0, time.process_time() - c0
    run.rate, run.clogged = discharge_rate(run.history, case.transient)
    run.inserted = float(sim.streams[0].inserted_mass)
    title = f"{label}, {sim.time - case.open_time:.2f} s after opening"
    run.final = report.single_snapshot(sim, h, title)
    return run


def run_hierarchy(
    case: SiloCase, output: Path | None, say: Say
) -> tuple[Run, list[report.Snapshot]]:
    """Pour, settle and discharge the hierarchy, its VTK files into ``output`` (None: none).
    Samples the finest level's outlet, the particle counts and the books every SAMPLE s;
    returns the run and the hierarchy's particles at the opening and at the end."""
    run = Run(name="mlcg", label=f"MLCG {case.coarse:g} -> 1")
    h = build_hierarchy(case)
    series = report.LevelSeries(output) if output is not None else None
    if output is not None:
        h.output(output, every=VTK_EVERY)
    t0, c0 = time.perf_counter(), time.process_time()
    say(f"{run.label}: pouring {case.fill_mass * 1e3:g} g and settling ...")
    h.run(until=case.open_time)
    _set_shutter(h.sims, SHUTTER_SPEED)
    h.run(until=case.open_time + SHUTTER_TIME)
    _set_shutter(h.sims, 0.0)
    title = f"{run.label}, {{:.2f}} s after opening"
    snapshots = [report.snapshot(h, title.format(h.time - case.open_time))]
    say(f"{run.label}: discharging ...")
    while h.time < case.end_time - 1e-9:
        h.run(until=min(h.time + SAMPLE, case.end_time))
        t = h.time - case.open_time
        _record(run, h, t)
        if series is not None and (len(run.history) == 1 or _crossed(t, 2 * VTK_EVERY)):
            series.write(h)
        if _crossed(t, 0.1):
            say(f"  {t:.1f} s after opening: {run.history[-1][1] * 1e3:5.1f} g discharged")
    run.wall_clock, run.cpu_time = time.perf_counter() - t0, time.process_time() - c0
    run.rate, run.clogged = discharge_rate(run.history, case.transient)
    run.mass_balance = h.mass_balance()
    run.inserted = float(run.mass_balance["inserted"])
    snapshots.append(report.snapshot(h, title.format(h.time - case.open_time)))
    return run, snapshots


def _record(run: Run, h: gs.Hierarchy, t: float) -> None:
    """One sample of the hierarchy at t (s after opening): the finest level's discharged mass,
    the particle counts (kept where their sum peaks) and the books' unaccounted mass."""
    run.history.append((t, float(h.level(len(h.sims) - 1).outlets[0].removed_mass)))
    counts = [s.num_particles for s in h.sims]
    if sum(counts) > sum(run.particles):
        run.particles = counts
    books = h.mass_balance()
    total = books["initial"] + books["inserted"]
    run.max_unaccounted = max(run.max_unaccounted, abs(books["unaccounted"]) / total)


def _crossed(t: float, every: float) -> bool:
    """Whether the sample at t (s) is the first at or after a multiple of ``every``."""
    k = round(t / every)
    return k > 0 and -1e-9 <= t - k * every < SAMPLE - 1e-9


# ------------------------------------------------------------------------------------------
# the demo
# ------------------------------------------------------------------------------------------


def run(
    output: str | Path,
    quick: bool = False,
    full: bool = False,
    seed: int = 1,
    verbose: bool = True,
    vtk: bool = True,
) -> DemoResult:
    """Run the demo and write its files into ``output``; returns what was measured.

    Args:
        output: output directory (created if needed).
        quick: the shallower, shorter case QUICK (its own reference).
        full: run the resolved reference live too (about 2 minutes of CPU more).
        seed: seed of the pour (the reference is over its own seeds).
        verbose: print progress and the summary.
        vtk: write the hierarchy's VTK files.
    """
    case = dataclasses.replace(QUICK if quick else JAM, seed=seed)
    out = Path(output)
    lead = gs.parallel.world_rank() == 0  # under mpirun rank 0 prints and writes
    out.mkdir(parents=True, exist_ok=True)

    def say(text: str) -> None:
        if verbose and lead:
            print(text, flush=True)

    say(report.setup_text(case, full))
    t_start = time.perf_counter()
    runs: dict[str, Run] = {"cg": run_single(case, case.coarse, say)}
    say(report.run_line(runs["cg"]))
    runs["mlcg"], snapshots = run_hierarchy(case, out if vtk else None, say)
    say(report.run_line(runs["mlcg"]))
    if full:
        runs["resolved"] = run_single(case, 1.0, say)
        say(report.run_line(runs["resolved"]))
    shipped = load_reference("quick" if quick else "default", case)
    result = DemoResult(case=case, runs=runs, shipped=shipped, output=out, vtk=vtk)
    pictures = [*snapshots, runs["cg"].final] if runs["cg"].final is not None else snapshots
    report.finish(result, pictures, time.perf_counter() - t_start, lead)
    say("")
    say(result.summary_text)
    return result


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------

DESCRIPTION = (
    "A silo whose orifice jams coarse graining: pure CG (h = 2) and a multi-level hierarchy "
    "(h = 2, resolved at the orifice) against a resolved reference (grainscale demo)."
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The demo's options (``grainscale demo`` and ``python -m grainscale.examples.silo_demo``)."""
    parser.add_argument(
        "--output", default="out/demo", help="output directory (default: %(default)s)"
    )
    parser.add_argument(
        "--full",
        action="store_true",
        help="run the resolved reference live too (otherwise read from the shipped reference)",
    )
    parser.add_argument(
        "--quick", action="store_true", help="a shallower bed, a 0.3 s discharge (the tests)"
    )
    parser.add_argument("--seed", type=int, default=1, help="seed of the pour (default: 1)")
    parser.add_argument("--no-vtk", action="store_true", help="no VTK files")


def run_from_args(args: argparse.Namespace) -> DemoResult:
    """The demo as the parsed options (see :func:`add_arguments`) ask."""
    return run(args.output, quick=args.quick, full=args.full, seed=args.seed, vtk=not args.no_vtk)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.silo_demo", description=DESCRIPTION
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
