"""The runs of the industrial silo study: the multi-level hierarchy (fill, settle, open,
discharge, with a checkpoint part-way and a restart from it) and single-level runs (the
resolved references, pure coarse graining). Each returns a plain dict (SI units) that
:mod:`studies.silo_industrial.silo_industrial` writes and reports. Collective under MPI: every
rank calls, every rank gets the same dict.
"""

from __future__ import annotations

import hashlib
import math
import resource
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs
from grainscale.examples.silo_demo import discharge_rate
from studies.silo_industrial.silo_case import (
    SHUTTER,
    SHUTTER_SPEED,
    SHUTTER_TIME,
    SiloCase,
    exchange,
    hierarchy_levels,
    reference_parameters,
)

SAMPLE = 0.05  # s between samples of the discharged mass and the inventories
VTK_EVERY = 0.5  # s between snapshots of the levels
RESTART_INTERVALS = 20  # exchange intervals run past the checkpoint, twice, and compared
Say = Callable[[str], None]


def peak_memory(comm: Any) -> list[float]:
    """Peak resident memory of every rank (bytes; Linux reports ru_maxrss in KiB)."""
    mine = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0
    return [float(v) for v in comm.allgather(mine)] if comm is not None else [mine]


def _set_shutter(sims: Sequence[gs.Simulation], speed: float) -> None:
    for sim in sims:
        sim.walls[SHUTTER].set_motion(velocity=(speed, 0.0, 0.0))


def state_digest(sims: Sequence[gs.Simulation]) -> str:
    """SHA-256 of every level's particles (ids, positions, velocities, spins, radii) in id
    order: equal digests are bit-identical states."""
    h = hashlib.sha256()
    for sim in sims:
        g = sim.gather()
        for name in ("id", "position", "velocity", "angular_velocity", "radius"):
            h.update(np.ascontiguousarray(g[name]).tobytes())
    return h.hexdigest()


# ------------------------------------------------------------------------------ single level
def run_single(case: SiloCase, h: float, comm: Any, say: Say) -> dict[str, Any]:
    """The silo as one Simulation at coarse-graining ratio h (1: resolved), on ``comm``."""
    params = reference_parameters(case)
    if h != 1:
        params = gs.scaling.scale(params, h, "cg").params
    sim = gs.scaling.build_simulation(params, comm=comm, quiet=True)
    sim.balance(every=2000)
    phases: dict[str, float] = {}
    t0 = time.perf_counter()
    sim.run(until=case.fill_mass / case.fill_rate, progress=False)
    phases["fill"] = time.perf_counter() - t0
    sim.run(until=case.open_time, progress=False)
    phases["settle"] = time.perf_counter() - t0 - phases["fill"]
    steps0, particles0 = sim.step, sim.num_particles
    _set_shutter([sim], SHUTTER_SPEED)
    sim.run(until=case.open_time + SHUTTER_TIME, progress=False)
    _set_shutter([sim], 0.0)
    history: list[tuple[float, float]] = []
    peak = sim.num_particles
    while sim.time < case.end_time - 1e-9:
        sim.run(until=min(sim.time + SAMPLE, case.end_time), progress=False)
        history.append((sim.time - case.open_time, float(sim.outlets[0].removed_mass)))
        say(f"  t = {history[-1][0]:.2f} s after opening: {history[-1][1] * 1e3:.1f} g out")
    wall = time.perf_counter() - t0
    phases["discharge"] = wall - phases["fill"] - phases["settle"]
    rate, clogged = discharge_rate(history, case.transient)
    inserted = float(sum(s.inserted_mass for s in sim.streams))
    return {
        "kind": "single",
        "cg": h,
        "diameter": case.diameter,
        "rate": rate,
        "clogged": clogged,
        "history": history,
        "particles": peak,
        "particles_at_opening": particles0,
        "inserted_mass": inserted,
        "resolved_equivalent_particles": case.resolved_equivalent(inserted),
        "discharge_steps": sim.step - steps0,
        "wall_clock_s": wall,
        "phases_s": phases,
        "ranks": sim.ranks,
        "peak_memory_bytes": peak_memory(comm),
    }


# ------------------------------------------------------------------------------ hierarchy
def build_hierarchy(case: SiloCase, comm: Any) -> gs.Hierarchy:
    """The chain of levels around the orifice, every level decomposed over ``comm`` and
    balancing its own work automatically."""
    h = gs.Hierarchy(
        base=reference_parameters(case),
        levels=hierarchy_levels(case),
        exchange=exchange(case),
        comm=comm,
        seed=case.seed,
    )
    for sim in h.sims:
        sim.balance(every=1000)
    return h


def _census(h: gs.Hierarchy) -> dict[str, Any]:
    """Particles per level and per rank, and each rank's share of each level."""
    counts = [list(sim.decomposition()["counts"]) for sim in h.sims]
    return {"per_level": [int(sum(c)) for c in counts], "per_level_per_rank": counts}


class HierarchyRun:
    """The hierarchy's run, phase by phase, sampled every SAMPLE seconds after opening."""

    def __init__(self, case: SiloCase, comm: Any, output: Path, say: Say, vtk: bool) -> None:
        self.case, self.comm, self.output, self.say = case, comm, output, say
        self.h = build_hierarchy(case, comm)
        if vtk:
            self.h.output(output / "vtk", every=VTK_EVERY)
        self.phases: dict[str, float] = {}
        self.history: list[tuple[float, float]] = []  # (s after opening, discharged kg)
        # (s after opening, per level: the mass it holds where it is the finest, and its
        # particles' whole mass, its children's regions included)
        self.inventory: list[tuple[float, list[float], list[float]]] = []
        self.max_unaccounted = 0.0
        self.peak_particles = 0
        self.census_peak: dict[str, Any] = {}
        self.restart: dict[str, Any] = {}

    def _phase(self, name: str, until: float) -> None:
        t0 = time.perf_counter()
        self.h.run(until=until)
        self.phases[name] = self.phases.get(name, 0.0) + time.perf_counter() - t0
        parts = ", ".join(f"{k} {v:.0f}" for k, v in self.h.wall_clock["exchange_parts"].items())
        self.say(
            f"  {name} to t = {self.h.time:.3f} s: {time.perf_counter() - t0:.0f} s "
            f"(exchange parts so far, s: {parts})"
        )

    def _sample(self) -> None:
        h, case = self.h, self.case
        b = h.mass_balance()
        t = h.time - case.open_time
        self.history.append((t, float(b["discharged"])))
        whole = [float(m) for m in b["held"]]
        for i in b["interfaces"]:
            whole[i["parent"]] += float(i["shadow"])
        self.inventory.append((t, [float(m) for m in b["held"]], whole))
        total = b["initial"] + b["inserted"]
        self.max_unaccounted = max(self.max_unaccounted, abs(b["unaccounted"]) / total)
        n = sum(sim.num_particles for sim in h.sims)
        if n > self.peak_particles:
            self.peak_particles, self.census_peak = n, _census(h)

    def run(self) -> dict[str, Any]:
        case, h = self.case, self.h
        t0 = time.perf_counter()
        self._phase("fill", case.fill_mass / case.fill_rate)
        self._phase("settle", case.open_time)
        self.at_opening = _census(h)
        _set_shutter(h.sims, SHUTTER_SPEED)
        self._phase("discharge", case.open_time + SHUTTER_TIME)
        _set_shutter(h.sims, 0.0)
        checkpoint_time = case.open_time + 0.5 * case.discharge
        checkpoint = self.output / "checkpoint.h5"
        written = False
        while h.time < case.end_time - 1e-9:
            t1 = time.perf_counter()
            h.run(until=min(h.time + SAMPLE, case.end_time))
            self.phases["discharge"] += time.perf_counter() - t1
            self._sample()
            if not written and h.time >= checkpoint_time - 1e-9:
                written = True
                self._checkpoint(checkpoint)
            t, m = self.history[-1]
            self.say(
                f"  t = {t:.2f} s after opening: {m * 1e3:.1f} g out, held per level (g) "
                + ", ".join(f"{x * 1e3:.0f}" for x in self.inventory[-1][1])
                + f", {time.perf_counter() - t0:.0f} s so far, exchanges "
                + f"{h.wall_clock['exchange']:.0f} s"
            )
        wall = time.perf_counter() - t0
        self.restart["check"] = self._restart_check(checkpoint)
        return self._result(wall)

    def _checkpoint(self, path: Path) -> None:
        """Writes the checkpoint, then runs RESTART_INTERVALS and records the state's digest:
        the restart check repeats those intervals from the file."""
        t0 = time.perf_counter()
        self.h.checkpoint(path)
        self.phases["checkpoint"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        self.h.run(intervals=RESTART_INTERVALS)
        self.phases["discharge"] += time.perf_counter() - t1
        self.restart.update(
            time=self.h.time,
            intervals=RESTART_INTERVALS,
            digest=state_digest(self.h.sims),
            balance=self.h.mass_balance(),
            bytes=path.stat().st_size,
        )

    def _restart_check(self, path: Path) -> dict[str, Any]:
        """A fresh hierarchy restarted from the checkpoint runs the same intervals: its state
        and books must be bit-identical to the continuing run's."""
        t0 = time.perf_counter()
        fresh = build_hierarchy(self.case, self.comm)
        fresh.restart(path)
        fresh.run(intervals=RESTART_INTERVALS)
        digest = state_digest(fresh.sims)
        books = fresh.mass_balance()
        self.phases["restart_check"] = time.perf_counter() - t0
        same_books = all(
            books[k] == self.restart["balance"][k] for k in ("held", "discharged", "unaccounted")
        )
        return {
            "digest": digest,
            "identical": digest == self.restart["digest"] and same_books,
            "books_identical": same_books,
        }

    def _result(self, wall: float) -> dict[str, Any]:
        case, h = self.case, self.h
        rate, clogged = discharge_rate(self.history, case.transient)
        b = h.mass_balance()
        total = b["initial"] + b["inserted"]
        # The coarsest level's inventory over the window, against what left the hierarchy: all
        # its particles (it pays the finer levels' discharge by removing its own in their
        # regions) and those outside the regions (its bed flowing into them).
        t = np.array([s[0] for s in self.inventory])
        keep = t >= case.transient

        def falling(values: list[float]) -> float:
            y = np.array(values)
            return -float(np.polyfit(t[keep], y[keep], 1)[0]) if keep.sum() > 2 else 0.0

        coarse_rate = falling([s[2][0] for s in self.inventory])
        outside_rate = falling([s[1][0] for s in self.inventory])
        # Resolved-equivalent particle-steps: the material as resolved spheres, stepped at the
        # resolved level's time step over the whole run.
        equivalent = case.resolved_equivalent(b["inserted"])
        dt_resolved = h.every / h.steps[-1] / h.levels[-1].cg  # dt grows as h (scheme cg)
        particle_steps = equivalent * h.time / dt_resolved
        return {
            "kind": "hierarchy",
            "ratios": [lv.cg for lv in h.levels],
            "regions": [
                None if lv.region is None else [list(lv.region.lo), list(lv.region.hi)]
                for lv in h.levels
            ],  # fmt: skip
            "time_steps_s": [h.every / n for n in h.steps],
            "exchange_every_s": h.every,
            "rate": rate,
            "clogged": clogged,
            "history": self.history,
            "inventory": self.inventory,
            "coarse_inventory_rate": coarse_rate,
            "coarse_outside_regions_rate": outside_rate,
            "mass_balance": b,
            "mass_unaccounted_kg": float(b["unaccounted"]),
            "max_unaccounted_relative": self.max_unaccounted,
            "unaccounted_relative": abs(float(b["unaccounted"])) / total,
            "inserted_mass": float(b["inserted"]),
            "resolved_equivalent_particles": equivalent,
            "resolved_time_step_s": dt_resolved,
            "resolved_equivalent_particle_steps": particle_steps,
            "throughput_particle_steps_per_s": particle_steps / wall,
            "particles": self.peak_particles,
            "census_at_opening": self.at_opening,
            "census_at_peak": self.census_peak,
            "census_at_end": _census(h),
            "wall_clock_s": wall,
            "phases_s": self.phases,
            "level_wall_clock_s": list(h.wall_clock["levels"]),
            "exchange_wall_clock_s": float(h.wall_clock["exchange"]),
            "exchange_parts_s": dict(h.wall_clock["exchange_parts"]),
            "ranks": h.sims[0].ranks,
            "peak_memory_bytes": peak_memory(self.comm),
            "restart": {k: v for k, v in self.restart.items() if k != "balance"},
        }


def run_hierarchy(case: SiloCase, comm: Any, output: Path, say: Say, vtk: bool) -> dict[str, Any]:
    """The hierarchy's whole run (see HierarchyRun)."""
    return HierarchyRun(case, comm, output, say, vtk).run()


def nan_to_none(value: Any) -> Any:
    """JSON has no NaN: None in its place, recursively."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: nan_to_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [nan_to_none(v) for v in value]
    return value
