"""Multi-level coarse graining (MLCG, DESIGN.md 4; Queteschiner et al. 2018): several
resolutions of one material in one run, coupled two-way by volume-averaged fields.

A :class:`Hierarchy` is built from one reference :class:`~grainscale.scaling.ParameterSet` (the
fully resolved system, h = 1) and a list of :class:`~grainscale.Level` s: the coarsest simulates
the whole system, every finer one only its ``region`` (a box, a finite cylinder or a closed
mesh), which must lie inside the region of a coarser level, its parent. Each level is a complete
Simulation whose parameters come from :func:`grainscale.scaling.scale` with its ratio ``cg``
(scheme ``"cg"`` by default) and whose time step is its own (the exchange interval is a whole
number of steps of every level). The parent keeps simulating inside its child's region: its
particles there are the child's material at its own resolution (its "shadow").

**One material, exact books.** Each level holds the material where it is the finest (the
coarsest: outside every region); an exchange grid generated from each region carries it across
the interface faces. Every exchange interval (:class:`~grainscale.Exchange`):

1. the parent runs the interval; a flux meter books, per interface face, the mass its particles
   carry into the region (owed to the child) and out of it (owed by the child), and its particles
   removed inside the region (its outlets, closed sides);
2. the child pays what it is owed by inserting fine particles in a shell at each face (what finds
   no room waits, nothing is dropped) and what it owes by giving up its particles nearest to the
   face; it runs the interval; its particles that leave the region are deleted and owed back to
   it at their face. What the child discharges (outlets, closed sides) its parent owes too: the
   parent's own outflow pays that debt, and whatever the parent lags behind by more than
   ``Exchange.max_lag`` of its particles it pays by removing its particles in the interior cells
   where it holds more than the child (then nearest to where the child discharged): a coarse bed
   jammed at an orifice it cannot pass follows the fine discharge all the same. So the coarsest
   level always holds the inventory of the equipment, and
   :meth:`~grainscale.Hierarchy.mass_balance` closes to round-off. Where the child's boundary
   cells hold less than a dense parent bed above them, the child may also place particles ahead
   of the flux (``Exchange.advance``), which the flux then repays.
3. both levels average mass, Favre velocity, solid fraction and stress on the exchange cells, and
   the controllers of :mod:`grainscale.coupling` set (a) the fine -> coarse velocity feedback in
   the interior cells, limited by the child's velocities so that it starts a jammed coarse bed,
   (b) the coarse -> fine velocity condition in the boundary cells and (c) the coarse -> fine
   stress condition at the faces.

Python schedules; the per-particle work (flux meter, insertion, extraction, averaging, coupling
forces) is in C++ (cpp/coupling, cpp/field). Under MPI every level is decomposed over the same
communicator.

Example::

    h = gs.Hierarchy(
        base=reference,                                   # a gs.scaling.ParameterSet
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=gs.Box(lo=..., hi=...))],
        exchange=gs.Exchange(every=1e-3),
    )
    h.run(until=1.0)
    print(describe_balance(h.mass_balance()))
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from collections.abc import Sequence
from typing import Any, cast

import numpy as np

from . import _core, parallel, scaling
from ._validate import flag, positive
from .coupling import Coupling, StressBoundary, rest_speed
from .dist import Distribution
from .levels import (
    Exchange,
    Level,
    _bounds,
    _flowing,
    cell_size_range,
    cells_across,
    check_nesting,
    check_setup_record,
    describe_balance,
    find_parents,
    in_cells,
    setup_record,
)
from .materials import Material
from .simulation import Simulation
from .stopwatch import Stopwatch
from .strict_attributes import StrictAttributes
from .timestep import rayleigh_time

EXCHANGE_PARTS = ("flux", "extract", "insert", "sample", "controls", "settle", "output")

__all__ = ["Exchange", "Hierarchy", "Level", "describe_balance", "in_cells"]


class Hierarchy(StrictAttributes):
    """Levels of one material at several resolutions, coupled by volume-averaged fields, with
    the mass of the material conserved across the levels.

    Args:
        base: the reference (fully resolved, h = 1) parameter set; its insertions and particles
            go to the coarsest level (scaled), its walls and outlets to every level.
        levels: coarsest first (no region), then finer ones with regions, ratios decreasing.
        exchange: default coupling settings of every interface.
        scheme: scaling scheme of grainscale.scaling for the levels' parameters.
        comm: mpi4py communicator of every level (see grainscale.parallel), default as for
            Simulation.
        seed: seed of the fine levels' insertions.
        force_time_step: passed to every level's Simulation.

    A finer level starts empty and receives what its parent carries across the interface: the
    parent may hold no particles in the region at the start (fill by a Stream), and a region
    keeps clear of its parent's own interface (the parent's insertion shells) by a shell depth.

    ``wall_clock`` holds where this rank's time went (s): ``levels``, per level, stepping it,
    ``exchange``, the rest of the intervals (fields, controllers, insertion, books), and
    ``exchange_parts``, the latter per part (EXCHANGE_PARTS).
    """

    def __init__(
        self,
        base: scaling.ParameterSet,
        levels: Sequence[Level],
        exchange: Exchange | None = None,
        scheme: str = "cg",
        comm: Any = None,
        seed: int = 1,
        force_time_step: bool = False,
    ) -> None:
        if not isinstance(base, scaling.ParameterSet):
            raise ValueError(f"Hierarchy.base must be a gs.scaling.ParameterSet, got {base!r}")
        levels = list(levels)
        if len(levels) < 1 or not all(isinstance(lv, Level) for lv in levels):
            raise ValueError(
                f"Hierarchy.levels must be a non-empty list of gs.Level, got {levels!r}"
            )
        force_time_step = flag("Hierarchy", "force_time_step", force_time_step)
        self.exchange = exchange if exchange is not None else Exchange()
        if not isinstance(self.exchange, Exchange):
            raise ValueError(f"Hierarchy.exchange must be a gs.Exchange, got {exchange!r}")
        if levels[0].region is not None:
            raise ValueError(
                "Hierarchy.levels[0] (the coarsest) must cover the whole domain (region=None), "
                f"got region={levels[0].region!r}"
            )
        for k in range(1, len(levels)):
            if levels[k].region is None:
                raise ValueError(f"Hierarchy.levels[{k}].region must be given (a finer level)")
            if not levels[k].cg < levels[k - 1].cg:
                raise ValueError(
                    f"Hierarchy.levels[{k}].cg must be smaller than levels[{k - 1}].cg "
                    f"({levels[k - 1].cg}), got {levels[k].cg}"
                )
        self.base = base
        self.levels = levels
        self.scheme = scheme
        size, material = _flowing(base)
        self.material = material
        bounds = [_bounds(lv.region, base.domain) for lv in levels]
        self.parents = find_parents(bounds)
        self._build_levels(bounds, size, material, comm, force_time_step)
        self.couplings = [self._couple(k, int(seed) + 1000 * k) for k in range(1, len(levels))]
        check_nesting(self.couplings, self.parents, self.sizes, bounds)
        self._refuse_initial_shadow()
        self.intervals = 0
        # Wall-clock (s, this rank) stepping each level and in the exchanges, the latter also per
        # part (flux metering, extraction, insertion, sampling, fields and controllers, shadow
        # removal, output; a collective's part includes waiting for the other ranks).
        self._watch = Stopwatch(EXCHANGE_PARTS)
        self.wall_clock: dict[str, Any] = {
            "levels": [0.0] * len(levels),
            "exchange": 0.0,
            "exchange_parts": self._watch.seconds,
        }
        self._cell_output: Any = None  # io.cells.ExchangeCellSeries once output() is called
        self.initial_mass = sum(self._held())
        self._freeze_attributes()

    # ------------------------------------------------------------------ set-up
    def _build_levels(
        self,
        bounds: list[tuple[np.ndarray, np.ndarray]],
        size: Distribution,
        material: Material,
        comm: Any,
        force_time_step: bool,
    ) -> None:
        """Every level's parameters (grainscale.scaling.level_parameters), time step and
        Simulation."""
        reference = dataclasses.replace(self.base, size=size)

        def parameters(k: int, time_step: float | None) -> scaling.ParameterSet:
            return scaling.level_parameters(
                reference,
                self.levels[k].cg,
                self.scheme,
                region=None if k == 0 else bounds[k],
                region_material=None if k == 0 else material,
                time_step=time_step,
            )

        drafts = [parameters(k, None) for k in range(len(self.levels))]
        self.sizes: list[Distribution] = [cast(Distribution, p.size) for p in drafts]
        # Time steps: the exchange interval is a whole number of steps of every level.
        dts = [self._stable_step(p, s) for p, s in zip(drafts, self.sizes, strict=True)]
        every = self.exchange.every if self.exchange.every is not None else 25 * dts[0]
        self.every = float(every)
        self.steps = [max(1, math.ceil(self.every / dt * (1 - 1e-12))) for dt in dts]
        self.params = [parameters(k, self.every / n) for k, n in enumerate(self.steps)]
        self.sims: list[Simulation] = [
            scaling.build_simulation(
                p, comm=comm, quiet=True, record_contacts=True, force_time_step=force_time_step
            )
            for p in self.params
        ]

    def _couple(self, k: int, seed: int) -> Coupling:
        """The interface of level k with its parent: exchange grid, coupling forces, region
        outlet and controllers."""
        parent = self.parents[k]
        ex = self.levels[k].exchange or self.exchange
        psim, csim = self.sims[parent], self.sims[k]
        d_parent, d_child = 2 * self.sizes[parent].max_radius, 2 * self.sizes[k].max_radius
        owner = f"Hierarchy.levels[{k}].exchange.cell_size"
        lowest, default = cell_size_range(d_parent, d_child)
        spec = self.levels[k].region
        assert spec is not None  # a child level has a region (checked in __init__)
        region = spec._to_core(f"Hierarchy.levels[{k}]")

        def interface(cell: float) -> _core.Interface:
            # the parent's largest particle mass (kg): the dead band of the faces' ledgers
            parcel = (
                float(self.material.density) * 4 / 3 * math.pi * self.sizes[parent].max_radius ** 3
            )
            itf = _core.Interface(
                region=region,
                cell_size=float(cell),
                parent=psim.engine.core,
                fine_radius=self.sizes[k]._to_core(),
                fine_density=float(self.material.density),
                fine_material=csim.material_index(self.material),
                size_ratio=float(self.levels[parent].cg / self.levels[k].cg),
                deadband=parcel,
                seed=seed,
            )
            across = cells_across(itf.grid())
            if across is not None:
                raise ValueError(f"Exchange.cell_size must leave the region {across}, got {cell!r}")
            return itf

        if ex.cell_size is not None:
            if ex.cell_size < lowest * (1 - 1e-9):
                raise ValueError(
                    f"{owner} must be at least {lowest:.4g} m (1.5 parent and 2.5 child "
                    f"diameters), got {ex.cell_size!r}"
                )
            try:
                itf = interface(ex.cell_size)
            except ValueError as err:
                raise ValueError(f"{owner}: {err}") from None
        else:
            itf = self._default_interface(interface, default, lowest, k)
        c = Coupling(parent, k, itf, ex)
        c.advance.downward = c.grid["face_normal"] @ np.asarray(self.base.gravity, float) > 0
        c.advance.density = float(self.material.density)
        layer, fade = ex.layer * d_child, ex.fade * d_child
        c.parent_coupling = psim.engine.add_coupling(itf, layer, fade)
        c.child_coupling = csim.engine.add_coupling(itf, layer, fade)
        c.region_outlet = csim.engine.add_region_outlet(itf, 1, self.sizes[k].max_radius)
        ki = ex.stress_integral if ex.stress_integral is not None else 1.0 / (4 * self.every)
        g = float(np.linalg.norm(self.base.gravity))
        c.stress = StressBoundary(ex.stress_gain, ki, ex.skip_ratio, rest_speed(g, d_child), c.grid)
        return c

    def _default_interface(self, interface: Any, preferred: float, lowest: float, k: int) -> Any:
        """The interface with the largest cell edge in [lowest, preferred] that leaves the
        region interior cells (tried in steps of 5 %)."""
        cell = preferred
        while True:
            try:
                return interface(max(cell, lowest))
            except ValueError:
                if cell <= lowest:
                    break
                cell *= 0.95
        lo, hi = _bounds(self.levels[k].region, self.base.domain)
        raise ValueError(
            f"Hierarchy.levels[{k}].region (extent {tuple(np.round(hi - lo, 6))} m) is too small "
            f"for its parent's particles: exchange cells must be at least {lowest:.4g} m "
            f"(1.5 parent diameters) and the region needs 4 cells across between opposite "
            f"interface faces; make it at least {4 * lowest:.4g} m across there"
        )

    def _refuse_initial_shadow(self) -> None:
        held = self._shadow_mass()
        for c, m in zip(self.couplings, held, strict=True):
            if m > 0:
                raise ValueError(
                    f"Hierarchy: levels[{c.parent}] holds {m:.4g} kg of particles in the region "
                    f"of levels[{c.child}] at the start; a finer level starts empty and receives "
                    "what its parent carries across the interface: fill the system with a "
                    "Stream, or place the region where the parent holds no particles yet"
                )

    @staticmethod
    def _stable_step(p: scaling.ParameterSet, size: Distribution) -> float:
        if p.time_step is not None:
            return float(p.time_step)
        mats = [m for m in p.all_materials()]
        t = min(rayleigh_time(m, size.min_radius) for m in mats if isinstance(m, Material))
        return 0.2 * t

    # ------------------------------------------------------------------ state
    @property
    def time(self) -> float:
        """Simulated time (s) of the coarsest level (every level is at it between intervals)."""
        return self.sims[0].time

    def level(self, k: int) -> Simulation:
        """The Simulation of level k (0: the coarsest)."""
        return self.sims[k]

    def _masses(self, k: int, grids: list[dict[str, Any]]) -> tuple[float, list[float]]:
        """Collective: level k's particle mass outside all `grids`' region cells, and inside
        each."""
        sim = self.sims[k]
        with sim.particles(writable=False) as p:
            x, m = np.asarray(p.position), np.asarray(p.mass)
            outside = np.ones(len(m), bool)
            inside = []
            for g in grids:
                cells = in_cells(g, x)
                inside.append(float(m[cells].sum()))
                outside &= ~cells
            mine = [float(m[outside].sum()), *inside]
        total = [float(sim.sum_over_ranks(v)) for v in mine]
        return total[0], total[1:]

    def _held(self) -> list[float]:
        """Collective: per level, the mass of its particles where it is the finest level."""
        return [
            self._masses(k, [c.grid for c in self.couplings if c.parent == k])[0]
            for k in range(len(self.sims))
        ]

    def _shadow_mass(self) -> list[float]:
        """Collective: per interface, the parent's particle mass in the child's region cells."""
        return [self._masses(c.parent, [c.grid])[1][0] for c in self.couplings]

    def _removed(self, k: int) -> tuple[float, float]:
        """Level k's outlet removals and lost mass (kg, cumulative; the region outlets excluded:
        what leaves a region is owed back to it)."""
        sim = self.sims[k]
        return sum(o.removed_mass for o in sim.outlets), sim.engine.lost_mass

    def mass_balance(self) -> dict[str, Any]:
        """Collective: the books of the material the hierarchy represents (kg). Each level holds
        the material where it is the finest::

            initial + inserted = sum(held) + pending + discharged + lost   (+ unaccounted)

        with ``initial`` the mass at the start, ``inserted`` what the streams added, ``held`` per
        level, ``pending`` what the interfaces still owe their children (negative: owed back),
        ``discharged`` what left through outlets and ``lost`` through closed sides where the
        removing level was the finest. ``unaccounted`` is zero up to round-off. Per interface
        (``interfaces``): what the parent carried in and out, what left the child's region and
        was owed back (``returned``), inserted, extracted and pending; the child's removals
        (outlets, closed sides, the debts it paid), the parent's removals in the region and what
        it paid to follow, and its remaining ``debt``; ``shadow`` is the parent's mass in the
        region and ``child`` the child's, so that ``shadow = child + pending + debt``: the
        coarsest level holds the inventory of the equipment."""
        held = self._held()
        shadow = self._shadow_mass()
        interfaces, pending = [], 0.0
        for c, s in zip(self.couplings, shadow, strict=True):
            st = c.interface.inserter_status()
            p = float(st["pending_mass"].sum())
            pending += p
            child = self.sims[c.child]
            with child.particles(writable=False) as view:
                mine = float(np.asarray(view.mass).sum())
            interfaces.append(
                {
                    "parent": c.parent,
                    "child": c.child,
                    "carried_in": float(st["fed_mass"].sum()),
                    "carried_out": float(st["debited_mass"].sum()),
                    "returned": float(st["credited_mass"].sum()),
                    "inserted": float(st["inserted_mass"].sum()),
                    "extracted": float(st["extracted_mass"].sum()),
                    "pending": p,
                    "child_removed": c.child_removed,
                    "parent_removed": c.parent_discharged + c.parent_lost,
                    "paid": c.paid,
                    "debt": c.debt,
                    "shadow": s,
                    "child_mass": float(child.sum_over_ranks(mine)),
                }
            )
        removed = [self._removed(k) for k in range(len(self.sims))]
        discharged = sum(r[0] for r in removed) - sum(c.parent_discharged for c in self.couplings)
        lost = sum(r[1] for r in removed) - sum(c.parent_lost for c in self.couplings)
        inserted = sum(s.inserted_mass for sim in self.sims for s in sim.streams)
        unaccounted = self.initial_mass + inserted - (sum(held) + pending + discharged + lost)
        return {
            "initial": self.initial_mass,
            "inserted": inserted,
            "held": held,
            "pending": pending,
            "discharged": discharged,
            "lost": lost,
            "unaccounted": unaccounted,
            "interfaces": interfaces,
        }

    # ------------------------------------------------------------------ running
    def run(self, until: float | None = None, intervals: int | None = None) -> None:
        """Advance every level by whole exchange intervals: ``intervals`` of them, or up to
        simulated time ``until`` (s; rounded up to a whole interval). Collective."""
        if (until is None) == (intervals is None):
            raise ValueError(
                f"Hierarchy.run needs exactly one of until or intervals, got until={until!r}, "
                f"intervals={intervals!r}"
            )
        comm = self.sims[0].comm
        parallel.same_arguments(comm, "Hierarchy.run", until=until, intervals=intervals)
        if intervals is None:
            u = float(until)  # type: ignore[arg-type]
            if not math.isfinite(u):
                raise ValueError(f"Hierarchy.run.until must be finite (s), got {until!r}")
            if u < self.time - self.every:  # an interval short of now: rounding
                raise ValueError(
                    f"Hierarchy.run.until must not lie before the current time t = "
                    f"{self.time:.9g} s (a run goes forward), got {until!r} s"
                )
            intervals = max(0, math.ceil((u - self.time) / self.every * (1 - 1e-9)))
        if isinstance(intervals, bool) or int(intervals) != intervals or intervals < 0:
            raise ValueError(
                f"Hierarchy.run.intervals must be a non-negative integer, got {intervals!r}"
            )
        for _ in range(int(intervals)):
            self._interval()

    def _interval(self) -> None:
        start, stepped = time.perf_counter(), sum(self.wall_clock["levels"])
        part = self._watch.part
        for sim in self.sims:  # before the exchange touches any level's particles
            sim.engine.check_unseen_writes()
        for k, sim in enumerate(self.sims):
            level = sim.engine.core
            children = [c for c in self.couplings if c.parent == k]
            level.clear_lost_log()
            with part("flux"):
                for c in children:
                    c.interface.start_flux(level, float(np.max(c.grid["edge"])))
            # What the parent carried across the faces this interval is paid now.
            for c in self.couplings:
                if c.child == k and c.flux is not None:
                    with part("extract"):
                        c.interface.book(c.flux, c.beyond)
                        c.flux = None
                        c.interface.extract(level)
                        c.interface.allow_advance(c.advance.budget)
                    with part("insert"):
                        c.interface.insert(level, self.sims[c.parent].engine.core)
            touching = [c for c in self.couplings if c.parent == k or c.child == k]
            samples = min(self.exchange.samples, self.steps[k])
            done = 0
            for s in range(samples):
                n = (self.steps[k] * (s + 1)) // samples - done
                t0 = time.perf_counter()
                sim.run(steps=n, progress=False)
                self.wall_clock["levels"][k] += time.perf_counter() - t0
                done += n
                with part("sample"):
                    for c in touching:
                        c.interface.sample(level, c.child == k)
                        if c.child == k and c.stress is not None and c.stress.active:
                            c.stress.sample(level, c.child_coupling)
            with part("flux"):
                for c in children:
                    c.book_parent_interval(c.interface.finish_flux(level))
                for c in self.couplings:
                    if c.child == k:
                        c.credit_leavers(level)
        with part("controls"):
            for c in self.couplings:
                c.parent_fields = c.interface.finish_average(self.sims[c.parent].engine.core, False)
                c.child_fields = c.interface.finish_average(self.sims[c.child].engine.core, True)
                c.update_controls(self.every)
                c.apply_controls(self.sims[c.parent].engine.core, self.sims[c.child].engine.core)
        with part("settle"):
            for c in sorted(self.couplings, key=lambda c: -c.child):  # finest first: debts go up
                self._settle(c)
        self.intervals += 1
        with part("output"):
            if self._cell_output is not None:
                rank = self.sims[0].rank
                self._cell_output.write(self.time, self.intervals, self.couplings, rank,
                                        1e-9 * self.every)  # fmt: skip
        stepping = sum(self.wall_clock["levels"]) - stepped
        self.wall_clock["exchange"] += time.perf_counter() - start - stepping

    def _settle(self, c: Coupling) -> None:
        """Books what the child removed this interval and lets the parent pay the part of its
        debt beyond ``max_lag`` by removing its particles where it holds more than the child
        (Coupling.mass_excess), then nearest to where the child discharged."""
        child = self.sims[c.child]
        discharged, lost = self._removed(c.child)
        paid_below = sum(g.paid for g in self.couplings if g.parent == c.child)
        moment = sum((o.removed_moment for o in child.outlets), np.zeros(3))
        if discharged > c.discharge_mass:  # where the child discharged this interval
            c.discharge_point = (moment - c.discharge_moment) / (discharged - c.discharge_mass)
        c.discharge_moment, c.discharge_mass = moment, discharged
        c.child_removed = discharged + lost + paid_below
        r = self.sizes[c.parent].max_radius
        budget = c.debt - c.exchange.max_lag * float(self.material.density) * 4 / 3 * math.pi * r**3
        if budget > 0:
            level = self.sims[c.parent].engine.core
            excess = c.mass_excess()
            near = tuple(c.discharge_point)
            c.paid += float(c.interface.remove_shadow(level, excess, near, budget))

    # ------------------------------------------------------------------ fields and output
    def fields(self, interface: int = 0) -> dict[str, Any]:
        """The last interval's cell averages of both levels of interface ``interface``:
        ``{"grid": ..., "parent": ..., "child": ..., "pressure": ...}``."""
        c = self.couplings[interface]
        pressure = c.stress.pressure.copy() if c.stress is not None else np.zeros(0)
        return {"grid": c.grid, "parent": c.parent_fields, "child": c.child_fields,
                "pressure": pressure}  # fmt: skip

    def output(self, directory: str | os.PathLike[str], every: float) -> None:
        """VTK snapshots of every level every ``every`` s: ``<directory>/level<k>.pvd`` (with a
        ``level`` array) and, per interface, the cell fields of both levels at the end of each
        interval written as ``<directory>/cells<k>_<interval>.vtp`` (points at the cell centres)."""
        from pathlib import Path

        from .io import VTK
        from .io.cells import ExchangeCellSeries

        positive("Hierarchy.output", "every", every, " (s)")
        for k, sim in enumerate(self.sims):
            sim.output(VTK(directory, every=every, prefix=f"level{k}", level=k))
        self._cell_output = ExchangeCellSeries(Path(directory), float(every), self.time,
                                               len(self.couplings))  # fmt: skip

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self, path: str | os.PathLike[str]) -> None:
        """Collective: every level's state and the coupling state (controllers, the interfaces'
        ledgers and pending insertions, the books) in one HDF5 file (grainscale.io.checkpoint)."""
        from .io import checkpoint

        extra = {
            "levels": setup_record(self.levels),
            "intervals": self.intervals,
            "initial_mass": self.initial_mass,
            "couplings": [c.state() for c in self.couplings],
        }
        checkpoint.save_hierarchy(self.sims, path, json.dumps(extra))

    def restart(self, path: str | os.PathLike[str]) -> None:
        """Collective: continue from a checkpoint of a hierarchy with the same set-up (the
        levels' ratios and regions and each level's set-up are compared before anything
        changes: ValueError naming the file and the level). A checkpoint written before the
        hierarchy kept exact books restarts with its books opened at the restart (``initial``
        set so that nothing is unaccounted then)."""
        from .io import checkpoint

        def check(text: str) -> None:
            saved = json.loads(text)
            check_setup_record(saved.get("levels"), self.levels)
            if len(saved["couplings"]) != len(self.couplings):
                raise ValueError(
                    f"checkpoint holds {len(saved['couplings'])} interfaces, this hierarchy has "
                    f"{len(self.couplings)}"
                )

        names = [
            f"Hierarchy.levels[{k}] (cg={r['cg']!r}, region={r['region']})"
            for k, r in enumerate(setup_record(self.levels))
        ]
        text = checkpoint.load_hierarchy(self.sims, path, check, names)
        extra = json.loads(text)
        self.intervals = int(extra["intervals"])
        for c, state in zip(self.couplings, extra["couplings"], strict=True):
            c.load(state)
            c.apply_controls(self.sims[c.parent].engine.core, self.sims[c.child].engine.core)
        if "initial_mass" in extra:
            self.initial_mass = float(extra["initial_mass"])
        else:
            self.initial_mass = 0.0
            self.initial_mass = -float(self.mass_balance()["unaccounted"])
