"""Spheres, meshes and helpers shared by the wall tests (test_mesh_walls, test_wall_motion)."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import Delaunay

import grainscale as gs

MAT = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="soft")
R = 1e-3  # sphere radius, m
MASS = MAT.density * 4.0 / 3.0 * math.pi * R**3
G = 9.81
E_STAR = MAT.youngs_modulus / (1.0 - MAT.poisson_ratio**2)  # rigid wall
K_HERTZ = 4.0 / 3.0 * E_STAR * math.sqrt(R)  # F = K delta^1.5, R* = r
H = 1.5e-3  # floor triangulation spacing, m
FLOOR_HALF = 0.03  # floors span [-FLOOR_HALF, FLOOR_HALF]^2 at z = 0

HISTORY_TOL = 1e-9  # mesh vs plane, relative


def static_overlap(load: float) -> float:
    """Overlap of a sphere pressed on a rigid flat wall by ``load`` (Hertz, R* = r)."""
    return (load / K_HERTZ) ** (2.0 / 3.0)


# --------------------------------------------------------------------------------------------
# meshes
# --------------------------------------------------------------------------------------------


def grid_floor(half: float = FLOOR_HALF, h: float = H) -> gs.geometry.Mesh:
    """Flat floor z = 0: squares of side h, each split along its (-1, 1) diagonal.

    Grid vertices at multiples of h (the origin is one); every interior vertex is shared by 6
    triangles. A path along (1, 1) passes over vertices and crosses diagonals at their middle.
    """
    n = 2 * int(round(half / h))
    xs = (np.arange(n + 1) - n // 2) * h
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    tris = []
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            c, d = b + 1, a + 1
            tris += [[a, b, d], [b, c, d]]
    return gs.geometry.Mesh(vertices=vertices, triangles=np.array(tris), origin=(0, 0, 0))


def irregular_floor(
    half: float = FLOOR_HALF, h: float = H, seed: int = 7
) -> tuple[gs.geometry.Mesh, int]:
    """Flat floor z = 0: Delaunay triangulation of a jittered grid with a hub vertex at the
    origin surrounded by an irregular ring of 7 vertices. Returns (mesh, hub vertex index)."""
    rng = np.random.default_rng(seed)
    n = 2 * int(round(half / h))
    xs = (np.arange(n + 1) - n // 2) * h
    X, Y = np.meshgrid(xs, xs, indexing="ij")
    pts = np.column_stack([X.ravel(), Y.ravel()])
    interior = np.all(np.abs(pts) < half - 1e-12, axis=1)
    pts[interior] += rng.uniform(-0.3 * h, 0.3 * h, size=(int(interior.sum()), 2))
    pts = pts[np.hypot(pts[:, 0], pts[:, 1]) > 1.3 * h]
    angles = np.array([0.1, 0.9, 1.8, 2.6, 3.5, 4.4, 5.4])  # irregular, gaps < pi/2
    ring = 0.8 * h * np.column_stack([np.cos(angles), np.sin(angles)])
    pts = np.vstack([[0.0, 0.0], ring, pts])
    tri = Delaunay(pts).simplices
    # counter-clockwise (normals +z); the walls are two-sided, but keep them consistent
    e1, e2 = pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]
    flip = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    vertices = np.column_stack([pts, np.zeros(len(pts))])
    return gs.geometry.Mesh(vertices=vertices, triangles=tri, origin=(0, 0, 0)), 0


def valence(mesh: gs.geometry.Mesh, vertex: int) -> int:
    return int(np.sum(np.any(mesh.triangles == vertex, axis=1)))


def box_mesh(lo: float, hi: float) -> gs.geometry.Mesh:
    """Closed cube [lo, hi]^3 made of 12 triangles."""
    c = np.array([[x, y, z] for x in (lo, hi) for y in (lo, hi) for z in (lo, hi)], dtype=float)
    quads = [  # vertex index = 4 x + 2 y + z
        (0, 2, 6, 4),  # z = lo
        (1, 5, 7, 3),  # z = hi
        (0, 4, 5, 1),  # y = lo
        (2, 3, 7, 6),  # y = hi
        (0, 1, 3, 2),  # x = lo
        (4, 6, 7, 5),  # x = hi
    ]
    tris = [t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))]
    return gs.geometry.Mesh(vertices=c, triangles=np.array(tris))


def disc_mesh(radius: float, rings: int, first_ring: int) -> gs.geometry.Mesh:
    """Flat disc z = 0 about the origin: a centre vertex and rings k = 1..rings with
    first_ring * k vertices each, zipped into triangles."""
    vertices = [[0.0, 0.0, 0.0]]
    tris = []
    prev = [0]
    for k in range(1, rings + 1):
        n = first_ring * k
        ring = list(range(len(vertices), len(vertices) + n))
        for j in range(n):
            a = 2 * math.pi * j / n
            vertices.append([radius * k / rings * math.cos(a), radius * k / rings * math.sin(a), 0])
        i = j = 0
        m = len(prev)
        while i < (m if k > 1 else 0) or j < n:
            if j < n and (k == 1 or (j + 1) / n <= (i + 1) / m or i >= m):
                tris.append([prev[i % m], ring[j], ring[(j + 1) % n]])
                j += 1
            else:
                tris.append([prev[i % m], ring[j % n], prev[(i + 1) % m]])
                i += 1
        prev = ring
    return gs.geometry.Mesh(
        vertices=np.array(vertices), triangles=np.array(tris), origin=(0.0, 0.0, 0.0)
    )


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


def by_id(sim: gs.Simulation, *fields: str) -> dict[str, dict[int, np.ndarray]]:
    """Copies of particle fields keyed by global id."""
    with sim.particles(writable=False) as p:
        ids = [int(i) for i in p.id]
        return {f: {i: np.array(getattr(p, f)[k]) for k, i in enumerate(ids)} for f in fields}


def contacts_per_particle(sim: gs.Simulation) -> dict[int, int]:
    c = sim.contacts()
    out: dict[int, int] = {}
    for i in c["id_i"]:
        out[int(i)] = out.get(int(i), 0) + 1
    return out


def nearest_vertex(mesh: gs.geometry.Mesh, x: np.ndarray) -> tuple[int, float]:
    d = np.linalg.norm(mesh.vertices[:, :2] - x[:2], axis=1)
    k = int(np.argmin(d))
    return k, float(d[k])
