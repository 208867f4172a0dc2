"""Domain boxes and walls (declarative; added to a Simulation with add_wall / domain=)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._validate import vector3
from .materials import Material


@dataclass(frozen=True)
class Box:
    """An axis-aligned box [lo, hi] in m, periodic or closed per axis.

    Example:
        >>> Box(lo=(0, 0, 0), hi=(0.1, 0.1, 0.2), periodic=(True, True, False)).volume
        0.002
    """

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    periodic: tuple[bool, bool, bool] = (False, False, False)

    def __post_init__(self) -> None:
        lo = vector3("Box", "lo", self.lo)
        hi = vector3("Box", "hi", self.hi)
        for a in range(3):
            if not hi[a] > lo[a]:
                raise ValueError(f"Box.hi must be greater than Box.lo on every axis, got {self.hi}")
        p = tuple(bool(v) for v in self.periodic)
        if len(p) != 3:
            raise ValueError(f"Box.periodic must have three entries, got {self.periodic!r}")
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)
        object.__setattr__(self, "periodic", p)

    @property
    def length(self) -> np.ndarray:
        """Edge lengths (m)."""
        return np.subtract(self.hi, self.lo)

    @property
    def volume(self) -> float:
        """Volume (m^3)."""
        return float(np.prod(self.length))

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Boolean mask of the points inside the closed box."""
        p = np.asarray(points, dtype=float)
        return np.all((p >= self.lo) & (p <= self.hi), axis=-1)


@dataclass(frozen=True)
class Plane:
    """An infinite, one-sided plane wall: particles live on the side ``normal`` points to.

    Args:
        point: a point of the plane (m); also the reference point for the wall torque.
        normal: direction into the particle side (normalised internally).
        material: the wall's material, or None for a rigid wall (E -> infinity).
        velocity: prescribed translation velocity (m/s).
    """

    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    material: Material | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", vector3("Plane", "point", self.point))
        n = vector3("Plane", "normal", self.normal)
        if np.linalg.norm(n) == 0:
            raise ValueError(f"Plane.normal must be a non-zero vector, got {self.normal}")
        object.__setattr__(self, "normal", n)
        object.__setattr__(self, "velocity", vector3("Plane", "velocity", self.velocity))
        if self.material is not None and not isinstance(self.material, Material):
            raise ValueError(f"Plane.material must be a Material or None, got {self.material!r}")


@dataclass(frozen=True)
class Rectangle:
    """A bounded, two-sided rectangular wall spanning corner + a*edge1 + b*edge2, a, b in [0, 1].

    Edges and corners of the rectangle are contacted like the edges of a mesh (closest point).
    """

    corner: tuple[float, float, float]
    edge1: tuple[float, float, float]
    edge2: tuple[float, float, float]
    material: Material | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "corner", vector3("Rectangle", "corner", self.corner))
        e1 = vector3("Rectangle", "edge1", self.edge1)
        e2 = vector3("Rectangle", "edge2", self.edge2)
        if np.linalg.norm(np.cross(e1, e2)) == 0:
            raise ValueError(
                f"Rectangle.edge2 must be non-zero and not parallel to edge1, got {self.edge2}"
            )
        object.__setattr__(self, "edge1", e1)
        object.__setattr__(self, "edge2", e2)
        object.__setattr__(self, "velocity", vector3("Rectangle", "velocity", self.velocity))
        if self.material is not None and not isinstance(self.material, Material):
            raise ValueError(
                f"Rectangle.material must be a Material or None, got {self.material!r}"
            )


def box_walls(box: Box, material: Material | None = None) -> list[Plane]:
    """Six inward-facing planes closing ``box`` (only on its non-periodic axes)."""
    walls = []
    for a in range(3):
        if box.periodic[a]:
            continue
        up = (float(a == 0), float(a == 1), float(a == 2))
        down = (-up[0], -up[1], -up[2])
        walls.append(Plane(point=box.lo, normal=up, material=material))
        walls.append(Plane(point=box.hi, normal=down, material=material))
    return walls


Wall = Plane | Rectangle
