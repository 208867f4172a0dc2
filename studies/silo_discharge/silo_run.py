"""Silo discharge study (CASES D1): one silo, poured, settled and discharged.

``run_orifice`` fills one silo (``silo_setup``, ``pour_and_settle``), opens the orifice and
measures the discharge rate from the outlet history (``measure_rate``); ``run_many`` runs
several in worker processes.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import math
import multiprocessing
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs
from studies.silo_discharge.silo_beverloo import G
from studies.silo_discharge.silo_case import WINDOW, SiloCase, annulus_mesh, cylinder_surface

# ------------------------------------------------------------------------------------------
# one discharge
# ------------------------------------------------------------------------------------------


@dataclass
class DischargeResult:
    """One filled-and-discharged silo (SI units; times after the shutter opened)."""

    orifice: float  # D0, m
    seed: int
    silo_diameter: float  # m
    particles: int  # inventory when the shutter opened
    inventory: float  # kg
    bed_height: float  # m
    bulk_density: float  # kg/m^3, inventory / (silo cross-section x bed height)
    core_bulk_density: float  # kg/m^3, in the bed away from walls, floor and surface (3 d)
    rate: float  # W, kg/s (NaN if the window was not reached)
    rate_first_half: float  # slope over 20-45 % of the inventory, kg/s
    rate_second_half: float  # slope over 45-70 %, kg/s
    r_squared: float  # of the linear fit in the window
    clogged: bool
    time: np.ndarray  # outlet history: s after opening
    mass: np.ndarray  # kg discharged
    count: np.ndarray
    inserted_count: int  # poured + re-poured
    inserted_mass: float
    refill_count: int  # re-poured on top (constant head)
    refill_mass: float
    remaining_count: int
    remaining_mass: float
    discharged_count: int
    discharged_mass: float
    lost: int
    time_step: float
    fill_time: float  # simulated s from the start to the opening
    discharge_time: float  # simulated s of discharge
    steps: int
    wall_clock: float  # s
    particle_steps: float
    notes: list[str] = field(default_factory=list)
    cg: float = 1.0  # coarse-graining ratio h of the run

    @property
    def mass_balance_error(self) -> float:
        """inserted - (in silo + discharged), kg (round-off only)."""
        return self.inserted_mass - (self.remaining_mass + self.discharged_mass)

    def summary(self) -> dict[str, Any]:
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        for key in ("time", "mass", "count"):
            d.pop(key)
        d["mass_balance_error"] = self.mass_balance_error
        return d


def _slope(time_: np.ndarray, mass: np.ndarray, sel: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of mass over time on the selected points and its R^2 (NaNs when
    fewer than 3 points)."""
    if np.count_nonzero(sel) < 3 or np.ptp(time_[sel]) <= 0:
        return math.nan, math.nan
    t, m = time_[sel], mass[sel]
    p = np.polyfit(t, m, 1)
    resid = m - np.polyval(p, t)
    ss = float(np.sum((m - m.mean()) ** 2))
    return float(p[0]), 1.0 - float(np.sum(resid**2)) / ss if ss > 0 else math.nan


def measure_rate(
    time_: np.ndarray, mass: np.ndarray, inventory: float, window: tuple[float, float] = WINDOW
) -> tuple[float, float, float, float]:
    """Slope (kg/s) of the discharged mass between window[0] and window[1] of ``inventory``.

    Returns (W, W over the first half of the window, W over the second half, R^2 of the linear
    fit); NaNs when the window holds fewer than 3 points.
    """
    lo, hi = window[0] * inventory, window[1] * inventory
    mid = 0.5 * (lo + hi)
    w, r2 = _slope(time_, mass, (mass >= lo) & (mass <= hi))
    first = _slope(time_, mass, (mass >= lo) & (mass <= mid))[0]
    return w, first, _slope(time_, mass, (mass >= mid) & (mass <= hi))[0], r2


def measure_rate_between(
    time_: np.ndarray, mass: np.ndarray, start: float, end: float
) -> tuple[float, float, float, float]:
    """Slope (kg/s) of the discharged mass between the times ``start`` and ``end`` (s), for a
    constant-head silo; returns (W, W over each half of the interval, R^2) like measure_rate."""
    mid = 0.5 * (start + end)
    w, r2 = _slope(time_, mass, (time_ >= start) & (time_ <= end))
    first = _slope(time_, mass, (time_ >= start) & (time_ <= mid))[0]
    return w, first, _slope(time_, mass, (time_ >= mid) & (time_ <= end))[0], r2


def rate_of(
    case: SiloCase, orifice: float, time_: np.ndarray, mass: np.ndarray, inventory: float
) -> tuple[float, float, float, float]:
    """The discharge rate of a run of ``case`` from its outlet history: over the steady window
    ``case.measure_window(orifice)`` with a constant head, else between 20 % and 70 % of the
    inventory."""
    if case.constant_head:
        return measure_rate_between(time_, mass, *case.measure_window(orifice))
    return measure_rate(time_, mass, inventory)


def _bed_height(position: np.ndarray, radius: np.ndarray, silo_radius: float, column: float):
    """Mean over columns (about ``column`` wide, inside the silo) of the highest sphere top."""
    n = max(1, int(2 * silo_radius / column))
    edges = np.linspace(-silo_radius, silo_radius, n + 1)
    centres = 0.5 * (edges[1:] + edges[:-1])
    cx, cy = np.meshgrid(centres, centres, indexing="ij")
    inside = (cx**2 + cy**2) <= (silo_radius - column) ** 2
    ix = np.clip(np.searchsorted(edges, position[:, 0]) - 1, 0, n - 1)
    iy = np.clip(np.searchsorted(edges, position[:, 1]) - 1, 0, n - 1)
    top = np.zeros((n, n))
    np.maximum.at(top, (ix, iy), position[:, 2] + radius)
    return float(top[inside].mean())


def _core_bulk_density(
    position: np.ndarray,
    radius: np.ndarray,
    silo_radius: float,
    height: float,
    margin: float,
    density: float,
) -> float:
    """rho_p x solid fraction of the particles centred in the bed's core: the cylinder
    ``margin`` away from the wall, the floor and the free surface (kg/m^3)."""
    r_core, z0, z1 = silo_radius - margin, margin, height - margin
    if r_core <= 0 or z1 <= z0:
        return math.nan
    inside = (np.hypot(position[:, 0], position[:, 1]) < r_core) & (
        (position[:, 2] > z0) & (position[:, 2] < z1)
    )
    solid = float(np.sum(4.0 / 3.0 * math.pi * radius[inside] ** 3))
    return density * solid / (math.pi * r_core**2 * (z1 - z0))


class _Refill:
    """Keeps the head constant: after each run chunk, as many particles as the outlet removed
    since the last call are packed into a slab just above the initial free surface and thrown
    down at ``refill_speed`` (the usual constant-head DEM silo)."""

    def __init__(
        self,
        case: SiloCase,
        seed: int,
        size: gs.dist.Uniform,
        radius: float,
        surface: float,
        particle_mass: float,
        material: gs.Material,
    ):
        self.case, self.seed, self.radius, self.surface = case, seed, radius, surface
        self.size = size  # of the simulated particles (parcels when coarse-grained)
        self.material = material
        self.count, self.mass, self.batches = 0, 0.0, 0
        self.volume = particle_mass / case.density

    def top_up(self, sim: gs.Simulation, removed: int) -> None:
        n = removed - self.count
        if n <= 0:
            return
        case, d_max = self.case, 2 * self.size.max
        # a slab loose enough (solid fraction <= 0.2) for random sequential addition
        thick = max(2 * d_max, n * self.volume / (0.2 * math.pi * self.radius**2))
        z0 = self.surface + d_max
        region = gs.geometry.Cylinder(
            point=(0.0, 0.0, z0), axis=(0, 0, 1), radius=self.radius, length=thick
        )
        self.batches += 1
        ids = sim.insert(
            gs.insert.Pack(
                region,
                radius=self.size,
                material=self.material,
                count=n,
                velocity=(0.0, 0.0, -case.refill_speed),
                seed=1_000_003 * self.seed + self.batches,
            )
        )
        with sim.particles(writable=False) as p:
            idx = np.isin(np.asarray(p.id), ids)
            self.mass += float(np.asarray(p.mass)[idx].sum())
        self.count += n


class _Clock:
    """Runs a simulation and counts its particle-steps (particles x steps)."""

    def __init__(self, sim: gs.Simulation) -> None:
        self.sim = sim
        self.particle_steps = 0.0

    def run(self, until: float, progress: bool = False) -> None:
        n, s0 = self.sim.num_particles, self.sim.step
        self.sim.run(until=until, progress=progress)
        self.particle_steps += 0.5 * (n + self.sim.num_particles) * (self.sim.step - s0)


#: index of the shutter among the walls of a silo's ParameterSet (cylinder, floor, shutter)
SHUTTER = 2


@dataclass(frozen=True)
class SiloSetup:
    """The parameter sets of one silo (SI units).

    ``reference`` holds the resolved particles (diameter d) in the silo of the resolved case;
    ``params`` is what is simulated: the reference itself when ``case.cg`` is 1, else
    ``scaled.params`` = ``grainscale.scaling.scale(reference, case.cg, "cg")`` (parcels h d
    across; time step and skin x h; silo, floor, pour face, outlet and mass rate unchanged).
    ``detail`` is the parcel diameter h d, the unit of the outlet depth, the shutter gap and
    drop, the pour-face margins and the measuring margins (bed surface, core density).
    """

    reference: gs.scaling.ParameterSet
    params: gs.scaling.ParameterSet
    scaled: gs.scaling.Scaled | None
    silo: float  # m
    top: float  # height of the pour face, m
    pour_time: float  # s
    detail: float  # m


def silo_setup(case: SiloCase, orifice: float, seed: int = 1) -> SiloSetup:
    """The reference and simulated parameter sets of the silo of ``case`` with the orifice D0
    (m) and the pour seeded with ``seed``: cylinder wall, annulus floor, shutter (walls 0, 1,
    2), the pouring stream and the outlet below the floor."""
    d = case.cg * case.diameter  # details follow the simulated particles
    silo = case.silo_for(orifice)  # geometry follows the resolved case
    R = 0.5 * silo
    if not 0 < orifice < silo - 2 * d:
        raise ValueError(
            f"run_orifice.orifice must be in (0, silo diameter - 2 h d) = "
            f"(0, {silo - 2 * d:g}) m, got {orifice!r}"
        )
    glass = case.material()
    dist = case.radius_distribution
    d_max = case.cg * 2 * dist.max
    h_nom = case.nominal_height(orifice)
    top = h_nom + max(6 * d_max, 0.15 * h_nom)  # the pouring face
    face_radius = R - d_max
    # the mass rate (and so the pour time) of the resolved case, poured through a face that
    # keeps the parcels off the wall
    area = math.pi * (R - 2 * dist.max) ** 2
    rate = case.pour_fraction * case.density * area * case.pour_speed
    pour_time = case.target_mass(orifice) / rate
    s = 0.5 * orifice + d  # shutter: a square under the orifice, 0.05 d below the floor
    # The Simulation defaults, explicit so that scale() maps them: 0.2 x the Rayleigh time of
    # the smallest sphere, skin 0.1 x the largest diameter.
    dt = case.time_step
    if dt is None:
        dt = 0.2 * gs.timestep.rayleigh_time(glass, dist.min)
    reference = gs.scaling.ParameterSet(
        domain=gs.Box(lo=(-R - 2 * d, -R - 2 * d, -8 * d), hi=(R + 2 * d, R + 2 * d, top + 2 * d)),
        contact=case.contact_law(),
        time_step=dt,
        skin=0.1 * 2 * dist.max,
        walls=(
            gs.geometry.Cylinder(
                point=(0.0, 0.0, -d), axis=(0, 0, 1), radius=R, length=top + 2 * d, material=glass
            ),
            annulus_mesh(0.5 * orifice, R + case.diameter, material=glass),
            gs.Rectangle(
                corner=(-s, -s, -0.05 * d), edge1=(2 * s, 0, 0), edge2=(0, 2 * s, 0), material=glass
            ),
        ),
        size=dist,
        insertions=(
            gs.insert.Stream(
                gs.insert.DiscFace(centre=(0.0, 0.0, top), normal=(0, 0, -1), radius=face_radius),
                mass_rate=rate,
                radius=dist,
                material=glass,
                velocity=(0.0, 0.0, -case.pour_speed),
                seed=seed,
                stop=pour_time,
            ),
        ),
        outlets=(
            gs.insert.Outlet(
                gs.Box(lo=(-R - 2 * d, -R - 2 * d, -1.0), hi=(R + 2 * d, R + 2 * d, -1.5 * d)),
                every=case.outlet_every,
            ),
        ),
    )
    scaled = None if case.cg == 1 else gs.scaling.scale(reference, case.cg, scheme="cg")
    params = reference if scaled is None else scaled.params
    return SiloSetup(reference, params, scaled, silo, top, pour_time, d)


def pour_and_settle(
    sim: gs.Simulation,
    case: SiloCase,
    setup: SiloSetup,
    clock: _Clock | None = None,
    progress: bool = False,
) -> list[str]:
    """Pour the stream of ``setup`` into the closed silo of ``sim`` and let the bed settle
    (rms speed below ``case.settle_speed``, between ``min_settle`` and ``max_settle`` s after
    the pour); return notes on anything unusual. ``clock`` counts the particle-steps."""
    clock = clock if clock is not None else _Clock(sim)
    stream = sim.streams[0]
    fall = math.sqrt(2 * setup.top / G)
    clock.run(setup.pour_time + fall, progress)
    while stream.pending_count > 0 and sim.time < setup.pour_time + case.max_settle:
        clock.run(sim.time + 0.01)
    t_settle0 = sim.time
    clock.run(t_settle0 + case.min_settle)
    with sim.particles(writable=False) as p:
        mass0 = float(p.mass.sum())
    while sim.time < t_settle0 + case.max_settle:
        if math.sqrt(2 * sim.kinetic_energy() / mass0) < case.settle_speed:
            break
        clock.run(sim.time + 0.02)
    v_rms = math.sqrt(2 * sim.kinetic_energy() / mass0)
    if v_rms >= case.settle_speed:
        return [f"bed not fully settled at opening: rms speed {v_rms:.3g} m/s"]
    return []


def run_orifice(
    case: SiloCase,
    orifice: float,
    seed: int = 1,
    output: str | Path | None = None,
    progress: bool = False,
    log: Any = None,
) -> DischargeResult:
    """Fill the silo of ``case`` by pouring, settle, open an orifice of diameter ``orifice`` (m)
    and discharge; return the measured rate and the bookkeeping.

    Args:
        case: the silo and material.
        orifice: D0 (m).
        seed: seed of the poured stream (sizes and positions).
        output: directory for VTK snapshots (only if ``case.vtk_every`` is set).
        progress: progress bars.
        log: callable taking a line of text (None: silent).
    """
    say = log if log is not None else (lambda _s: None)
    t_clock = time.perf_counter()
    setup = silo_setup(case, orifice, seed)
    params, d, silo, top = setup.params, setup.detail, setup.silo, setup.top
    R = 0.5 * silo
    sim = gs.scaling.build_simulation(params, quiet=True)
    stream, outlet = sim.streams[0], sim.outlets[0]
    glass, size = params.insertions[0].material, params.insertions[0].radius
    assert isinstance(size, gs.dist.Uniform)
    vtk = None
    if case.vtk_every is not None and output is not None:
        vtk = gs.io.VTK(output, every=case.vtk_every)
        sim.output(vtk)
        v, t = cylinder_surface(R, -d, top + d)
        Path(output).mkdir(parents=True, exist_ok=True)
        gs.io.write_vtp_mesh(Path(output) / "silo_cylinder.vtp", v, t)

    clock = _Clock(sim)
    notes = pour_and_settle(sim, case, setup, clock, progress)
    with sim.particles(writable=False) as p:
        inventory = float(p.mass.sum())
        n0 = len(p)
        position, radius = np.array(p.position), np.array(p.radius)
        height = _bed_height(position, radius, R, d)
        core = _core_bulk_density(position, radius, R, height, 3 * d, case.density)
    bulk = inventory / (math.pi * R**2 * height)
    t_open = sim.time
    say(
        f"  D0 = {orifice * 1e3:g} mm, seed {seed}: silo {silo * 1e3:g} mm, {n0} particles, "
        f"{inventory:.4g} kg, bed {height * 1e3:.1f} mm, rho_b = {bulk:.0f} kg/m^3 (core "
        f"{core:.0f}); opening at t = {t_open:.3f} s"
    )

    # ----- open: the shutter drops 4 d at shutter_speed, then stops inside the outlet region
    sim.walls[SHUTTER].set_motion(velocity=(0.0, 0.0, -case.shutter_speed))
    clock.run(t_open + 4 * d / case.shutter_speed)
    sim.walls[SHUTTER].set_motion(velocity=(0.0, 0.0, 0.0))
    clogged = False
    last_mass, last_change = outlet.removed_mass, sim.time
    refill = _Refill(case, seed, size, R - 2 * size.max, height, inventory / n0, glass)
    chunk = case.refill_every if case.constant_head else 0.05
    while True:
        elapsed = sim.time - t_open
        if case.constant_head and elapsed >= case.measure_window(orifice)[1]:
            break
        if not case.constant_head and outlet.removed_mass >= case.stop_fraction * inventory:
            break
        if elapsed >= case.max_discharge:
            notes.append(f"stopped at the time limit {case.max_discharge:g} s")
            break
        clock.run(sim.time + chunk, progress)
        if case.constant_head:
            refill.top_up(sim, outlet.removed_count)
        if outlet.removed_mass > last_mass:
            last_mass, last_change = outlet.removed_mass, sim.time
        elif sim.time - last_change >= case.clog_time:
            clogged = True
            notes.append(
                f"clogged: nothing discharged for {case.clog_time:g} s after "
                f"{last_mass / inventory:.0%} of the inventory"
            )
            break

    h_time, h_mass, h_count = (np.asarray(a) for a in outlet.history())
    t_rel = h_time - t_open
    w, w1, w2, r2 = rate_of(case, orifice, t_rel, h_mass, inventory)
    with sim.particles(writable=False) as p:
        remaining_mass = float(p.mass.sum())
    status = stream.status()
    wall = time.perf_counter() - t_clock
    if vtk is not None:
        notes.append(f"VTK: {len(vtk.files)} snapshots in {output}")
    result = DischargeResult(
        orifice=orifice,
        seed=seed,
        silo_diameter=silo,
        particles=n0,
        inventory=inventory,
        bed_height=height,
        bulk_density=bulk,
        core_bulk_density=core,
        rate=w,
        rate_first_half=w1,
        rate_second_half=w2,
        r_squared=r2,
        clogged=clogged,
        time=t_rel,
        mass=h_mass,
        count=h_count.astype(np.int64),
        inserted_count=int(status["inserted_count"]) + refill.count,
        inserted_mass=float(status["inserted_mass"]) + refill.mass,
        refill_count=refill.count,
        refill_mass=refill.mass,
        remaining_count=sim.num_particles,
        remaining_mass=remaining_mass,
        discharged_count=outlet.removed_count,
        discharged_mass=outlet.removed_mass,
        lost=sim.lost_particles,
        time_step=float(sim.time_step),  # type: ignore[arg-type]
        fill_time=t_open,
        discharge_time=sim.time - t_open,
        steps=sim.step,
        wall_clock=wall,
        particle_steps=clock.particle_steps,
        notes=notes,
        cg=case.cg,
    )
    say(
        f"  D0 = {orifice * 1e3:g} mm, seed {seed}: W = {w:.4g} kg/s (R^2 = {r2:.4f}), "
        f"{outlet.removed_count} out, {sim.num_particles} left, {wall:.0f} s wall-clock"
    )
    return result


def print_flush(line: str) -> None:
    """Print a progress line at once (worker processes share the terminal)."""
    print(line, flush=True)


def _run_task(args: tuple[SiloCase, float, int, str | None]) -> DischargeResult:
    """One (orifice, seed) run in a worker process, printing its progress lines."""
    case, orifice, seed, vtk_dir = args
    return run_orifice(case, orifice, seed, output=vtk_dir, log=print_flush)


def _run_task_quiet(args: tuple[SiloCase, float, int, str | None]) -> DischargeResult:
    case, orifice, seed, vtk_dir = args
    return run_orifice(case, orifice, seed, output=vtk_dir)


def run_many(
    tasks: Sequence[tuple[SiloCase, float, int, str | None]], jobs: int = 1, verbose: bool = False
) -> list[DischargeResult]:
    """Run (case, orifice m, seed, VTK directory or None) tasks, in ``jobs`` worker processes
    when jobs > 1; results sorted by orifice, then seed."""
    if jobs > 1 and len(tasks) > 1:
        ctx = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            runs = list(pool.map(_run_task if verbose else _run_task_quiet, tasks))
    else:
        log = print_flush if verbose else None
        runs = [run_orifice(c, d0, seed, output=vtk, log=log) for c, d0, seed, vtk in tasks]
    return sorted(runs, key=lambda r: (r.orifice, r.seed))
