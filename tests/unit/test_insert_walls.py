"""Insertion that respects walls, and packing inside a closed triangle mesh.

Every check of a placement is independent of the core: distances to planes, rectangles,
cylinders and boxes are computed here in numpy from the closed-form geometry; mesh interiors are
checked against convex polyhedra written as half-spaces (or cubes, analytically).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs
from grainscale import _core

GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
LAW = gs.contact.HertzMindlin(restitution=0.5, friction=0.5)
R = 1e-3
BOX = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.02, 0.02, 0.02))


def positions(sim: gs.Simulation) -> tuple[np.ndarray, np.ndarray]:
    with sim.particles(writable=False) as p:
        order = np.argsort(p.id)
        return p.position[order].copy(), p.radius[order].copy()


def min_pair_gap(x: np.ndarray, r: np.ndarray) -> float:
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2) - r[:, None] - r[None, :]
    np.fill_diagonal(d, np.inf)
    return float(d.min())


def box_mesh(lo, hi, inward: bool = False) -> gs.geometry.Mesh:
    """Closed box [lo, hi] of 12 triangles, normals outward (or inward)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    c = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], dtype=float)
    quads = [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]
    tris = np.array([t for a, b, cc, d in quads for t in ((a, b, cc), (a, cc, d))])
    return gs.geometry.Mesh(vertices=c, triangles=tris[:, ::-1] if inward else tris)


def cube_mesh(lo: float, hi: float, inward: bool = False) -> gs.geometry.Mesh:
    return box_mesh((lo, lo, lo), (hi, hi, hi), inward)


def cube_surface_distance(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Distance from points to the surface of the cube [lo, hi]^3 (inside or outside)."""
    inside = np.all((x > lo) & (x < hi), axis=1)
    depth = np.minimum(x - lo, hi - x).min(axis=1)
    outside = np.linalg.norm(np.maximum(np.maximum(lo - x, x - hi), 0.0), axis=1)
    return np.where(inside, depth, outside)


def prism_mesh(n: int, radius: float, z0: float, z1: float, centre: tuple[float, float]):
    """Closed right prism over a regular n-gon (circumradius ``radius``), outward normals;
    returns the mesh and its side planes as (unit normals, apothem)."""
    a = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])
    v = np.vstack(
        [np.column_stack([ring, np.full(n, z0)]), np.column_stack([ring, np.full(n, z1)])]
    )
    v = np.vstack([v, [[*centre, z0], [*centre, z1]]])
    bottom, top = 2 * n, 2 * n + 1
    tris = []
    for k in range(n):
        j = (k + 1) % n
        tris += [(k, j, n + j), (k, n + j, n + k), (bottom, j, k), (top, n + k, n + j)]
    mid = a + np.pi / n
    normals = np.column_stack([np.cos(mid), np.sin(mid)])
    return (
        gs.geometry.Mesh(vertices=v, triangles=np.array(tris)),
        normals,
        radius * math.cos(math.pi / n),
    )


def octahedron() -> gs.geometry.Mesh:
    """|x| + |y| + |z| <= 1, outward normals."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    tris = []
    for sx, i in ((1, 0), (-1, 1)):
        for sy, j in ((1, 2), (-1, 3)):
            for sz, k in ((1, 4), (-1, 5)):
                tris.append((i, j, k) if sx * sy * sz > 0 else (i, k, j))
    return gs.geometry.Mesh(vertices=v, triangles=np.array(tris))


def icosphere(subdivisions: int, radius: float, centre: np.ndarray) -> gs.geometry.Mesh:
    """Closed sphere mesh: an icosahedron subdivided 4^subdivisions times, vertices on the
    sphere (20 x 4^s triangles, outward normals)."""
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]  # fmt: skip
    vertices = [np.array(p) / np.linalg.norm(p) for p in v]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
             (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
             (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]  # fmt: skip
    middle: dict[tuple[int, int], int] = {}  # an edge split once is never an edge again

    def mid(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in middle:
            m = vertices[a] + vertices[b]
            vertices.append(m / np.linalg.norm(m))
            middle[key] = len(vertices) - 1
        return middle[key]

    for _ in range(subdivisions):
        finer = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = finer
    return gs.geometry.Mesh(
        vertices=np.array(vertices) * radius + centre, triangles=np.array(faces)
    )


def pack(sim: gs.Simulation, region, **kw) -> np.ndarray:
    return sim.insert(gs.insert.Pack(region, radius=R, material=GLASS, **kw))


# --------------------------------------------------------------------------- Pack and walls


def test_pack_stays_on_the_particle_side_of_a_plane_and_off_a_rectangle():
    plane = gs.geometry.Plane(point=(0, 0, 0.008), normal=(0, 0, 1))
    # Two-sided vertical rectangle in x = 0.01 across part of the box.
    rect = gs.geometry.Rectangle(corner=(0.01, 0.0, 0.0), edge1=(0, 0.012, 0), edge2=(0, 0, 0.02))

    def run(seed: int) -> tuple[np.ndarray, np.ndarray]:
        sim = gs.Simulation(domain=BOX, contact=LAW)
        sim.add_wall(plane)
        sim.add_wall(rect)
        assert len(pack(sim, BOX, count=150, seed=seed)) == 150
        return positions(sim)

    x, r = run(3)
    assert np.all(x[:, 2] - 0.008 >= r - 1e-15)  # in front of the plane, not touching it
    p = np.column_stack(
        [np.full(len(x), 0.01), np.clip(x[:, 1], 0, 0.012), np.clip(x[:, 2], 0, 0.02)]
    )
    assert np.all(np.linalg.norm(x - p, axis=1) >= r - 1e-15)
    # The rectangle is an obstacle, not a fence: particles on both sides of it.
    assert np.any(x[:, 0] < 0.01) and np.any(x[:, 0] > 0.01)
    assert min_pair_gap(x, r) >= -1e-15
    x2, _ = run(3)
    assert np.array_equal(x, x2)
    assert not np.array_equal(x, run(4)[0])


def test_pack_fills_a_box_only_inside_a_cylinder_wall_up_to_the_volume_fraction():
    """An inside cylinder wall (infinite) through the box: a sphere outside it touches it (the
    contact code pushes it in), so every sphere ends up inside, clear of the surface."""
    cyl = gs.geometry.Cylinder(point=(0.01, 0.01, 0), axis=(0, 0, 1), radius=0.008)
    sim = gs.Simulation(domain=BOX, contact=LAW)
    sim.add_wall(cyl)
    ids = pack(sim, BOX, volume_fraction=0.08, seed=2)
    x, r = positions(sim)
    assert np.sum(4 / 3 * np.pi * r**3) == pytest.approx(0.08 * BOX.volume, rel=0.01)
    assert len(ids) == len(r)
    rho = np.linalg.norm(x[:, :2] - 0.01, axis=1)
    assert np.all(0.008 - rho >= r - 1e-15)
    assert min_pair_gap(x, r) >= -1e-15


def test_pack_around_a_mesh_block_avoids_the_block():
    """A closed cube mesh wall in the middle of the box. Mesh walls are two-sided: spheres that
    fit inside the block without touching it are valid too."""
    sim = gs.Simulation(domain=BOX, contact=LAW)
    sim.add_wall(cube_mesh(0.006, 0.014))
    n = 300  # volume fraction 0.16 of the box
    assert len(pack(sim, BOX, count=n, seed=5)) == n
    x, r = positions(sim)
    assert np.all(cube_surface_distance(x, 0.006, 0.014) >= r - 1e-15)
    inside = np.all((x > 0.006) & (x < 0.014), axis=1)
    assert 0 < inside.sum() < 0.1 * n
    assert min_pair_gap(x, r) >= -1e-15


def test_pack_near_jamming_inside_a_cylinder_wall_matches_the_cylinder_region():
    """A box with an inside cylinder wall offers the centres the same room as the cylinder
    region itself. Close to jamming the voxel sampler places the last particles (dropping voxels
    the wall blocks); it must get as close to saturation with the wall as with the region."""
    box = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.012, 0.012, 0.006))
    cyl = gs.geometry.Cylinder(point=(0.006, 0.006, 0), axis=(0, 0, 1), radius=0.005)
    r = 0.5e-3
    sphere = 4 / 3 * math.pi * r**3

    def sim_with_wall() -> gs.Simulation:
        sim = gs.Simulation(domain=box, contact=LAW)
        sim.add_wall(cyl)
        return sim

    sim = sim_with_wall()
    n = 290  # 0.32 of the cylinder volume; this thin cylinder saturates near 0.33 (300)
    assert n * sphere / (math.pi * 0.005**2 * 0.006) > 0.3
    sim.insert(gs.insert.Pack(box, radius=r, material=GLASS, count=n, seed=8))
    x, rr = positions(sim)
    rho = np.linalg.norm(x[:, :2] - 0.006, axis=1)
    assert np.all(0.005 - rho >= rr - 1e-15)
    assert min_pair_gap(x, rr) >= -1e-15

    def most_placed(region) -> int:
        with pytest.raises(RuntimeError, match="Pack placed only") as err:
            sim_with_wall().insert(
                gs.insert.Pack(region, radius=r, material=GLASS, count=600, seed=8)
            )
        return int(str(err.value).split()[3])

    as_region = gs.geometry.Cylinder(
        point=(0.006, 0.006, 0), axis=(0, 0, 1), radius=0.005, length=0.006
    )
    assert most_placed(box) >= 0.97 * most_placed(as_region) > n


def test_pack_tests_a_moving_wall_where_it_is_now():
    sim = gs.Simulation(domain=BOX, contact=LAW, gravity=(0, 0, 0), time_step=1e-5)
    k = sim.add_wall(gs.geometry.Plane(point=(0, 0, 0), normal=(0, 0, 1), velocity=(0, 0, 1.0)))
    sim.run(until=0.01)  # the plane has moved up 10 mm
    z = float(k.position[2])
    assert z == pytest.approx(0.01, rel=1e-9)
    pack(sim, BOX, count=60, seed=1)
    x, r = positions(sim)
    assert np.all(x[:, 2] - z >= r - 1e-15)


# --------------------------------------------------------------------------- Pack in a mesh


def test_pack_inside_a_cube_read_back_from_stl(tmp_path):
    path = tmp_path / "cube.stl"
    cube_mesh(0.002, 0.018).to_stl(path)
    mesh = gs.geometry.Mesh.from_stl(path)
    region = _core.Region.mesh(mesh.vertices, mesh.triangles)
    assert region.volume == pytest.approx(0.016**3, rel=1e-6)  # float32 STL coordinates

    def run() -> tuple[np.ndarray, np.ndarray]:
        sim = gs.Simulation(domain=BOX, contact=LAW)
        ids = sim.insert(
            gs.insert.Pack(
                mesh,
                radius=gs.dist.Uniform(min=0.6e-3, max=1.2e-3),
                material=GLASS,
                volume_fraction=0.2,
                seed=7,
            )
        )
        assert len(ids) > 100
        return positions(sim)

    x, r = run()
    assert np.sum(4 / 3 * np.pi * r**3) == pytest.approx(0.2 * region.volume, rel=0.01)
    lo, hi = 0.002, 0.018
    tol = 1e-9  # float32 vertices of the STL
    assert np.all((x - r[:, None] >= lo - tol) & (x + r[:, None] <= hi + tol))
    assert min_pair_gap(x, r) >= -1e-15
    assert np.array_equal(x, run()[0])


def test_pack_inside_a_closed_prism_mesh_stays_inside_and_clear_of_the_surface():
    n, rc, z0, z1 = 12, 0.009, 0.001, 0.019
    mesh, normals, apothem = prism_mesh(n, rc, z0, z1, (0.01, 0.01))
    region = _core.Region.mesh(mesh.vertices, mesh.triangles)
    exact = 0.5 * n * rc**2 * math.sin(2 * math.pi / n) * (z1 - z0)
    assert region.volume == pytest.approx(exact, rel=1e-12)
    sim = gs.Simulation(domain=BOX, contact=LAW)
    pack(sim, mesh, volume_fraction=0.25, seed=11)
    x, r = positions(sim)
    assert np.sum(4 / 3 * np.pi * r**3) == pytest.approx(0.25 * exact, rel=0.01)
    side = (x[:, :2] - 0.01) @ normals.T  # distance along each side normal
    assert np.all(apothem - side.max(axis=1) >= r - 1e-15)
    assert np.all((x[:, 2] - z0 >= r - 1e-15) & (z1 - x[:, 2] >= r - 1e-15))


def test_pack_inside_a_sphere_mesh_of_5120_triangles_is_inside_every_face_plane():
    """A convex polyhedron is the intersection of its faces' half-spaces: a sphere is inside
    and clear of the surface iff it is at least r behind every face plane."""
    centre = np.array([0.01, 0.01, 0.01])
    mesh = icosphere(4, 0.0095, centre)
    assert len(mesh.triangles) == 5120
    v, t = mesh.vertices, mesh.triangles
    n = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
    region = _core.Region.mesh(v, t)
    # Divergence theorem: a cone of height (n . a) over each face.
    exact = float(np.sum(np.einsum("ij,ij->i", n, v[t[:, 0]] - centre)) / 6)
    assert region.volume == pytest.approx(exact, rel=1e-12)
    assert exact == pytest.approx(4 / 3 * math.pi * 0.0095**3, rel=0.01)
    sim = gs.Simulation(domain=BOX, contact=LAW)
    pack(sim, mesh, volume_fraction=0.2, seed=6)
    x, r = positions(sim)
    assert np.sum(4 / 3 * np.pi * r**3) == pytest.approx(0.2 * exact, rel=0.01)
    unit = n / np.linalg.norm(n, axis=1)[:, None]
    behind = np.einsum("ij,ij->i", unit, v[t[:, 0]])[None, :] - x @ unit.T
    assert np.all(behind.min(axis=1) >= r - 1e-15)


def test_pack_inside_a_hollow_mesh_fills_only_the_shell():
    """Outer cube with outward normals, inner cube with inward normals: the solid is the shell;
    its volume follows from the divergence theorem, the inside test from the ray parity."""
    outer, inner = cube_mesh(0.001, 0.019), cube_mesh(0.007, 0.013, inward=True)
    mesh = gs.geometry.Mesh(
        vertices=np.vstack([outer.vertices, inner.vertices]),
        triangles=np.vstack([outer.triangles, inner.triangles + len(outer.vertices)]),
    )
    region = _core.Region.mesh(mesh.vertices, mesh.triangles)
    assert region.volume == pytest.approx(0.018**3 - 0.006**3, rel=1e-12)
    sim = gs.Simulation(domain=BOX, contact=LAW)
    pack(sim, mesh, count=200, seed=4)
    x, r = positions(sim)
    assert np.all(cube_surface_distance(x, 0.007, 0.013) >= r - 1e-15)
    assert not np.any(np.all((x > 0.007) & (x < 0.013), axis=1))
    assert np.all((x - r[:, None] >= 0.001 - 1e-15) & (x + r[:, None] <= 0.019 + 1e-15))


def test_inside_test_is_exact_on_rays_through_edges_and_vertices():
    """Octahedron |x|+|y|+|z| < 1: rays along +x from these points pass exactly through its
    vertices and edges (and graze a vertex); the parity must still be right."""
    mesh = octahedron()
    region = _core.Region.mesh(mesh.vertices, mesh.triangles)
    assert region.volume == pytest.approx(4 / 3, rel=1e-12)
    ties = np.array(
        [
            [-0.5, 0, 0], [0.2, 0, 0], [-2, 0, 0], [0.3, 0.1, 0], [-3, 0.5, 0], [0.1, 0, 0.4],
            [-2, 1, 0], [-2, 0, 1], [-2, 0.5, 0.5], [0.1, 0.25, 0.25], [-0.7, 0.1, -0.1],
        ]
    )  # fmt: skip
    rng = np.random.default_rng(0)
    random = rng.uniform(-1.2, 1.2, size=(20000, 3))
    points = np.vstack([ties, random])
    l1 = np.abs(points).sum(axis=1)
    off_surface = np.abs(l1 - 1) > 1e-12
    assert np.array_equal(region.contains(points, 0.0)[off_surface], (l1 < 1)[off_surface])
    # With a radius: inside and at least r from every face plane, (1 - |x|_1) / sqrt(3) >= r.
    r = 0.1
    depth = (1 - l1) / math.sqrt(3)
    clear = np.abs(depth - r) > 1e-12
    assert np.array_equal(region.contains(points, r)[clear], (depth >= r)[clear])


def test_open_or_inconsistent_meshes_are_refused_with_a_clear_error():
    cube = cube_mesh(0.002, 0.018)
    opened = gs.geometry.Mesh(vertices=cube.vertices, triangles=cube.triangles[1:])
    with pytest.raises(ValueError, match=r"Pack.region \(Mesh\) must be a closed surface.*open"):
        gs.insert.Pack(opened, radius=R, material=GLASS, count=1)
    tris = cube.triangles.copy()
    tris[0] = tris[0][::-1]
    flipped = gs.geometry.Mesh(vertices=cube.vertices, triangles=tris)
    with pytest.raises(ValueError, match="consistently oriented"):
        gs.insert.Pack(flipped, radius=R, material=GLASS, count=1)
    with pytest.raises(ValueError, match="Outlet.region must be a grainscale.Box or"):
        gs.insert.Outlet(cube)


# --------------------------------------------------------------------------- Stream and walls

POUR_BOX = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.03, 0.03, 0.1))
TOP = gs.insert.RectangleFace(corner=(0, 0, 0.08), edge1=(0.03, 0, 0), edge2=(0, 0.03, 0))


def test_stream_half_blocked_by_a_mesh_block_delivers_its_mass_clear_of_the_block():
    """A mesh block over half of the face reaches into the slab (z in [76, 80] mm) down to
    78.5 mm: under it only centres with z <= 77.5 mm are clear. Without gravity all particles
    move down at the same velocity, away from the block, so none can touch it later unless it
    was placed touching it."""
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW, gravity=(0.0, 0.0, 0.0))
    block_lo, block_hi = np.array([0.0, 0.0, 0.0785]), np.array([0.015, 0.03, 0.1])
    sim.add_wall(box_mesh(block_lo, block_hi))
    rate = 0.1  # solid fraction 0.044 of the stream, 0.09 in the free half
    h = sim.insert(
        gs.insert.Stream(TOP, mass_rate=rate, radius=R, material=GLASS, velocity=(0, 0, -1.0))
    )
    sim.run(until=0.03)
    x, r = positions(sim)
    assert len(r) > 250
    gap = np.linalg.norm(np.maximum(np.maximum(block_lo - x, x - block_hi), 0.0), axis=1)
    assert np.all(gap >= r - 1e-12)
    under = x[:, 0] < 0.015
    assert 0.05 * len(r) < under.sum() < 0.3 * len(r)  # a quarter of the free centre room
    assert h.inserted_mass + h.pending_mass == pytest.approx(h.scheduled_mass, rel=1e-12)
    particle = GLASS.density * 4 / 3 * math.pi * R**3
    assert 0 <= h.inserted_mass - h.requested_mass <= rate * h.interval + particle
    assert min_pair_gap(x, r) >= -1e-12


def test_stream_blocked_by_a_wall_keeps_its_mass_pending_until_the_wall_moves_away():
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW, gravity=(0.0, 0.0, 0.0))
    h = sim.insert(
        gs.insert.Stream(TOP, mass_rate=0.02, radius=R, material=GLASS, velocity=(0, 0, -1.0))
    )
    depth = h.status()["thickness"]
    # A horizontal rectangle halfway through the slab (4 radii deep): no sphere fits beside it.
    k = sim.add_wall(
        gs.geometry.Rectangle(
            corner=(0, 0, 0.08 - 0.5 * depth), edge1=(0.03, 0, 0), edge2=(0, 0.03, 0)
        )
    )
    sim.run(until=0.01)
    assert h.inserted_count == 0 and h.requested_mass > 0
    assert h.pending_mass == pytest.approx(h.scheduled_mass, rel=1e-12)
    k.set_motion(velocity=(0, 0, -2.0))  # slides down out of the slab, then below it
    sim.run(until=0.06)
    assert h.pending_count == 0
    particle = GLASS.density * 4 / 3 * math.pi * R**3
    assert 0 <= h.inserted_mass - h.requested_mass <= 0.02 * h.interval + particle
    x, r = positions(sim)
    z_wall = float(k.position[2])
    # All particles move at -1 m/s, the wall at -2 m/s: the wall ran ahead and no particle was
    # ever placed across or on it (each is at least r above it).
    assert np.all(x[:, 2] - z_wall >= r - 1e-12)
