"""Set-up checks of particles placed by hand (``Simulation.add_particles``) and of walls added
among them: what would otherwise be accepted without a word and blow particles away at the
first step (issue 25).

Refused, with the count and the first offenders (indices in the call for the particles being
added, global ids for those already in the simulation):

- a particle larger than the box along an axis;
- coordinates so large that float64 cannot resolve a millionth of the radius;
- a particle that overlaps a plane, a rectangle or a cylinder wall by more than
  ``WALL_OVERLAP`` of its radius, or lies behind it;
- a particle that overlaps a mesh wall by more than ``WALL_OVERLAP`` of its radius (distance
  from its centre to the closest point of a triangle, at the mesh's current position). "Behind"
  is not checked: an open mesh has no inside;
- two particles that overlap by more than ``PAIR_OVERLAP`` of the smaller radius (identical
  centres included), among those added and between them and the particles already in the
  simulation, across periodic boundaries (nearest image) and in the 2-D mode (discs).

``add_wall`` refuses a wall that the particles present overlap or lie behind by the same rules.
``check_placement=False`` accepts what is refused. The searches are vectorised cell lists
(:mod:`grainscale.overlap_search`): 200 000 particles are checked in a fraction of a second.

Under MPI every rank checks the particles being added (the same on every rank) against the
particles it owns; the counts and first offenders are gathered, so that every rank raises the
same ValueError.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .geometry import Box, Cylinder, Mesh, Plane, Rectangle
from .overlap_search import Space, mesh_overlaps, overlapping_pairs

WALL_OVERLAP = 0.1  # largest accepted initial overlap with a wall, in units of the radius
PAIR_OVERLAP = 0.1  # largest accepted initial overlap of two particles, x the smaller radius
RESOLUTION = 1e-6  # the float64 spacing of a coordinate must stay below this x the radius
SHOWN = 5  # offenders named in a message


def _unit(v: Any) -> np.ndarray:
    a = np.asarray(v, float)
    unit: np.ndarray = a / np.linalg.norm(a)
    return unit


def wall_offenders(
    geometry: Any, position: np.ndarray, radius: np.ndarray, reference: np.ndarray
) -> np.ndarray:
    """Indices of the particles that overlap the wall by more than WALL_OVERLAP of their radius
    or lie behind it. ``reference``: the wall's reference point now, for a mesh its current
    vertices."""
    reach = (1.0 - WALL_OVERLAP) * radius
    if isinstance(geometry, Mesh):
        return mesh_overlaps(reference, geometry.triangles, position, reach)
    rel = position - reference
    if isinstance(geometry, Plane):
        bad = rel @ _unit(geometry.normal) < reach
    elif isinstance(geometry, Rectangle):
        e1, e2 = np.asarray(geometry.edge1, float), np.asarray(geometry.edge2, float)
        s, t = rel @ e1 / (e1 @ e1), rel @ e2 / (e2 @ e2)
        on_face = (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
        bad = on_face & (np.abs(rel @ _unit(np.cross(e1, e2))) < reach)
    elif isinstance(geometry, Cylinder):
        axis = _unit(geometry.axis)
        along = rel @ axis
        radial = np.linalg.norm(rel - along[:, None] * axis, axis=1)
        within = np.ones(len(rel), bool)
        if geometry.length is not None:
            within = (along >= 0) & (along <= geometry.length)
        if geometry.inside:
            bad = within & (radial > geometry.radius - reach)
        else:
            bad = within & (radial < geometry.radius + reach)
    else:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero(bad)


Existing = tuple[np.ndarray, np.ndarray, np.ndarray]  # positions, radii, ids


@np.errstate(over="ignore")  # a box or coordinates near the float64 limit: reported, not warned
def check_particles(
    owner: str,
    domain: Box,
    position: np.ndarray,
    radius: np.ndarray,
    walls: list[tuple[Any, Any, str]],
    labels: np.ndarray | None = None,
    axes: int = 3,
    existing: Existing | None = None,
    comm: Any = None,
) -> None:
    """ValueError naming the first offenders (``labels``: their ids, else their indices in the
    call) if any particle is refused (see the module docstring). ``walls``: (geometry, reference
    point now or a mesh's current vertices, name). ``axes``: 2 in the 2-D mode (the box's
    thickness does not bound a disc). ``existing``: the particles already present (this rank's
    under MPI), for the pair check among the particles and against them; None: no pair check.
    Collective over ``comm`` when ``existing`` is given."""
    what = "index" if labels is None else "id"
    labels = np.arange(len(radius)) if labels is None else labels
    problems: list[str] = []

    def report(indices: np.ndarray, text: str) -> None:
        if len(indices):
            first = ", ".join(f"{what} {labels[i]}" for i in indices[:SHOWN])
            problems.append(f"{len(indices)} particle(s) {text} (first: {first})")

    length = (np.asarray(domain.hi, float) - np.asarray(domain.lo, float))[:axes]
    report(np.flatnonzero(np.any(2 * radius[:, None] > length, axis=1)), "larger than the box")
    spacing = np.max(np.spacing(np.abs(position)), axis=1)
    report(
        np.flatnonzero(spacing > RESOLUTION * radius),
        f"with coordinates too large for float64 to resolve {RESOLUTION:g} of the radius",
    )
    for geometry, reference, name in walls:
        bad = wall_offenders(geometry, position, radius, np.asarray(reference, float))
        behind = "" if isinstance(geometry, Mesh) else " or behind it"
        report(
            bad,
            f"overlapping {name} ({type(geometry).__name__}) by more than "
            f"{WALL_OVERLAP:.0%} of the radius{behind}",
        )
    if existing is not None:
        problem = _pair_problem(domain, position, radius, labels, what, axes, existing, comm)
        if problem:
            problems.append(problem)
    if problems:
        raise ValueError(
            f"{owner}: " + "; ".join(problems) + "; move them, or pass check_placement=False "
            "to accept them"
        )


def _pair_problem(
    domain: Box,
    position: np.ndarray,
    radius: np.ndarray,
    labels: np.ndarray,
    what: str,
    axes: int,
    existing: Existing,
    comm: Any,
) -> str | None:
    """The pairs that overlap by more than PAIR_OVERLAP of the smaller radius, described the
    same on every rank (collective over ``comm``)."""
    lo = np.asarray(domain.lo, float)
    space = Space(lo, np.asarray(domain.hi, float) - lo, np.asarray(domain.periodic), axes)
    among = overlapping_pairs(position, radius, space, PAIR_OVERLAP)
    old_position, old_radius, old_id = existing
    against = overlapping_pairs(position, radius, space, PAIR_OVERLAP, (old_position, old_radius))
    # the pairs among the new particles are found alike on every rank; those with existing
    # ones only on the rank that owns the existing particle
    mine = (
        against.total,
        [(int(i), int(old_id[j])) for i, j in against.pairs[:SHOWN]],
        against.complete,
    )
    every = [mine] if comm is None else comm.allgather(mine)
    count = among.total + sum(c for c, _, _ in every)
    if count == 0:
        return None
    complete = among.complete and all(done for _, _, done in every)
    named = [(int(i), 0, int(j)) for i, j in among.pairs[:SHOWN]]
    named += [(i, 1, j) for _, pairs, _ in every for i, j in pairs]
    first = ", ".join(
        f"{what} {labels[i]} and " + (f"{what} {labels[j]}" if old == 0 else f"id {j}")
        for i, old, j in sorted(named)[:SHOWN]
    )
    return (
        f"{'' if complete else 'at least '}{count} pair(s) of particles overlap by more than "
        f"{PAIR_OVERLAP:.0%} of the smaller radius (first: {first})"
    )


def check_new_particles(sim: Any, owner: str, position: np.ndarray, radius: np.ndarray) -> None:
    """The checks of ``Simulation.add_particles`` against the simulation's walls (at their
    current position) and particles (collective under MPI)."""
    vertices = {m["index"]: m["vertices"] for m in sim.mesh_walls()}
    walls = [
        (w.geometry, vertices[w.index] if w.index in vertices else w.position, f"wall {w.index}")
        for w in sim.walls
    ]
    with sim.particles(writable=False) as p:
        existing = (np.array(p.position), np.array(p.radius), np.array(p.id))
    check_particles(
        owner,
        sim.domain,
        position,
        radius,
        walls,
        axes=sim.dimension,
        existing=existing,
        comm=sim.comm,
    )
