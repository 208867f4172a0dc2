"""Every wall of a simulation as triangles where it is now, for output (ParaView).

Planes are clipped to the domain box (the polygon where the plane cuts it), rectangles are two
triangles, cylinders a tessellated surface (an infinite one clipped to the box's extent along
its axis), meshes their current triangles. Each triangle carries the index of its wall.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..geometry import Box, Cylinder, Mesh, Plane, Rectangle

SEGMENTS = 48  # facets around a cylinder: 0.2 % short of its true area


@dataclass
class WallSurfaces:
    """Triangles of all walls: ``vertices`` (V, 3) m, ``triangles`` (T, 3) indices, ``wall``
    (T,) wall index of each triangle; ``moving``: whether any wall moves (translation, servo
    or rotation that changes its shape's place)."""

    vertices: np.ndarray
    triangles: np.ndarray
    wall: np.ndarray
    moving: bool


def plane_in_box(point: Any, normal: Any, box: Box) -> tuple[np.ndarray, np.ndarray]:
    """The polygon where the plane cuts the box, fan-triangulated (empty if it misses).

    >>> import grainscale as gs
    >>> v, t = plane_in_box((0, 0, 0.5), (0, 0, 1), gs.Box((0, 0, 0), (1, 2, 1)))
    >>> len(v), len(t), float(v[:, 2].max())
    (4, 2, 0.5)
    """
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    p0 = np.asarray(point, float)
    lo, hi = np.asarray(box.lo, float), np.asarray(box.hi, float)
    corners = np.array(list(itertools.product(*zip(lo, hi, strict=True))))
    side = (corners - p0) @ n
    cuts = [c for c, s in zip(corners, side, strict=True) if s == 0]  # corners on the plane
    for a, b in itertools.combinations(range(8), 2):
        if np.count_nonzero(corners[a] != corners[b]) != 1:
            continue  # not an edge of the box
        sa, sb = side[a], side[b]
        if sa * sb < 0:  # the edge crosses the plane
            cuts.append(corners[a] + sa / (sa - sb) * (corners[b] - corners[a]))
    if len(cuts) < 3:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    pts = np.unique(np.round(np.array(cuts), 15), axis=0)
    if len(pts) < 3:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    centre = pts.mean(axis=0)
    u = pts[0] - centre
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    order = np.argsort(np.arctan2((pts - centre) @ w, (pts - centre) @ u))
    pts = pts[order]
    fan = np.array([[0, k, k + 1] for k in range(1, len(pts) - 1)], dtype=np.int64)
    return pts, fan


def cylinder_surface(
    point: Any, axis: Any, radius: float, start: float, end: float
) -> tuple[np.ndarray, np.ndarray]:
    """The side of a cylinder from ``start`` to ``end`` along its axis (m from ``point``)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.eye(3)[int(np.argmin(np.abs(a)))]
    u = np.cross(a, helper)
    u /= np.linalg.norm(u)
    w = np.cross(a, u)
    phi = np.linspace(0.0, 2 * math.pi, SEGMENTS, endpoint=False)
    ring = radius * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * w)
    p = np.asarray(point, float)
    vertices = np.concatenate([p + start * a + ring, p + end * a + ring])
    k = np.arange(SEGMENTS)
    nxt = (k + 1) % SEGMENTS
    triangles = np.concatenate(
        [np.stack([k, nxt, k + SEGMENTS], 1), np.stack([nxt, nxt + SEGMENTS, k + SEGMENTS], 1)]
    )
    return vertices, triangles.astype(np.int64)


def _axial_extent(point: np.ndarray, axis: np.ndarray, box: Box) -> tuple[float, float]:
    corners = np.array(list(itertools.product(*zip(box.lo, box.hi, strict=True))), float)
    along = (corners - point) @ (axis / np.linalg.norm(axis))
    return float(along.min()), float(along.max())


def wall_surfaces(sim: Any) -> WallSurfaces:
    """The triangles of every wall of ``sim`` where it is now (see the module docstring)."""
    level = sim.engine.core
    parts: list[tuple[np.ndarray, np.ndarray, int]] = []
    moving = False
    for handle in sim.walls:
        k, geometry = handle.index, handle.geometry
        if isinstance(geometry, Mesh):
            vertices = np.asarray(level.wall_vertices(k))
            parts.append((vertices, np.asarray(geometry.triangles, np.int64), k))
            motion = handle.motion
            moving = moving or bool(np.any(motion.velocity) or np.any(motion.angular_velocity))
            continue
        frame = level.wall_frame(k)
        moving = moving or bool(frame["moving"])
        point = np.asarray(frame["point"], float)
        if isinstance(geometry, Plane):
            vertices, triangles = plane_in_box(point, frame["normal"], sim.domain)
        elif isinstance(geometry, Rectangle):
            e1, e2 = np.asarray(frame["edge1"]), np.asarray(frame["edge2"])
            vertices = np.array([point, point + e1, point + e1 + e2, point + e2])
            triangles = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int64)
        elif isinstance(geometry, Cylinder):
            axis = np.asarray(frame["axis"], float)
            if geometry.length is None:
                start, end = _axial_extent(point, axis, sim.domain)
            else:
                start, end = 0.0, float(geometry.length)
            vertices, triangles = cylinder_surface(point, axis, geometry.radius, start, end)
        else:  # pragma: no cover - every wall type is handled above
            raise TypeError(f"no surface for {type(geometry).__name__}")
        parts.append((vertices, triangles, k))
    vertices_all, triangles_all, wall = [], [], []
    offset = 0
    for vertices, triangles, k in parts:
        vertices_all.append(vertices)
        triangles_all.append(triangles + offset)
        wall.append(np.full(len(triangles), k, dtype=np.int32))
        offset += len(vertices)
    if not parts:
        empty = np.zeros((0, 3))
        return WallSurfaces(empty, empty.astype(np.int64), np.zeros(0, np.int32), False)
    return WallSurfaces(
        np.concatenate(vertices_all), np.concatenate(triangles_all), np.concatenate(wall), moving
    )
