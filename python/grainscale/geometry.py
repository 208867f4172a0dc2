"""Domain boxes and walls (declarative; added to a Simulation with add_wall / domain=)."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _core
from ._validate import direction, finite, flag, non_negative, positive, real_array, vector3
from .materials import Material


@dataclass(frozen=True)
class Box:
    """An axis-aligned box [lo, hi] in m, periodic or closed per axis (``periodic``: three
    bools for x, y, z, or one bool for every axis).

    Example:
        >>> box = Box(lo=(0, 0, 0), hi=(0.1, 0.1, 0.2), periodic=(True, True, False))
        >>> round(box.volume, 12)  # m^3
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
        object.__setattr__(self, "lo", lo)
        object.__setattr__(self, "hi", hi)
        object.__setattr__(self, "periodic", _periodic(self.periodic))

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
        inside: np.ndarray = np.all((p >= self.lo) & (p <= self.hi), axis=-1)
        return inside

    def _to_core(self, owner: str) -> _core.Region:
        """The core's region (package-internal; ``owner`` names the box in errors)."""
        return _core.Region.box(self.lo, self.hi)


def _periodic(value: object) -> tuple[bool, bool, bool]:
    """Box.periodic: one bool for every axis or three bools (x, y, z); a string such as 'yes',
    a number or None is refused (it was taken for its truth value)."""
    if isinstance(value, bool | np.bool_):
        return (bool(value),) * 3
    ok = isinstance(value, list | tuple | np.ndarray) and np.ndim(value) == 1 and len(value) == 3
    # past ``ok`` value is a list, tuple or array of three, which mypy cannot infer
    if not ok or not all(isinstance(v, bool | np.bool_) for v in value):  # type: ignore[attr-defined]
        raise ValueError(
            f"Box.periodic must be True, False or three of them (x, y, z), got {value!r}"
        )
    return tuple(bool(v) for v in value)  # type: ignore[return-value, attr-defined]


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
        object.__setattr__(self, "normal", direction("Plane", "normal", self.normal))
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
        with np.errstate(over="ignore", invalid="ignore"):
            area = float(np.linalg.norm(np.cross(e1, e2)))
        if not 0 < area < 1e300:  # 0: degenerate; beyond: the normal would overflow
            raise ValueError(
                f"Rectangle.edge2 must be non-zero, not parallel to edge1 and span an area "
                f"below 1e300 m^2 with it, got {self.edge2}"
            )
        object.__setattr__(self, "edge1", e1)
        object.__setattr__(self, "edge2", e2)
        object.__setattr__(self, "velocity", vector3("Rectangle", "velocity", self.velocity))
        if self.material is not None and not isinstance(self.material, Material):
            raise ValueError(
                f"Rectangle.material must be a Material or None, got {self.material!r}"
            )


@dataclass(frozen=True)
class Cylinder:
    """A cylinder: a wall (particles inside or outside it) or a region for packing.

    The axis runs through ``point`` along ``axis``; the cylinder spans [0, length] along the
    axis from ``point`` (length None: infinite, only as a wall). Open ends: as a wall it has no
    caps — close it with planes or a mesh.

    Args:
        point: a point on the axis (m), the start of the axial extent.
        axis: axis direction (normalised internally).
        radius: m.
        length: axial extent (m) or None.
        inside: as a wall, particles live inside (True) or outside (False).
        material: the wall's material, or None for a rigid wall.
        velocity: translation velocity (m/s).
        angular_velocity: rotation (rad/s) about ``point`` (e.g. a drum spinning about its
            axis: only its surface velocity changes).
    """

    point: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    length: float | None = None
    inside: bool = True
    material: Material | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    angular_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", vector3("Cylinder", "point", self.point))
        a = direction("Cylinder", "axis", self.axis)
        object.__setattr__(self, "axis", tuple(float(v) for v in np.divide(a, np.linalg.norm(a))))
        object.__setattr__(self, "radius", positive("Cylinder", "radius", self.radius, " (m)"))
        if self.length is not None:
            object.__setattr__(self, "length", positive("Cylinder", "length", self.length, " (m)"))
        object.__setattr__(self, "inside", flag("Cylinder", "inside", self.inside))
        object.__setattr__(self, "velocity", vector3("Cylinder", "velocity", self.velocity))
        object.__setattr__(
            self, "angular_velocity", vector3("Cylinder", "angular_velocity", self.angular_velocity)
        )
        _check_material("Cylinder", self.material)

    @property
    def volume(self) -> float:
        """Volume (m^3) of the finite cylinder."""
        if self.length is None:
            raise ValueError("Cylinder.volume needs a finite length")
        return math.pi * self.radius**2 * self.length

    def contains(self, points: np.ndarray) -> np.ndarray:
        """Boolean mask of the points inside the (finite) cylinder."""
        p = np.asarray(points, dtype=float) - np.asarray(self.point)
        h = p @ np.asarray(self.axis)
        rho = p - np.outer(h, self.axis)
        inside: np.ndarray = np.einsum("ij,ij->i", rho, rho) <= self.radius**2
        if self.length is not None:
            inside &= (h >= 0) & (h <= self.length)
        return inside

    def _to_core(self, owner: str) -> _core.Region:
        """The core's region of the finite cylinder (package-internal; ``owner`` names it in
        errors)."""
        if self.length is None:
            raise ValueError(
                f"{owner}.region must be a finite Cylinder (length in m), got length=None"
            )
        centre = np.asarray(self.point) + 0.5 * self.length * np.asarray(self.axis)
        return _core.Region.cylinder(tuple(centre), self.axis, self.radius, self.length)


@dataclass(frozen=True)
class Mesh:
    """A triangle-mesh wall (hoppers, chutes, dies from CAD), two-sided.

    Args:
        vertices: (V, 3) m.
        triangles: (T, 3) vertex indices.
        material: the wall's material, or None for a rigid wall.
        velocity: translation velocity (m/s).
        angular_velocity: rotation (rad/s) about ``origin``.
        origin: rotation centre and torque reference (m); default: the vertex centroid.
    """

    vertices: np.ndarray
    triangles: np.ndarray
    material: Material | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    angular_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    origin: tuple[float, float, float] | None = None

    def __post_init__(self) -> None:
        v = real_array("Mesh", "vertices", self.vertices, (None, 3))
        t = np.ascontiguousarray(np.asarray(self.triangles))
        if len(v) and np.max(np.abs(v)) > 1e100:  # no geometry; sums of coordinates overflow
            row = int(np.argmax(np.max(np.abs(v), axis=1)))
            raise ValueError(
                f"Mesh.vertices must lie within 1e100 m of the origin, got {v[row].tolist()} at "
                f"vertex {row}"
            )
        if t.ndim != 2 or t.shape[1] != 3 or t.shape[0] == 0:
            raise ValueError(f"Mesh.triangles must be a (T, 3) array, T > 0, got shape {t.shape}")
        if not np.issubdtype(t.dtype, np.integer) or t.min() < 0 or t.max() >= len(v):
            raise ValueError(
                f"Mesh.triangles must hold vertex indices in [0, {len(v)}), "
                f"got range [{t.min()}, {t.max()}]"
            )
        v.flags.writeable = False
        t = t.astype(np.int32)
        t.flags.writeable = False
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "triangles", t)
        object.__setattr__(self, "velocity", vector3("Mesh", "velocity", self.velocity))
        object.__setattr__(
            self, "angular_velocity", vector3("Mesh", "angular_velocity", self.angular_velocity)
        )
        origin = v.mean(axis=0) if self.origin is None else self.origin
        object.__setattr__(self, "origin", vector3("Mesh", "origin", origin))
        _check_material("Mesh", self.material)

    @classmethod
    def from_stl(
        cls,
        path: str | os.PathLike[str],
        material: Material | None = None,
        scale: float = 1.0,
        **motion: Any,
    ) -> Mesh:
        """Read an ASCII or binary STL file (numpy-stl); shared vertices are merged.

        Args:
            path: the .stl file.
            material: the wall's material, or None for a rigid wall.
            scale: factor applied to the coordinates (e.g. 1e-3 for a file in mm).
            motion: velocity, angular_velocity, origin (see Mesh).
        """
        from stl import mesh as stl_mesh

        scale = positive("Mesh.from_stl", "scale", scale)
        try:
            data = stl_mesh.Mesh.from_file(os.fspath(path))
        except FileNotFoundError:
            raise ValueError(
                f"Mesh.from_stl.path must be an existing STL file, got {path!r}"
            ) from None
        except Exception as err:  # numpy-stl reports damage in its own words and types
            raise ValueError(
                f"Mesh.from_stl.path must be a readable ASCII or binary STL file, got {path!r} "
                f"({type(err).__name__}: {err})"
            ) from None
        corners = np.asarray(data.vectors, dtype=float).reshape(-1, 3) * scale
        if len(corners) == 0 or not np.all(np.isfinite(corners)):
            raise ValueError(
                f"Mesh.from_stl.path must hold triangles with finite coordinates, got {path!r} "
                f"({len(corners) // 3} triangles)"
            )
        _check_binary_size(path, len(corners) // 3)
        vertices, inverse = np.unique(corners, axis=0, return_inverse=True)
        triangles = inverse.reshape(-1, 3)
        # drop degenerate triangles (repeated vertices)
        keep = (
            (triangles[:, 0] != triangles[:, 1])
            & (triangles[:, 1] != triangles[:, 2])
            & (triangles[:, 0] != triangles[:, 2])
        )
        tri = corners.reshape(-1, 3, 3)[keep]
        with np.errstate(over="ignore", invalid="ignore"):
            area = np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        if not np.any(area > 0):
            raise ValueError(
                f"Mesh.from_stl.path must hold at least one triangle of non-zero area, got "
                f"{path!r}: every one of its {len(triangles)} triangle(s) is degenerate (zero "
                "area: repeated or collinear vertices)"
            )
        return cls(vertices=vertices, triangles=triangles[keep], material=material, **motion)

    def to_stl(self, path: str | os.PathLike[str]) -> None:
        """Write the mesh as a binary STL file."""
        from stl import mesh as stl_mesh

        out = stl_mesh.Mesh(np.zeros(len(self.triangles), dtype=stl_mesh.Mesh.dtype))
        out.vectors[:] = self.vertices[self.triangles]
        out.save(os.fspath(path))

    def _to_core(self, owner: str) -> _core.Region:
        """The core's region inside the closed mesh (package-internal; refused with an error
        naming ``owner`` unless the mesh is closed)."""
        return _core.Region.mesh(self.vertices, self.triangles, f"{owner}.region (Mesh)")


@dataclass(frozen=True)
class Servo:
    """Force- or stress-controlled wall motion (compression tests, presses).

    Each step the wall moves along ``direction`` (into the material) at

        v = clamp(gain e + integral_gain I, -max_speed, max_speed),  e = target - load,

    where load is the force the particles push the wall back with and I = sum of e dt, the
    integrated error. A proportional servo (integral_gain = 0) lags by v / gain whenever the
    wall has to keep moving (a sample compressed from another side, a creeping bed); the
    integral term removes that lag. I is integrated only while that does not push a saturated
    speed further (conditional integration, the usual anti-windup), and it is kept when the
    servo of a wall under PI control is set again (a new target or gain), reset when it is
    switched off. ``Simulation.wall_servo_integral`` reads it; checkpoints carry it.

    Args:
        gain: (m/s)/N.
        max_speed: m/s.
        target_force: N; or
        target_stress: Pa, with ``area`` (m^2; default: the rectangle's area).
        direction: default: the wall's normal (Plane, Rectangle).
        integral_gain: (m/s)/(N s), >= 0 (default 0: proportional only). For a bed of
            stiffness K (N/m) under the wall, integral_gain <= gain^2 K / 4 keeps the linearised
            loop from oscillating (critical damping at equality, where a step in the target
            overshoots by exp(-2), 14 %; less with a smaller integral gain).
    """

    gain: float
    max_speed: float
    target_force: float | None = None
    target_stress: float | None = None
    area: float | None = None
    direction: tuple[float, float, float] | None = None
    integral_gain: float = 0.0

    def __post_init__(self) -> None:
        positive("Servo", "gain", self.gain, " ((m/s)/N)")
        positive("Servo", "max_speed", self.max_speed, " (m/s)")
        non_negative("Servo", "integral_gain", self.integral_gain)
        if (self.target_force is None) == (self.target_stress is None):
            raise ValueError(
                "Servo needs exactly one of target_force or target_stress, got "
                f"target_force={self.target_force!r}, target_stress={self.target_stress!r}"
            )
        if self.target_force is not None:
            finite("Servo", "target_force", self.target_force, " (N)")
        if self.target_stress is not None:
            finite("Servo", "target_stress", self.target_stress, " (Pa)")
        if self.area is not None:
            positive("Servo", "area", self.area, " (m^2)")
        if self.direction is not None:
            d = vector3("Servo", "direction", self.direction)
            if np.linalg.norm(d) == 0:
                raise ValueError(f"Servo.direction must be non-zero, got {self.direction}")
            object.__setattr__(self, "direction", d)

    def force_for(self, wall: Any) -> float:
        """The target force (N) on ``wall``."""
        if self.target_force is not None:
            return float(self.target_force)
        area = self.area
        if area is None and isinstance(wall, Rectangle):
            area = float(np.linalg.norm(np.cross(wall.edge1, wall.edge2)))
        if area is None:
            raise ValueError("Servo.area must be given for a target_stress on this wall, got None")
        return float(self.target_stress) * area  # type: ignore[arg-type]

    def direction_for(self, wall: Any) -> tuple[float, float, float]:
        if self.direction is not None:
            return self.direction
        if isinstance(wall, Plane):
            return wall.normal
        if isinstance(wall, Rectangle):
            n = np.cross(wall.edge1, wall.edge2)
            return tuple(float(v) for v in n / np.linalg.norm(n))  # type: ignore[return-value]
        raise ValueError(f"Servo.direction must be given for {type(wall).__name__} walls, got None")


def _check_binary_size(path: str | os.PathLike[str], loaded: int) -> None:
    """A binary STL (its 80-byte header does not start with "solid") must be exactly
    84 + 50 n bytes for the n triangles its header claims: numpy-stl reads the triangles that
    are there and says nothing of the rest (a file cut short in a transfer). A header starting
    with "solid" is an ASCII file or a binary one numpy-stl reads with its own size check."""
    with open(path, "rb") as fh:
        head = fh.read(84)
    if len(head) < 84 or head[:80].lstrip().lower().startswith(b"solid"):
        return
    count = int.from_bytes(head[80:84], "little")
    size = os.path.getsize(path)
    if size != 84 + 50 * count:
        raise ValueError(
            f"Mesh.from_stl.path must be a binary STL file of 84 + 50 x {count} = "
            f"{84 + 50 * count} bytes (its header claims {count} triangles), got {path!r} of "
            f"{size} bytes (numpy-stl read {loaded} triangles): it is truncated or damaged"
        )


def _check_material(owner: str, material: Any) -> None:
    if material is not None and not isinstance(material, Material):
        raise ValueError(f"{owner}.material must be a Material or None, got {material!r}")


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


Wall = Plane | Rectangle | Cylinder | Mesh
