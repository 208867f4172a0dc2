"""The declarative parts of a multi-level hierarchy (grainscale.hierarchy): the :class:`Level` s
and the :class:`Exchange` settings of their interfaces, the rules for exchange cells, and the
description of the hierarchy's books.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import scaling
from ._validate import flag, non_negative, positive
from .dist import Distribution, as_distribution
from .geometry import Box, Cylinder, Mesh
from .insert import Pack, Stream
from .materials import Material
from .sim_checkpoint import geometry_record

Region = Box | Cylinder | Mesh

# Exchange cells: by default CELL_PARENT_DIAMETERS largest parent diameters; never below
# MIN_CELL_PARENT_DIAMETERS (a cell must hold a few parent particles for its averages to mean
# anything) nor below MIN_CELL_CHILD_DIAMETERS (the child's insertion shell and stress layer must
# fit in a cell).
CELL_PARENT_DIAMETERS = 2.0
MIN_CELL_PARENT_DIAMETERS = 1.5
MIN_CELL_CHILD_DIAMETERS = 2.5
# A region keeps this many largest parent radii clear of its parent's interface faces (the
# parent's insertion shells, check_nesting).
NESTING_RADII = 5.0


def cell_size_range(parent_diameter: float, child_diameter: float) -> tuple[float, float]:
    """(lowest, default) exchange cell edge (m) of an interface between particles of largest
    diameters ``parent_diameter`` and ``child_diameter`` (m): the default is
    CELL_PARENT_DIAMETERS parent diameters, never below lowest = max(1.5 parent, 2.5 child
    diameters); the hierarchy reduces it towards lowest only where a region is too small for
    its cells across (cells_across)."""
    lowest = max(
        MIN_CELL_PARENT_DIAMETERS * parent_diameter, MIN_CELL_CHILD_DIAMETERS * child_diameter
    )
    return lowest, max(CELL_PARENT_DIAMETERS * parent_diameter, lowest)


@dataclass(frozen=True)
class Exchange:
    """Coupling settings of an interface between a level and its finer child.

    Args:
        cell_size: exchange cell edge (m; the edges are the nearest that tile the region's
            bounding box). Default: 2 largest diameters of the parent level, reduced (not below
            the valid range) until the region is 4 cells across between opposite interface
            faces (2 where one side is closed), so that it has two layers of interior cells,
            where the child's flow drives the parent's. Valid range: at least max(1.5 parent
            diameters, 2.5 child diameters), at most what keeps those 4 (2) cells; outside it
            the hierarchy refuses the grid with a clear error. With one interior layer the
            parent's following rests on a single column of cells, and the discharge rate of
            studies/mlcg_jam fell by 20 %; across the range it holds within 5 % where the
            region is large enough (see Level.region).
        every: exchange interval (s); default 25 time steps of the coarsest level. The levels'
            time steps are shortened, if needed, to divide it.
        samples: cell-average samples per interval and level.
        velocity_gain: fine -> coarse feedback, the fraction of the velocity difference
            chi u_fine - u_coarse removed per interval in the interior cells (0 switches it off).
        mass_flux_correction: chi = phi_fine / phi_coarse (else 1), so that the parent carries
            the child's mass flux where it packs more loosely.
        stress_gain: proportional gain of the stress controller (Pa per Pa; 0 and a zero
            ``stress_integral`` switch the stress condition off).
        stress_integral: integral gain (1/s); default 1 / (4 every).
        layer: thickness of the pushed layer, in largest child diameters.
        fade: width of its sin^2 fade, in largest child diameters.
        skip_ratio: no stress control in a cell whose parent solid fraction is below
            skip_ratio x the child's (a nearly empty parent cell has no stress to follow).
        boundary_velocity_gain: coarse -> fine, the fraction of the velocity difference
            u_coarse - u_fine removed per interval in the child's boundary cells (every
            component): the shear and the pace the material beyond the faces imposes, which the
            normal push cannot; 0 switches it off.
        shear_traction: coarse -> fine, the fraction of the tangential traction the parent's
            material beyond each face carries (its cell stress on the face) that acts on the
            child's particles in the face's cell: the friction of the slower material beside a
            flowing zone (a silo's dead zones beside the orifice's converging flow), which the
            normal push cannot give; 0 switches it off.
        max_lag: how far (in largest parent particles' mass) the parent's own outflow from the
            region may lag behind the child's discharge before the parent pays the rest by
            removing its particles in the region where it holds more than the child.
        advance: below a dense parent bed (faces gravity points into, parent cell solid
            fraction at least ``advance_min_fraction``) the child may place particles ahead of
            the flux, up to advance x (phi - phi_child) rho V of the face's cell per interval,
            phi the smaller of the parent's solid fraction there and the child's one cell further
            in (its own packing away from the face): the bed above sinks into the room the
            child's bed leaves below it, which the parent's crossings deliver later, in amounts
            its own packing sets. What the parent then carries in repays the advance before
            anything more is placed; an outstanding advance is negative pending in the books
            (0 switches it off).
        advance_min_fraction: the parent solid fraction from which a cell counts as a dense bed
            (default 0.49, near the freezing point of hard spheres, 0.494: Hoover & Ree, J.
            Chem. Phys. 49 (1968) 3609); a dilute stream is carried by the flux alone.
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
    shear_traction: float = 1.0
    max_lag: float = 1.0
    advance: float = 1.0
    advance_min_fraction: float = 0.49

    def __post_init__(self) -> None:
        for name in ("cell_size", "every"):
            if getattr(self, name) is not None:
                positive("Exchange", name, getattr(self, name))
        if self.stress_integral is not None:  # 0 with stress_gain 0: no stress condition
            non_negative("Exchange", "stress_integral", self.stress_integral)
        flag("Exchange", "mass_flux_correction", self.mass_flux_correction)
        if isinstance(self.samples, bool) or not isinstance(self.samples, int) or self.samples < 1:
            raise ValueError(f"Exchange.samples must be a positive integer, got {self.samples!r}")
        for name in (
            "velocity_gain",
            "stress_gain",
            "skip_ratio",
            "boundary_velocity_gain",
            "shear_traction",
            "advance",
        ):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v >= 0):
                raise ValueError(f"Exchange.{name} must be non-negative and finite, got {v!r}")
        for name in ("velocity_gain", "boundary_velocity_gain", "shear_traction"):
            if getattr(self, name) > 1:
                raise ValueError(f"Exchange.{name} must be in [0, 1], got {getattr(self, name)}")
        positive("Exchange", "layer", self.layer, " (child diameters)")
        positive("Exchange", "fade", self.fade, " (child diameters)")
        if self.fade > self.layer:
            raise ValueError(f"Exchange.fade must be at most layer ({self.layer}), got {self.fade}")
        if not (
            isinstance(self.advance_min_fraction, int | float)
            and 0 <= self.advance_min_fraction < 1
        ):
            raise ValueError(
                "Exchange.advance_min_fraction must be in [0, 1), "
                f"got {self.advance_min_fraction!r}"
            )
        if not (isinstance(self.max_lag, int | float) and 0 <= self.max_lag < math.inf):
            raise ValueError(
                f"Exchange.max_lag must be non-negative and finite (parent particles), "
                f"got {self.max_lag!r}"
            )


@dataclass(frozen=True)
class Level:
    """One resolution of a :class:`Hierarchy`.

    Args:
        cg: coarse-graining ratio h against the reference, at least 1 (1: fully resolved; the
            reference is the real material, a level cannot be finer than it).
        region: where the level lives (Box, finite Cylinder, closed Mesh); None for the
            coarsest level, which covers the whole domain. Size it so that its interior cells
            hold the whole flow the parent cannot represent: its boundary cells (one exchange
            cell deep along every interface face) are held to the parent's motion. Around an
            orifice the parent cannot pass, the parent sinks there as a plug paying the child's
            discharge, so a region whose boundary cells reach into the orifice's converging
            flow imposes that plug on it. In studies/mlcg_jam a region 2.5 orifice widths
            wide and 1.25 high (interior cells 1.5-3 mm beyond the orifice's edge) ran up to
            8 % fast, the more so the smaller the cells and the deeper the bed; one 3 wide and
            2 high (3-6 mm beyond the edge) held the resolved rate within 5 % across the cell
            sizes, in the 4 -> 2 -> 1 chain and in a bed twice as deep.
        exchange: settings of the interface to its parent (default: the hierarchy's).
    """

    cg: float
    region: Region | None = None
    exchange: Exchange | None = None

    def __post_init__(self) -> None:
        positive("Level", "cg", self.cg)
        if not self.cg >= 1:
            raise ValueError(
                "Level.cg must be >= 1 (the coarse-graining ratio against the fully resolved "
                f"reference, h = 1: a level cannot be finer than the reference), got {self.cg!r}"
            )
        if self.region is not None and not isinstance(self.region, Box | Cylinder | Mesh):
            raise ValueError(
                f"Level.region must be a gs.Box, gs.geometry.Cylinder or gs.geometry.Mesh, "
                f"got {self.region!r}"
            )
        if self.exchange is not None and not isinstance(self.exchange, Exchange):
            raise ValueError(f"Level.exchange must be a gs.Exchange, got {self.exchange!r}")


def _box_text(lo: np.ndarray, hi: np.ndarray) -> str:
    return f"[{tuple(float(v) for v in lo)}, {tuple(float(v) for v in hi)}]"


def find_parents(bounds: list[tuple[np.ndarray, np.ndarray]]) -> list[int]:
    """Each level's parent (-1 for the coarsest): the finest coarser level whose region holds
    its region (``bounds``: the regions' bounding boxes, the domain first). Regions are nested:
    a region lies inside the domain, and inside or apart from every coarser level's region —
    one overlapping a coarser region without lying inside it would leave the material of the
    overlap to two levels (ValueError naming both levels and their bounds)."""
    dom_lo, dom_hi = bounds[0]
    tol = 1e-9 * float(np.max(dom_hi - dom_lo))
    parents = [-1]
    for k in range(1, len(bounds)):
        lo, hi = bounds[k]
        if np.any(lo < dom_lo - tol) or np.any(hi > dom_hi + tol):
            raise ValueError(
                f"Hierarchy.levels[{k}].region must lie inside the domain "
                f"{_box_text(dom_lo, dom_hi)}, got bounds {_box_text(lo, hi)}"
            )
        parent = 0
        for j in range(1, k):
            plo, phi = bounds[j]
            if np.all(lo >= plo - tol) and np.all(hi <= phi + tol):
                parent = j  # the finest coarser level whose region holds this one
            elif np.all(np.minimum(hi, phi) - np.maximum(lo, plo) > tol):
                raise ValueError(
                    f"Hierarchy.levels[{k}].region must lie inside the region of levels[{j}] or "
                    f"apart from it (regions are nested: each inside its parent's, those of one "
                    f"parent apart), got bounds {_box_text(lo, hi)} that overlap levels[{j}]'s "
                    f"{_box_text(plo, phi)}"
                )
        parents.append(parent)
    return parents


def setup_record(levels: Sequence[Level]) -> list[dict[str, Any]]:
    """What a hierarchy's restart compares per level: its ratio and its region as constructed."""
    return [
        {"cg": float(lv.cg), "region": None if lv.region is None else geometry_record(lv.region)}
        for lv in levels
    ]


def check_setup_record(saved: Any, levels: Sequence[Level]) -> None:
    """ValueError naming the first level whose ratio or region differs from ``saved`` (a
    checkpoint's setup_record; None: written before it was recorded, nothing to compare)."""
    if saved is None:
        return
    for k, (theirs, mine) in enumerate(zip(saved, setup_record(levels), strict=False)):
        if theirs != mine:
            raise ValueError(
                f"checkpoint was written for Hierarchy.levels[{k}] with cg={theirs.get('cg')!r}, "
                f"region={theirs.get('region')}, this hierarchy's levels[{k}] has "
                f"cg={mine['cg']!r}, region={mine['region']}: the set-up differs"
            )


def _bounds(region: Region | None, domain: Box) -> tuple[np.ndarray, np.ndarray]:
    if region is None:
        return np.asarray(domain.lo, float), np.asarray(domain.hi, float)
    lo, hi = region._to_core("Level").bounds()
    return np.asarray(lo, float), np.asarray(hi, float)


def flowing_size(base: scaling.ParameterSet, owner: str = "Hierarchy") -> Distribution | None:
    """The size distribution (radius, m) of the particles a hierarchy resolves: ``base.size``,
    else the first insertion's; None if neither gives one."""
    size = base.size
    if size is None:
        for op in base.insertions:
            size = as_distribution(op.radius, owner, "base.size")
            break
    return None if size is None else as_distribution(size, owner, "base.size")


def _flowing(base: scaling.ParameterSet) -> tuple[Distribution, Material]:
    """The size distribution and material of the particles the hierarchy resolves."""
    material = None
    for op in base.insertions:
        if isinstance(op, Pack | Stream):
            material = op.material
            break
    if material is None and base.particles:
        material = base.particles[0].material
    size = flowing_size(base)
    if size is None or material is None:
        raise ValueError(
            "Hierarchy.base must insert particles (a Pack or Stream in insertions) or give size "
            "and particles, so that the fine levels know their particles, got neither"
        )
    return size, material


def in_cells(grid: dict[str, Any], x: np.ndarray) -> np.ndarray:
    """Whether each position (n, 3) lies in a region cell of an exchange grid (the rule of the
    C++ grid: the upper faces belong to the last cells)."""
    f = (np.asarray(x, float) - np.asarray(grid["origin"])) / np.asarray(grid["edge"])
    dims = np.asarray(grid["dims"])
    ok = np.all((f >= 0) & (f <= dims), axis=1)
    k = np.minimum(np.floor(np.where(ok[:, None], f, 0)).astype(int), dims - 1)
    cell = k[:, 0] + dims[0] * (k[:, 1] + dims[1] * k[:, 2])
    inside: np.ndarray = ok & (np.asarray(grid["inside"])[cell] > 0)
    return inside


def describe_balance(b: dict[str, Any]) -> str:
    """A few lines of a :meth:`~grainscale.Hierarchy.mass_balance` (grams; unaccounted in kg)."""
    g = 1e3
    lines = [
        f"hierarchy: initial {b['initial'] * g:.3f} g + inserted {b['inserted'] * g:.3f} g = "
        f"held {sum(b['held']) * g:.3f} g (per level "
        + ", ".join(f"{m * g:.3f}" for m in b["held"])
        + f") + pending {b['pending'] * g:.4f} g + discharged {b['discharged'] * g:.3f} g + "
        f"lost {b['lost'] * g:.4f} g; unaccounted {b['unaccounted']:.2e} kg"
    ]
    for i in b["interfaces"]:
        lines.append(
            f"interface {i['parent']} -> {i['child']}: carried in {i['carried_in'] * g:.3f} g, "
            f"out {i['carried_out'] * g:.3f} g, returned {i['returned'] * g:.3f} g; inserted "
            f"{i['inserted'] * g:.3f} g, extracted {i['extracted'] * g:.3f} g, pending "
            f"{i['pending'] * g:.4f} g; child discharged {i['child_removed'] * g:.3f} g, parent "
            f"discharged {i['parent_removed'] * g:.3f} g + paid {i['paid'] * g:.3f} g, debt "
            f"{i['debt'] * g:.4f} g"
        )
    return "\n".join(lines)


def check_nesting(
    couplings: list[Any],
    parents: list[int],
    sizes: list[Distribution],
    bounds: list[tuple[np.ndarray, np.ndarray]],
) -> None:
    """A region must keep clear of its parent's interface faces by the parent's insertion shell
    (NESTING_RADII largest parent radii): what the parent inserts or gives up there must not
    happen inside it. ``couplings``: the hierarchy's interfaces (with ``child`` and ``grid``)."""
    for c in couplings:
        for k in range(1, len(parents)):
            if parents[k] != c.child:
                continue
            lo, hi = bounds[k]
            depth = NESTING_RADII * sizes[c.child].max_radius
            g = c.grid
            edge = np.asarray(g["edge"])
            for centre, axis in zip(g["face_centre"], g["face_axis"].astype(int), strict=True):
                half = 0.5 * edge.copy()
                half[axis] = 0.0
                gap = np.maximum(np.maximum(centre - half - hi, lo - centre - half), 0.0)
                if np.linalg.norm(gap) < depth:
                    raise ValueError(
                        f"Hierarchy.levels[{k}].region must keep {depth:.4g} m clear of the "
                        f"interface of its parent levels[{c.child}] (its insertion shells), "
                        f"got a face at {tuple(np.round(centre, 6))} m"
                    )


def cells_across(grid: dict[str, Any]) -> str | None:
    """None if an exchange grid is at least 4 cells across along every axis where the region
    has interface faces on both sides (2 where on one side only), else what is missing."""
    normals = np.rint(np.asarray(grid["face_normal"])).astype(int)
    for a, name in enumerate("xyz"):
        sides = {int(n) for n in normals[:, a] if n != 0}
        need = 4 if len(sides) == 2 else 2 if sides else 0
        if grid["dims"][a] < need:
            return (
                f"{need} cells across along {name} (interior cells), it would be {grid['dims'][a]}"
            )
    return None
