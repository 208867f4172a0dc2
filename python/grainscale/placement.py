"""Set-up checks of particles placed by hand (``Simulation.add_particles``) and of walls added
among them: what would otherwise be accepted without a word and blow particles away at the
first step (issue 25).

Refused, with the count and the first offenders: a particle larger than the box along an axis;
coordinates so large that float64 cannot resolve a millionth of the radius; a particle that
overlaps a plane, a rectangle or a cylinder wall by more than ``WALL_OVERLAP`` of its radius, or
lies behind it. Mesh walls are not checked here (their contacts are found by the core's
closest-point search). Overlaps between particles are caught by the run's overlap guard.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .geometry import Box, Cylinder, Plane, Rectangle

WALL_OVERLAP = 0.1  # largest accepted initial overlap with a wall, in units of the radius
RESOLUTION = 1e-6  # the float64 spacing of a coordinate must stay below this x the radius
SHOWN = 5  # offenders named in a message


def _unit(v: Any) -> np.ndarray:
    a = np.asarray(v, float)
    return a / np.linalg.norm(a)


def wall_offenders(
    geometry: Any, position: np.ndarray, radius: np.ndarray, reference: np.ndarray
) -> np.ndarray:
    """Indices of the particles that overlap the wall (at its reference point ``reference``)
    by more than WALL_OVERLAP of their radius or lie behind it."""
    reach = (1.0 - WALL_OVERLAP) * radius
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


def check_particles(
    owner: str,
    domain: Box,
    position: np.ndarray,
    radius: np.ndarray,
    walls: list[Any],
    labels: np.ndarray | None = None,
    axes: int = 3,
) -> None:
    """ValueError naming the first offenders (``labels``: their ids, else their indices in the
    call) if any particle is refused (see the module docstring). ``axes``: 2 in the 2-D mode
    (the box's thickness does not bound a disc)."""
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
    for k, wall in enumerate(walls):
        name = f"wall {k}"
        if isinstance(wall, tuple):  # a wall about to be added: (geometry, reference point)
            geometry, reference, name = *wall, "the new wall"
        else:
            geometry, reference = wall.geometry, wall.position
        bad = wall_offenders(geometry, position, radius, np.asarray(reference, float))
        report(
            bad,
            f"overlapping {name} ({type(geometry).__name__}) by more than "
            f"{WALL_OVERLAP:.0%} of the radius or behind it",
        )
    if problems:
        raise ValueError(
            f"{owner}: " + "; ".join(problems) + "; move them, or pass check_placement=False "
            "to accept them"
        )
