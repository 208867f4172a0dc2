"""Multi-level coarse graining (MLCG, DESIGN.md 4; Queteschiner et al. 2018): several
resolutions of one system in one run, coupled two-way by volume-averaged fields.

A :class:`Hierarchy` is built from one reference :class:`~grainscale.scaling.ParameterSet`
(the fully resolved system, h = 1) and a list of :class:`Level` s: the coarsest simulates the
whole system, every finer one only its ``region`` (a box, a finite cylinder or a closed mesh),
which must lie inside the region of a coarser level, its parent. Each level is a complete
Simulation whose parameters come from :func:`grainscale.scaling.scale` with its ratio ``cg``
(scheme ``"cg"`` by default) and whose time step is its own (the exchange interval is a whole
number of steps of every level). Every exchange interval (:class:`Exchange`), coarse to fine:

1. the parent runs the interval; its particles entering the child's region cells are booked per
   interface face (mass, momentum, spin), on an exchange grid generated from the region;
2. the child receives that mass as fine particles placed in a shell at each face (what finds no
   room waits; nothing is dropped), plus, below a dense coarse bed, a top-up of what its boundary
   cell lacks (booked apart), runs the interval, and deletes its particles that leave the region
   cells;
3. both levels average mass, Favre velocity, solid fraction and stress on the exchange cells;
   the controllers then set (a) the fine -> coarse velocity feedback, an acceleration of the
   parent's particles in the interior cells towards the child's Favre velocity (times the solid
   fraction ratio when ``mass_flux_correction``), limited by the cell's velocity range, and
   (b) the coarse -> fine stress boundary condition, a PI controller per interface face
   (anti-windup, never pulling) whose pressure pushes the child's particles in a layer of
   ~1.3 fine diameters (sin^2 fade) so that the child's normal stress in the boundary cell
   follows the parent's; the child's stress there counts the push as the contacts it stands
   for (its virial: push force times distance from the face), and (c) the coarse -> fine
   velocity condition, an acceleration of the child's particles in the boundary cells towards
   the parent's Favre velocity (the shear and pace of the material beyond the faces).

Python schedules; the per-particle work (flux meter, insertion, averaging, coupling forces) is in
C++ (cpp/coupling, cpp/field). Under MPI every level is decomposed over the same communicator.

Example::

    h = gs.Hierarchy(
        base=reference,                                   # a gs.scaling.ParameterSet
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=gs.Box(lo=..., hi=...))],
        exchange=gs.Exchange(every=1e-3),
    )
    h.run(until=1.0)
    print(h.mass_balance())
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core, scaling
from ._validate import positive
from .dist import Distribution, as_distribution
from .geometry import Box, Cylinder, Mesh
from .insert import Pack, Stream, _core_region
from .materials import Material
from .simulation import Simulation
from .timestep import rayleigh_time

Region = Box | Cylinder | Mesh


@dataclass(frozen=True)
class Exchange:
    """Coupling settings of an interface between a level and its finer child.

    Args:
        cell_size: exchange cell edge (m); default 5 largest diameters of the parent level.
        every: exchange interval (s); default 25 time steps of the coarsest level. The levels'
            time steps are shortened, if needed, to divide it.
        samples: cell-average samples per interval and level.
        velocity_gain: fraction of the velocity difference fine - coarse removed per interval in
            the interior cells (0 switches the feedback off).
        mass_flux_correction: scale the fine Favre velocity by phi_fine / phi_coarse.
        stress_gain: proportional gain of the stress controller (Pa per Pa; 0 and a zero
            ``stress_integral`` switch the stress condition off).
        stress_integral: integral gain (1/s); default 1 / (4 every).
        layer: thickness of the pushed layer, in largest fine diameters.
        fade: width of its sin^2 fade, in largest fine diameters.
        skip_ratio: no stress control in a cell whose coarse solid fraction is below
            skip_ratio x the fine one (a nearly empty coarse cell has no stress to follow).
        boundary_velocity_gain: fraction of the velocity difference coarse - fine removed per
            interval in the fine level's boundary cells (Favre velocities, every component): the
            shear and the pace the material beyond the faces imposes, which the normal push
            cannot (without it a side face acts as a frictionless wall); 0 switches it off.
        top_up: on the faces gravity points into, the fine level may place extra particles in
            its insertion shell, up to top_up x the solid the coarse cell holds beyond the
            fine one, (phi_c - phi_f) rho V per interval, in cells whose coarse solid fraction
            is at least ``top_up_min_fraction``: the dense bed above a face sinks into the room
            the fine bed leaves, which the coarse crossing flux does not see. Booked apart
            (``topped_up`` in :meth:`Hierarchy.mass_balance`); 0 switches it off.
        top_up_min_fraction: the coarse solid fraction from which a cell counts as a dense bed
            (default 0.49, near the freezing point of hard spheres, 0.494: Hoover & Ree, J. Chem.
            Phys. 49 (1968) 3609). A dilute stream is carried by the flux alone: its deficit
            would be topped up again every interval while the same grains cross the cell.
    """

    cell_size: float | None = None
    every: float | None = None
    samples: int = 4
    velocity_gain: float = 0.1
    mass_flux_correction: bool = True
    stress_gain: float = 0.5
    stress_integral: float | None = None
    layer: float = 1.3
    fade: float = 0.25
    skip_ratio: float = 0.5
    boundary_velocity_gain: float = 1.0
    top_up: float = 1.0
    top_up_min_fraction: float = 0.49

    def __post_init__(self) -> None:
        for name in ("cell_size", "every", "stress_integral"):
            if getattr(self, name) is not None:
                positive("Exchange", name, getattr(self, name))
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 1:
            raise ValueError(f"Exchange.samples must be a positive integer, got {self.samples!r}")
        for name in (
            "velocity_gain",
            "stress_gain",
            "skip_ratio",
            "boundary_velocity_gain",
            "top_up",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"Exchange.{name} must be non-negative and finite, got {v!r}")
        for name in ("velocity_gain", "boundary_velocity_gain"):
            if getattr(self, name) > 1:
                raise ValueError(f"Exchange.{name} must be in [0, 1], got {getattr(self, name)}")
        positive("Exchange", "layer", self.layer, " (fine diameters)")
        positive("Exchange", "fade", self.fade, " (fine diameters)")
        if not (
            isinstance(self.top_up_min_fraction, int | float) and 0 <= self.top_up_min_fraction < 1
        ):
            raise ValueError(
                f"Exchange.top_up_min_fraction must be in [0, 1), got {self.top_up_min_fraction!r}"
            )
        if self.fade > self.layer:
            raise ValueError(f"Exchange.fade must be at most layer ({self.layer}), got {self.fade}")


@dataclass(frozen=True)
class Level:
    """One resolution of a :class:`Hierarchy`.

    Args:
        cg: coarse-graining ratio h against the reference (1: fully resolved).
        region: where the level lives (Box, finite Cylinder, closed Mesh); None for the
            coarsest level, which covers the whole domain.
        exchange: settings of the interface to its parent (default: the hierarchy's).
    """

    cg: float
    region: Region | None = None
    exchange: Exchange | None = None

    def __post_init__(self) -> None:
        positive("Level", "cg", self.cg)
        if self.region is not None and not isinstance(self.region, Box | Cylinder | Mesh):
            raise ValueError(
                f"Level.region must be a gs.Box, gs.geometry.Cylinder or gs.geometry.Mesh, "
                f"got {self.region!r}"
            )
        if self.exchange is not None and not isinstance(self.exchange, Exchange):
            raise ValueError(f"Level.exchange must be a gs.Exchange, got {self.exchange!r}")


def _bounds(region: Region | None, domain: Box) -> tuple[np.ndarray, np.ndarray]:
    if region is None:
        return np.asarray(domain.lo, float), np.asarray(domain.hi, float)
    lo, hi = _core_region(region, "Level", allow_mesh=True).bounds()
    return np.asarray(lo, float), np.asarray(hi, float)


def _flowing(base: scaling.ParameterSet) -> tuple[Distribution, Material]:
    """The size distribution and material of the particles the hierarchy resolves."""
    material = None
    for op in base.insertions:
        if isinstance(op, Pack | Stream):
            material = op.material
            break
    if material is None and base.particles:
        material = base.particles[0].material
    size = base.size
    if size is None:
        for op in base.insertions:
            size = as_distribution(op.radius, "Hierarchy", "base.size")
            break
    if size is None or material is None:
        raise ValueError(
            "Hierarchy.base must insert particles (a Pack or Stream in insertions) or give size "
            "and particles, so that the fine levels know their particles, got neither"
        )
    return as_distribution(size, "Hierarchy", "base.size"), material


def describe_balance(b: dict[str, float]) -> str:
    """One line of a :meth:`Hierarchy.mass_balance` entry, in grams (unaccounted in kg)."""
    return (
        f"interface {b['parent']:g} -> {b['child']:g}: expected {b['expected'] * 1e3:.3f} g, "
        f"inserted {b['inserted'] * 1e3:.3f} g, pending {b['pending'] * 1e3:.4f} g, "
        f"unaccounted {b['unaccounted']:.2e} kg"
        + (f"; topped up {b['topped_up'] * 1e3:.3f} g" if b.get("topped_up", 0) > 0 else "")
    )


class _Coupled:
    """One parent-child pair: the C++ interface and the controllers' state."""

    def __init__(self, parent: int, child: int, interface: _core.Interface, ex: Exchange) -> None:
        self.parent = parent
        self.child = child
        self.interface = interface
        self.exchange = ex
        grid = interface.grid()
        self.grid = grid
        self.n_faces = len(grid["face_cell"])
        self.integral = np.zeros(self.n_faces)
        self.pressure = np.zeros(self.n_faces)
        self.max_inward = np.zeros(self.n_faces)
        # The pushed layer's virial per face (N m), summed over this interval's child samples.
        self.push_moment = np.zeros(self.n_faces)
        self.push_samples = 0
        self.acceleration = np.zeros((len(grid["inside"]), 3))
        self.child_acceleration = np.zeros((len(grid["inside"]), 3))
        self.top_up = np.zeros(self.n_faces)
        self.top_up_velocity = np.zeros((self.n_faces, 3))
        self.downward = np.zeros(self.n_faces, bool)
        self.cell_volume = 0.0
        self.parent_coupling = -1
        self.child_coupling = -1
        self.outlet = -1
        self.flux: dict[str, np.ndarray] | None = None
        self.parent_fields: dict[str, Any] | None = None
        self.child_fields: dict[str, Any] | None = None


class Hierarchy:
    """Levels of one system at several resolutions, coupled by volume-averaged fields.

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
        dom_lo, dom_hi = np.asarray(base.domain.lo, float), np.asarray(base.domain.hi, float)
        tol = 1e-9 * float(np.max(dom_hi - dom_lo))
        bounds = [_bounds(lv.region, base.domain) for lv in levels]
        self.parents = [-1]
        for k in range(1, len(levels)):
            lo, hi = bounds[k]
            if np.any(lo < dom_lo - tol) or np.any(hi > dom_hi + tol):
                raise ValueError(
                    f"Hierarchy.levels[{k}].region must lie inside the domain "
                    f"[{tuple(dom_lo)}, {tuple(dom_hi)}], got bounds [{tuple(lo)}, {tuple(hi)}]"
                )
            # The parent: the finest coarser level whose region holds this one.
            parent = 0
            for j in range(1, k):
                plo, phi = bounds[j]
                if np.all(lo >= plo - tol) and np.all(hi <= phi + tol):
                    parent = j
            self.parents.append(parent)

        # Every level's parameters from the reference, by the scaling scheme.
        self.params: list[scaling.ParameterSet] = []
        self.sizes: list[Distribution] = []
        for k, lv in enumerate(levels):
            scaled = scaling.scale(base, lv.cg, scheme).params
            if k > 0:  # a region: no insertions, no particles, a box around the region
                lo, hi = bounds[k]
                d = scaled.size if scaled.size is not None else None
                dmax = 2 * (d.max_radius if d is not None else lv.cg * size.max_radius)
                margin = 2 * dmax
                box_lo = np.maximum(lo - margin, dom_lo)
                box_hi = np.minimum(hi + margin, dom_hi)
                periodic = tuple(
                    bool(base.domain.periodic[a])
                    and lo[a] <= dom_lo[a] + tol
                    and hi[a] >= dom_hi[a] - tol
                    for a in range(3)
                )
                scaled = dataclasses.replace(
                    scaled,
                    domain=Box(lo=tuple(box_lo), hi=tuple(box_hi), periodic=periodic),
                    insertions=(),
                    particles=(),
                    materials=(*scaled.materials, material),
                )
            self.params.append(scaled)
            self.sizes.append(
                scaling.scale(dataclasses.replace(base, size=size), lv.cg, scheme).params.size  # type: ignore[arg-type]
            )

        # Time steps: the exchange interval is a whole number of steps of every level.
        dts = [self._stable_step(p, s) for p, s in zip(self.params, self.sizes, strict=True)]
        every = self.exchange.every if self.exchange.every is not None else 25 * dts[0]
        self.every = float(every)
        self.steps = [max(1, math.ceil(self.every / dt * (1 - 1e-12))) for dt in dts]
        self.sims: list[Simulation] = []
        for k, p in enumerate(self.params):
            d_max = 2 * self.sizes[k].max_radius
            p = dataclasses.replace(
                p,
                time_step=self.every / self.steps[k],
                skin=p.skin if p.skin is not None else 0.1 * d_max,
            )
            self.params[k] = p
            sim = scaling.build_simulation(
                p, comm=comm, quiet=True, record_contacts=True, force_time_step=force_time_step
            )
            self.sims.append(sim)

        # Interfaces.
        self.couplings: list[_Coupled] = []
        for k in range(1, len(levels)):
            parent = self.parents[k]
            ex = levels[k].exchange or self.exchange
            psim, csim = self.sims[parent], self.sims[k]
            cell = ex.cell_size if ex.cell_size is not None else 10 * self.sizes[parent].max_radius
            d_fine = 2 * self.sizes[k].max_radius
            region = _core_region(levels[k].region, f"Hierarchy.levels[{k}]", allow_mesh=True)
            itf = _core.Interface(
                region,
                float(cell),
                psim._level,
                self.sizes[k]._to_core(),
                float(material.density),
                csim.material_index(material),
                float(levels[parent].cg / levels[k].cg),
                int(seed) + 1000 * k,
                float(ex.layer * d_fine),
                float(ex.fade * d_fine),
            )
            c = _Coupled(parent, k, itf, ex)
            # For the top-up: the faces gravity points into, and the cell volume.
            c.downward = c.grid["face_normal"] @ np.asarray(base.gravity, float) > 0
            c.cell_volume = float(np.prod(c.grid["edge"]))
            c.parent_coupling = int(
                psim._level.add_coupling(itf, ex.layer * d_fine, ex.fade * d_fine)
            )
            c.child_coupling = int(
                csim._level.add_coupling(itf, ex.layer * d_fine, ex.fade * d_fine)
            )
            c.outlet = int(csim._level.add_region_outlet(itf, 1))
            self.couplings.append(c)
        self.intervals = 0
        self._cell_output: dict[str, Any] | None = None

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

    def mass_balance(self) -> list[dict[str, float]]:
        """Collective: per interface, the mass (kg) the parent carried into the region
        (expected), inserted into the child, pending (scheduled or owed, not yet placed), the
        top-up placed on top of the flux (``Exchange.top_up``), the child's particles deleted
        on leaving the region, the child's own outlets' removals, the mass the child holds
        (inserted + topped_up - deleted_leaving - removed_by_outlets), and what is unaccounted
        for (expected - inserted - pending, zero up to round-off)."""
        out = []
        for c in self.couplings:
            s = c.interface.inserter_status()
            csim = self.sims[c.child]
            with csim.particles(writable=False) as p:
                held = float(csim.sum_over_ranks(float(p.mass.sum())))
            left = float(csim._level.outlet_status(c.outlet)["removed_mass"])
            own = sum(o.removed_mass for o in csim.outlets)  # the child's own (base) outlets
            expected = float(s["fed_mass"].sum())
            inserted = float(s["inserted_mass"].sum())
            pending = float(s["pending_mass"].sum())
            out.append(
                {
                    "parent": c.parent,
                    "child": c.child,
                    "expected": expected,
                    "inserted": inserted,
                    "pending": pending,
                    "topped_up": float(s["topped_up_mass"].sum()),
                    "deleted_leaving": float(left),
                    "removed_by_outlets": float(own),
                    "held": held,
                    "unaccounted": expected - inserted - pending,
                }
            )
        return out

    # ------------------------------------------------------------------ running
    def run(self, until: float | None = None, intervals: int | None = None) -> None:
        """Advance every level by whole exchange intervals: ``intervals`` of them, or up to
        simulated time ``until`` (s; rounded up to a whole interval). Collective."""
        if (until is None) == (intervals is None):
            raise ValueError(
                f"Hierarchy.run needs exactly one of until or intervals, got until={until!r}, "
                f"intervals={intervals!r}"
            )
        if intervals is None:
            u = float(until)  # type: ignore[arg-type]
            if not math.isfinite(u):
                raise ValueError(f"Hierarchy.run.until must be finite (s), got {until!r}")
            intervals = max(0, math.ceil((u - self.time) / self.every * (1 - 1e-9)))
        if isinstance(intervals, bool) or int(intervals) != intervals or intervals < 0:
            raise ValueError(
                f"Hierarchy.run.intervals must be a non-negative integer, got {intervals!r}"
            )
        for _ in range(int(intervals)):
            self._interval()

    def _interval(self) -> None:
        for k, sim in enumerate(self.sims):
            # Particles the parent carried in during this interval enter now.
            for c in self.couplings:
                if c.child == k and c.flux is not None:
                    c.interface.feed(c.flux)
                    c.interface.allow_top_up(c.top_up, c.top_up_velocity)
                    c.interface.insert(sim._level)
            children = [c for c in self.couplings if c.parent == k]
            for c in children:
                margin = float(np.max(c.grid["edge"]))
                c.interface.start_flux(sim._level, margin)
            touching = [c for c in self.couplings if c.parent == k or c.child == k]
            samples = min(self.exchange.samples, self.steps[k])
            done = 0
            for s in range(samples):
                n = (self.steps[k] * (s + 1)) // samples - done
                sim.run(steps=n, progress=False)
                done += n
                for c in touching:
                    c.interface.sample(sim._level, c.child == k)
                    if c.child == k and c.child_coupling >= 0:
                        c.push_moment += sim._level.coupling_push_moment(c.child_coupling)
                        c.push_samples += 1
            for c in children:
                c.flux = c.interface.finish_flux(sim._level)
        for c in self.couplings:
            c.parent_fields = c.interface.finish_average(self.sims[c.parent]._level, False)
            c.child_fields = c.interface.finish_average(self.sims[c.child]._level, True)
            self._control(c)
            c.push_moment[:] = 0.0
            c.push_samples = 0
        self.intervals += 1
        self._write_cells()

    def _control(self, c: _Coupled) -> None:
        ex = c.exchange
        pf, cf = c.parent_fields, c.child_fields
        assert pf is not None and cf is not None
        inside = c.grid["inside"] > 0
        boundary = c.grid["boundary"] > 0
        T = self.every
        # Fine -> coarse: velocity feedback in the interior cells that hold both levels.
        psim, csim = self.sims[c.parent], self.sims[c.child]
        if ex.velocity_gain > 0:
            coupled = inside & ~boundary & (pf["mass"] > 0) & (cf["mass"] > 0)
            chi = np.ones(len(inside))
            if ex.mass_flux_correction:
                with np.errstate(divide="ignore", invalid="ignore"):
                    chi = np.where(coupled, cf["solid_fraction"] / pf["solid_fraction"], 1.0)
            du = ex.velocity_gain * (chi[:, None] * cf["velocity"] - pf["velocity"])
            span = np.maximum(pf["velocity_max"] - pf["velocity_min"], 0.0)
            du = np.clip(du, -span, span)  # limiter: at most the cell's own velocity range
            du[~coupled] = 0.0
            c.acceleration = du / T
            psim._level.set_coupling_acceleration(c.parent_coupling, c.acceleration)
        # Coarse -> fine top-up through the faces gravity points into: where the coarse cell
        # is a dense bed holding more solid than the fine one, the fine level may fill its shell
        # with up to top_up x the difference (booked apart from the flux in the mass balance).
        if ex.top_up > 0:
            cells = c.grid["face_cell"].astype(int)
            phi_c = pf["solid_fraction"][cells]
            deficit = np.maximum(phi_c - cf["solid_fraction"][cells], 0.0)
            fed = c.downward & (phi_c >= ex.top_up_min_fraction)
            rho = float(self.material.density)
            c.top_up = np.where(fed, ex.top_up * deficit * rho * c.cell_volume, 0.0)
            c.top_up_velocity = pf["velocity"][cells]
        # Coarse -> fine, velocity condition: the boundary cells' velocity relaxed towards the
        # coarse one. Every component: relaxing only those along the faces left the fine
        # top cells falling 20 % too fast (docs/studies/mlcg_silo/NOTES.md).
        if ex.boundary_velocity_gain > 0:
            held = inside & boundary & (pf["mass"] > 0) & (cf["mass"] > 0)
            du = ex.boundary_velocity_gain * (pf["velocity"] - cf["velocity"])
            span = np.maximum(cf["velocity_max"] - cf["velocity_min"], 0.0)
            du = np.clip(du, -span, span)  # limiter: at most the fine cell's velocity range
            du[~held] = 0.0
            c.child_acceleration = du / T
            csim._level.set_coupling_acceleration(c.child_coupling, c.child_acceleration)
        # Coarse -> fine: stress boundary condition, a PI controller per interface face.
        kp = ex.stress_gain
        ki = ex.stress_integral if ex.stress_integral is not None else 1.0 / (4 * T)
        if kp > 0 or ki > 0:
            cells = c.grid["face_cell"].astype(int)
            axes = c.grid["face_axis"].astype(int)
            normal = c.grid["face_normal"]
            sc = pf["stress"][cells, axes, axes]
            # The fine cell's stress counts the push as the contacts with the material beyond
            # the face it stands for (their virial, push force x distance from the face): the
            # load the pushed layer passes on is what the coarse cell carries, not the cell
            # average that ramps up from zero across the layer.
            volume = float(np.prod(c.grid["edge"]))
            key = cells * 3 + axes  # faces of one cell along one axis share its sigma_aa
            moment = np.zeros(3 * len(inside))
            np.add.at(moment, key, c.push_moment)
            pushed = moment[key] / (max(c.push_samples, 1) * volume)
            sf = cf["stress"][cells, axes, axes] + pushed
            phi_c, phi_f = pf["solid_fraction"][cells], cf["solid_fraction"][cells]
            active = (pf["mass"][cells] > 0) & (phi_c >= ex.skip_ratio * phi_f)
            # The fine cell carries the coarse cell's normal stress (stress is invariant under CG
            # scaling, and so the load passed into the region balances the coarse one's even
            # where the fine level fills its boundary cell less densely); the variants measured
            # (sigma / phi, the push's virial left out) are in docs/studies/mlcg_silo/NOTES.md.
            target = np.where(active, sc, 0.0)
            error = np.where(active, target - sf, 0.0)
            trial = c.integral + error * T
            p = kp * error + ki * trial
            # Anti-windup (conditional integration): the integral stops while the output is
            # clipped (never pulling, at most 10 x the coarse stress) and the error drives it
            # further out, and (frozen, not reset) on faces not controlled this interval.
            p_max = 10.0 * np.maximum(sc, 0.0)
            saturated = ((p < 0) & (error < 0)) | ((p > p_max) & (error > 0)) | ~active
            c.integral = np.where(saturated, c.integral, trial)
            c.pressure = np.where(active, np.clip(p, 0.0, p_max), 0.0)
            # Limiter: no push on particles moving inward faster than the coarse ones do (their
            # largest speed along the inward normal n = +-e_axis), nor faster than a tenth of the
            # free-fall speed over a fine diameter when the coarse bed is at rest.
            extreme = np.where(normal > 0, pf["velocity_max"][cells], pf["velocity_min"][cells])
            coarse_in = np.einsum("ij,ij->i", extreme, normal)
            g = float(np.linalg.norm(self.base.gravity))
            floor = 0.1 * math.sqrt(g * 2 * self.sizes[c.child].max_radius)
            c.max_inward = np.maximum(coarse_in, floor)
            csim._level.set_coupling_pressure(c.child_coupling, c.pressure, c.max_inward)

    def _apply_controls(self, c: _Coupled) -> None:
        ex = c.exchange
        if ex.velocity_gain > 0:
            self.sims[c.parent]._level.set_coupling_acceleration(c.parent_coupling, c.acceleration)
        if ex.boundary_velocity_gain > 0:
            self.sims[c.child]._level.set_coupling_acceleration(
                c.child_coupling, c.child_acceleration
            )
        if ex.stress_gain > 0 or ex.stress_integral is None or ex.stress_integral > 0:
            self.sims[c.child]._level.set_coupling_pressure(
                c.child_coupling, c.pressure, c.max_inward
            )

    # ------------------------------------------------------------------ fields
    def fields(self, interface: int = 0) -> dict[str, Any]:
        """The last interval's cell averages of both levels of interface ``interface``:
        ``{"grid": ..., "parent": ..., "child": ..., "pressure": ...}``."""
        c = self.couplings[interface]
        return {
            "grid": c.grid,
            "parent": c.parent_fields,
            "child": c.child_fields,
            "pressure": c.pressure.copy(),
        }

    def output(self, directory: str | os.PathLike[str], every: float) -> None:
        """VTK snapshots of every level every ``every`` s: ``<directory>/level<k>.pvd`` (with a
        ``level`` array) and, per interface, the cell fields of both levels at the end of each
        interval written as ``<directory>/cells<k>_<interval>.vtp`` (points at the cell centres)."""
        from pathlib import Path

        from .io import VTK, PVDSeries

        positive("Hierarchy.output", "every", every, " (s)")
        for k, sim in enumerate(self.sims):
            sim.output(VTK(directory, every=every, prefix=f"level{k}", level=k))
        path = Path(directory)
        self._cell_output = {
            "directory": path,
            "every": float(every),
            "next": self.time,
            "series": [PVDSeries(path / f"cells{k}.pvd") for k in range(len(self.couplings))],
        }

    def _write_cells(self) -> None:
        from .io import write_vtp

        out = self._cell_output
        if out is None or self.time < out["next"] - 1e-9 * self.every:
            return
        out["next"] += out["every"] * max(1, math.ceil((self.time - out["next"]) / out["every"]))
        if self.sims[0].rank != 0:
            return
        out["directory"].mkdir(parents=True, exist_ok=True)
        for k, c in enumerate(self.couplings):
            g, pf, cf = c.grid, c.parent_fields, c.child_fields
            assert pf is not None and cf is not None
            cells = np.flatnonzero(g["inside"] > 0)
            dims, origin, edge = np.array(g["dims"]), np.array(g["origin"]), np.array(g["edge"])
            ijk = np.stack(
                [cells % dims[0], (cells // dims[0]) % dims[1], cells // (dims[0] * dims[1])], 1
            )
            centres = origin + (ijk + 0.5) * edge
            data = {"boundary": g["boundary"][cells].astype(np.int32)}
            for name, fields in (("coarse", pf), ("fine", cf)):
                data[f"{name}_mass"] = fields["mass"][cells]
                data[f"{name}_solid_fraction"] = fields["solid_fraction"][cells]
                data[f"{name}_velocity"] = fields["velocity"][cells]
                data[f"{name}_stress"] = fields["stress"][cells].reshape(-1, 9)
            name = f"cells{k}_{self.intervals:08d}.vtp"
            write_vtp(out["directory"] / name, centres, data)
            out["series"][k].add(self.time, name)

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self, path: str | os.PathLike[str]) -> None:
        """Collective: every level's state and the coupling state (controllers, pending
        insertions, the last fluxes) in one HDF5 file (see grainscale.io.checkpoint)."""
        from .io import checkpoint

        extra = {
            "intervals": self.intervals,
            "couplings": [
                {
                    "integral": c.integral.tolist(),
                    "pressure": c.pressure.tolist(),
                    "max_inward": c.max_inward.tolist(),
                    "acceleration": c.acceleration.tolist(),
                    "child_acceleration": c.child_acceleration.tolist(),
                    "top_up": c.top_up.tolist(),
                    "top_up_velocity": c.top_up_velocity.tolist(),
                    "inserters": list(c.interface.inserter_states()),
                    "flux": None
                    if c.flux is None
                    else {k: np.asarray(v).tolist() for k, v in c.flux.items()},
                }
                for c in self.couplings
            ],
        }
        checkpoint.save_hierarchy(self.sims, path, json.dumps(extra))

    def restart(self, path: str | os.PathLike[str]) -> None:
        """Collective: continue from a checkpoint of a hierarchy with the same set-up."""
        from .io import checkpoint

        text = checkpoint.load_hierarchy(self.sims, path)
        extra = json.loads(text)
        if len(extra["couplings"]) != len(self.couplings):
            raise ValueError(
                f"checkpoint holds {len(extra['couplings'])} interfaces, this hierarchy has "
                f"{len(self.couplings)}"
            )
        self.intervals = int(extra["intervals"])
        for c, state in zip(self.couplings, extra["couplings"], strict=True):
            c.integral = np.asarray(state["integral"], float)
            c.pressure = np.asarray(state["pressure"], float)
            c.max_inward = np.asarray(state["max_inward"], float)
            c.acceleration = np.asarray(state["acceleration"], float).reshape(-1, 3)
            if "child_acceleration" in state:  # written since the velocity condition and top-up
                c.child_acceleration = np.asarray(state["child_acceleration"], float).reshape(-1, 3)
                c.top_up = np.asarray(state["top_up"], float)
                c.top_up_velocity = np.asarray(state["top_up_velocity"], float).reshape(-1, 3)
            self._apply_controls(c)
            c.interface.load_inserter_states(state["inserters"])
            c.flux = (
                None
                if state["flux"] is None
                else {k: np.asarray(v, float) for k, v in state["flux"].items()}
            )
