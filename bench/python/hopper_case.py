"""Definition of the 'hopper' benchmark case, shared by the driver and the grainscale worker.

A conical hopper given as a triangle mesh (binary STL): a vertical cylinder of radius R = 40 mm
and height 120 mm on top of a cone (half-angle 30 degrees from the vertical) that narrows to a
circular outlet of radius 10 mm (10 particle diameters) in the plane z = 0. The surface is a
48-sided prism / pyramid frustum: rings of 48 vertices at 16 heights on the cone and 24 on the
cylinder, each quad split into two triangles (3840 triangles, normals towards the axis). Top and
outlet are open.

N monodisperse spheres (d = 2 mm, rho = 2500 kg/m^3) start on a simple-cubic lattice (spacing
2.2 mm, one site on the axis, first layer 1.1 mm above the outlet plane) restricted to the sites
at least r + 0.15 mm away from the (faceted) hopper wall, filled bottom-up, layer by layer and
row by row, the last layer partial. Sites get a seeded uniform jitter of +-0.05 mm in x and y
and a seeded uniform initial velocity of +-0.05 m/s per component. The outlet is open from the
start: the lattice collapses under gravity and discharges. The box (closed on every axis, no
walls) reaches 3 mm below the outlet; particles crossing its floor are deleted (LIGGGHTS: lost
atoms at reneighbouring with ``thermo_modify lost ignore``; grainscale: the same, lost at the
list rebuild, or optionally a ``gs.insert.Outlet`` slab at the floor).

Contact law: Hertz-Mindlin with tangential history, E = 1e7 Pa, nu = 0.3, e = 0.5, mu = 0.5 for
particle pairs and particle-mesh contacts (the mesh of the particle material: E* = E/(2(1-nu^2))).
dt = 1e-5 s, neighbour skin 0.2 mm, gravity 9.81 m/s^2 along -z.

This module only uses numpy so that it can be imported without grainscale being built.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from settle_case import liggghts_script

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class HopperCase:
    """Parameters of one 'hopper' run (SI units)."""

    n_particles: int
    steps: int = 20_000
    seed: int = 12345
    diameter: float = 2.0e-3
    density: float = 2500.0
    spacing: float = 2.2e-3
    jitter: float = 0.05e-3
    initial_speed: float = 0.05
    wall_gap: float = 0.15e-3  # minimum initial gap between a sphere and the hopper wall
    youngs_modulus: float = 1.0e7
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    time_step: float = 1.0e-5
    skin: float = 0.2e-3
    gravity: float = 9.81
    # grainscale's spring rotation: "project" is LIGGGHTS' tangential history model (the spring
    # projected onto the new tangent plane), "rescale" grainscale's default (length kept)
    spring_rotation: str = "project"
    # hopper geometry
    hopper_radius: float = 40.0e-3
    outlet_radius: float = 10.0e-3
    cone_half_angle_deg: float = 30.0
    cylinder_height: float = 120.0e-3
    n_sides: int = 48
    cone_rows: int = 16
    cylinder_rows: int = 24
    drop_depth: float = 3.0e-3  # box floor below the outlet plane (1.5 diameters)
    box_margin: float = 5.0e-3  # box beyond the hopper laterally and above its top
    sample_every: int = 250  # steps between samples of particle count, KE, mean z

    @property
    def cone_height(self) -> float:
        return (self.hopper_radius - self.outlet_radius) / math.tan(
            math.radians(self.cone_half_angle_deg)
        )

    @property
    def hopper_top(self) -> float:
        return self.cone_height + self.cylinder_height

    @property
    def n_triangles(self) -> int:
        return 2 * self.n_sides * (self.cone_rows + self.cylinder_rows)

    @property
    def box_lo(self) -> tuple[float, float, float]:
        a = self.hopper_radius + self.box_margin
        return (-a, -a, -self.drop_depth)

    @property
    def box_hi(self) -> tuple[float, float, float]:
        a = self.hopper_radius + self.box_margin
        return (a, a, self.hopper_top + self.box_margin)

    @property
    def particle_mass(self) -> float:
        return self.density * math.pi / 6.0 * self.diameter**3

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d.update(
            cone_height=self.cone_height,
            hopper_top=self.hopper_top,
            n_triangles=self.n_triangles,
            box_lo=list(self.box_lo),
            box_hi=list(self.box_hi),
            particle_mass=self.particle_mass,
        )
        return d


# ---------------------------------------------------------------------------------------------
# hopper surface


def wall_radius(case: HopperCase, z: FloatArray) -> FloatArray:
    """Radius of the (circumscribed) hopper surface at height z (cone below, cylinder above)."""
    tan_a = math.tan(math.radians(case.cone_half_angle_deg))
    return np.minimum(case.outlet_radius + np.asarray(z) * tan_a, case.hopper_radius)


def hopper_mesh(case: HopperCase) -> tuple[FloatArray, IntArray]:
    """(vertices (V, 3), triangles (T, 3)) of the hopper; triangle normals point to the axis."""
    z_cone = np.linspace(0.0, case.cone_height, case.cone_rows + 1)
    z_cyl = case.cone_height + np.linspace(0.0, case.cylinder_height, case.cylinder_rows + 1)[1:]
    z_rings = np.concatenate([z_cone, z_cyl])
    r_rings = wall_radius(case, z_rings)
    r_rings[case.cone_rows :] = case.hopper_radius  # exact, no round-off at the junction
    theta = 2.0 * math.pi * np.arange(case.n_sides) / case.n_sides
    n_rings, m = len(z_rings), case.n_sides
    vertices = np.empty((n_rings, m, 3), dtype=np.float64)
    vertices[:, :, 0] = r_rings[:, None] * np.cos(theta)[None, :]
    vertices[:, :, 1] = r_rings[:, None] * np.sin(theta)[None, :]
    vertices[:, :, 2] = z_rings[:, None]
    vertices = vertices.reshape(-1, 3)

    ring = np.arange(n_rings - 1)[:, None]
    side = np.arange(m)[None, :]
    a0 = ring * m + side  # lower ring, this side
    a1 = ring * m + (side + 1) % m  # lower ring, next side
    b0 = a0 + m  # upper ring
    b1 = a1 + m
    lower = np.stack([a0, b1, a1], axis=-1).reshape(-1, 3)
    upper = np.stack([a0, b0, b1], axis=-1).reshape(-1, 3)
    triangles = np.concatenate([lower, upper]).astype(np.int64)

    # orient every normal towards the axis (into the hopper)
    p = vertices[triangles]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    centre = p.mean(axis=1)
    outward = np.einsum("ij,ij->i", normal[:, :2], centre[:, :2]) > 0
    triangles[outward] = triangles[outward][:, ::-1]
    return vertices, triangles


def write_binary_stl(path: Path, vertices: FloatArray, triangles: IntArray, name: str) -> None:
    """Write a binary STL (float32 coordinates, unit facet normals)."""
    p = vertices[triangles]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    record = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(triangles), dtype=record)
    data["normal"] = normal
    data["vertices"] = p
    header = f"grainscale hopper benchmark: {name}".encode()[:80].ljust(80, b" ")
    with path.open("wb") as f:
        f.write(header)
        f.write(np.uint32(len(triangles)).tobytes())
        f.write(data.tobytes())


# ---------------------------------------------------------------------------------------------
# initial state


def lattice_sites(case: HopperCase) -> FloatArray:
    """All admissible lattice sites inside the hopper, in fill order (bottom-up, row by row)."""
    s = case.spacing
    r = 0.5 * case.diameter
    clearance = r + case.wall_gap + case.jitter * math.sqrt(2.0)
    # the flat facets lie inside the circumscribed surface by a factor cos(pi / n_sides)
    shrink = math.cos(math.pi / case.n_sides)
    cos_a = math.cos(math.radians(case.cone_half_angle_deg))
    half = int(math.floor(case.hopper_radius / s))
    grid = np.arange(-half, half + 1) * s
    x, y = np.meshgrid(grid, grid, indexing="xy")  # row-major: rows of constant y
    x, y = x.ravel(), y.ravel()
    rho = np.hypot(x, y)
    top = case.hopper_top - r - case.wall_gap
    z_layers = np.arange(0.5 * s, top, s)
    sites = []
    for z in z_layers:
        in_cone = z < case.cone_height
        limit = float(wall_radius(case, np.array(z))) * shrink
        limit -= clearance / cos_a if in_cone else clearance
        # a sphere near the cone-cylinder junction also has to clear the cylinder wall
        limit = min(limit, case.hopper_radius * shrink - clearance)
        keep = rho <= limit
        sites.append(np.column_stack([x[keep], y[keep], np.full(int(keep.sum()), z)]))
    return np.concatenate(sites)


def initial_state(case: HopperCase) -> tuple[FloatArray, FloatArray]:
    """Return (positions, velocities), both (N, 3) float64, for the seeded lattice."""
    sites = lattice_sites(case)
    n = case.n_particles
    if n > len(sites):
        raise ValueError(
            f"the hopper holds at most {len(sites)} lattice sites, {n} particles requested"
        )
    pos = sites[:n].copy()
    rng = np.random.default_rng(case.seed)
    pos[:, :2] += rng.uniform(-case.jitter, case.jitter, size=(n, 2))
    vel = rng.uniform(-case.initial_speed, case.initial_speed, size=(n, 3))
    return pos, vel


# ---------------------------------------------------------------------------------------------
# LIGGGHTS input


def write_granular_data(
    path: Path,
    title: str,
    box: tuple[Any, Any],
    diameter: FloatArray,
    density: FloatArray,
    pos: FloatArray,
    vel: FloatArray,
    spin: FloatArray | None = None,
) -> None:
    """Write a LIGGGHTS data file (atom_style granular, one atom type) with Atoms and
    Velocities sections; ``box`` = (lo, hi) corners, per-atom diameter and density arrays."""
    n = len(pos)
    ids = np.arange(1, n + 1, dtype=np.float64)
    atoms = np.column_stack([ids, np.ones(n), diameter, density, pos])
    vels = np.column_stack([ids, vel, np.zeros((n, 3)) if spin is None else spin])
    with path.open("w") as f:
        f.write(f"{title}\n\n{n} atoms\n1 atom types\n\n")
        for axis, a, b in zip("xyz", box[0], box[1], strict=True):
            f.write(f"{a!r} {b!r} {axis}lo {axis}hi\n")
        f.write("\nAtoms\n\n")
        np.savetxt(f, atoms, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g", "%.17g"])
        f.write("\nVelocities\n\n")
        np.savetxt(f, vels, fmt=["%d"] + ["%.17g"] * 6)


def write_liggghts_data(path: Path, case: HopperCase, pos: FloatArray, vel: FloatArray) -> None:
    """Write the LIGGGHTS data file of the case (atom_style granular)."""
    n = len(pos)
    title = f"LIGGGHTS data file, grainscale hopper benchmark, N = {n}, seed = {case.seed}"
    write_granular_data(
        path,
        title,
        (case.box_lo, case.box_hi),
        np.full(n, case.diameter),
        np.full(n, case.density),
        pos,
        vel,
    )


def liggghts_input(case: HopperCase, data_file: str, stl_file: str) -> str:
    """LIGGGHTS 3.8 input script: the STL hopper as one mesh wall/gran, lost atoms deleted."""
    wall_lines = (
        f"fix hopper all mesh/surface file {stl_file} type 1\n"
        "fix walls all wall/gran model hertz tangential history mesh n_meshes 1 meshes hopper"
    )
    return liggghts_script("hopper", case, data_file, wall_lines, case.sample_every, lost="ignore")


def mean_count(steps: list[float], counts: list[float]) -> float:
    """Time-average of the particle count over the run (trapezoid rule over the samples)."""
    s = np.asarray(steps, dtype=float)
    c = np.asarray(counts, dtype=float)
    if len(s) < 2 or s[-1] <= s[0]:
        return float(c.mean())
    return float(np.sum(0.5 * (c[1:] + c[:-1]) * np.diff(s)) / (s[-1] - s[0]))
