"""The hopper of the demo as a triangle mesh: shape, STL, and the geometry read back.

``hopper_mesh`` builds the mesh of a ``HopperShape`` (a cylindrical bin on a cone),
``write_hopper_stl`` writes it (the packaged ``data/hopper.stl`` is one), and
``HopperGeometry.of`` recovers outlet, cone and bin from any such mesh.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import grainscale as gs

DATA = Path(__file__).resolve().parent / "data"
PACKAGED_STL = DATA / "hopper.stl"


# ------------------------------------------------------------------------------------------
# the hopper mesh
# ------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HopperShape:
    """A conical hopper: outlet at z = 0 centred on the z axis, cone up to the bin radius, then a
    cylindrical bin (all m, angle in degrees from the vertical)."""

    outlet_diameter: float = 0.021
    bin_diameter: float = 0.06
    bin_height: float = 0.045
    half_angle: float = 30.0
    segments: int = 48

    @property
    def cone_height(self) -> float:
        rise = 0.5 * (self.bin_diameter - self.outlet_diameter)
        return rise / math.tan(math.radians(self.half_angle))

    @property
    def height(self) -> float:
        return self.cone_height + self.bin_height


def hopper_mesh(
    shape: HopperShape | None = None, material: gs.Material | None = None
) -> gs.geometry.Mesh:
    """The hopper surface as a gs.geometry.Mesh (cone + cylinder, open at both ends).

    Rings of ``segments`` vertices, about square quads (each split into two triangles).
    """
    shape = shape if shape is not None else HopperShape()
    n = int(shape.segments)
    r0, r1 = 0.5 * shape.outlet_diameter, 0.5 * shape.bin_diameter
    if not (0 < r0 < r1 and shape.bin_height > 0 and 0 < shape.half_angle < 90 and n >= 8):
        raise ValueError(f"hopper_mesh.shape is not a valid hopper, got {shape!r}")
    arc = 2 * math.pi * r1 / n
    slant = math.hypot(r1 - r0, shape.cone_height)
    cone = np.linspace(0.0, 1.0, max(2, math.ceil(slant / arc)) + 1)
    rings = [(r0 + (r1 - r0) * s, shape.cone_height * s) for s in cone]
    n_bin = max(1, math.ceil(shape.bin_height / arc))
    rings += [(r1, shape.cone_height + shape.bin_height * k / n_bin) for k in range(1, n_bin + 1)]
    theta = np.arange(n) * 2 * math.pi / n
    vertices = np.array([(r * math.cos(t), r * math.sin(t), z) for r, z in rings for t in theta])
    triangles = []
    for i in range(len(rings) - 1):
        for j in range(n):
            a, b = i * n + j, i * n + (j + 1) % n
            triangles += [(a, b, b + n), (a, b + n, a + n)]
    return gs.geometry.Mesh(vertices, np.array(triangles), material=material)


def write_hopper_stl(path: str | Path, shape: HopperShape | None = None) -> Path:
    """Write the hopper of ``shape`` as a binary STL file (m); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    hopper_mesh(shape).to_stl(path)
    return path


@dataclass(frozen=True)
class HopperGeometry:
    """What the demo needs to know about a hopper mesh (m), read off its vertices."""

    outlet_z: float
    outlet_radius: float
    top_z: float
    top_radius: float

    @classmethod
    def of(cls, mesh: gs.geometry.Mesh) -> HopperGeometry:
        v = np.asarray(mesh.vertices)
        r = np.hypot(v[:, 0], v[:, 1])
        z0, z1 = float(v[:, 2].min()), float(v[:, 2].max())
        tol = 1e-9 + 1e-6 * (z1 - z0)
        return cls(
            outlet_z=z0,
            outlet_radius=float(r[v[:, 2] <= z0 + tol].min()),
            top_z=z1,
            top_radius=float(r[v[:, 2] >= z1 - tol].max()),
        )
