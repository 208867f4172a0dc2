"""Walls: STL input/output, VTK output of mesh walls, rigid motion bookkeeping, wall torque and
parameter validation (DESIGN.md 2.5, 2.7)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs

MAT = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="soft")
R = 1e-3

# unit cube corners, vertex index = 4 x + 2 y + z, and its 12 outward triangles
CUBE = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
CUBE_TRIANGLES = np.array(
    [
        t
        for a, b, c, d in [
            (0, 2, 6, 4),  # z = 0
            (1, 5, 7, 3),  # z = 1
            (0, 4, 5, 1),  # y = 0
            (2, 3, 7, 6),  # y = 1
            (0, 1, 3, 2),  # x = 0
            (4, 6, 7, 5),  # x = 1
        ]
        for t in ((a, b, c), (a, c, d))
    ]
)


def triangle_corners(mesh: gs.geometry.Mesh) -> np.ndarray:
    """(T, 3, 3) corner coordinates of every triangle, in file order."""
    return mesh.vertices[mesh.triangles]


# --------------------------------------------------------------------------------------------
# STL
# --------------------------------------------------------------------------------------------


def test_stl_binary_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    vertices = rng.uniform(-0.05, 0.05, size=(30, 3))
    triangles = np.array([rng.choice(30, size=3, replace=False) for _ in range(40)])
    mesh = gs.geometry.Mesh(vertices=vertices, triangles=triangles)
    path = tmp_path / "part.stl"
    mesh.to_stl(path)

    raw = path.read_bytes()
    assert len(raw) == 84 + 50 * len(triangles), (
        f"binary STL of {len(triangles)} triangles should be {84 + 50 * len(triangles)} bytes, "
        f"got {len(raw)}"
    )
    assert int(np.frombuffer(raw[80:84], "<u4")[0]) == len(triangles)
    assert not raw.startswith(b"solid"), "binary STL header starts with 'solid' (read as ASCII)"

    back = gs.geometry.Mesh.from_stl(path)
    used = np.unique(triangles)
    assert len(back.vertices) == len(used), (
        f"{len(back.vertices)} vertices after reading, {len(used)} distinct ones written "
        "(shared vertices not merged?)"
    )
    assert len(back.triangles) == len(triangles)
    # STL stores float32 coordinates; triangle order and corner order are kept
    expected = triangle_corners(mesh).astype(np.float32).astype(float)
    np.testing.assert_array_equal(triangle_corners(back), expected)


def test_stl_round_trip_keeps_motion_and_material(tmp_path: Path) -> None:
    path = tmp_path / "cube.stl"
    gs.geometry.Mesh(vertices=CUBE, triangles=CUBE_TRIANGLES).to_stl(path)
    back = gs.geometry.Mesh.from_stl(
        path, material=MAT, velocity=(0, 0, -0.1), angular_velocity=(0, 0, 2), origin=(1, 2, 3)
    )
    assert back.material == MAT
    assert back.velocity == (0.0, 0.0, -0.1)
    assert back.angular_velocity == (0.0, 0.0, 2.0)
    assert back.origin == (1.0, 2.0, 3.0)


def ascii_cube(side: float, name: str = "cube") -> str:
    """An ASCII STL of the cube [0, side]^3 written by hand (12 facets, 36 corners)."""
    lines = [f"solid {name}"]
    for t in CUBE_TRIANGLES:
        p = CUBE[t] * side
        n = np.cross(p[1] - p[0], p[2] - p[0])
        n /= np.linalg.norm(n)
        lines.append(f"  facet normal {n[0]:g} {n[1]:g} {n[2]:g}")
        lines.append("    outer loop")
        lines += [f"      vertex {v[0]:.6e} {v[1]:.6e} {v[2]:.6e}" for v in p]
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append(f"endsolid {name}")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize(("side", "scale"), [(0.02, 1.0), (20.0, 1e-3)])
def test_stl_ascii_cube_merges_vertices(tmp_path: Path, side: float, scale: float) -> None:
    path = tmp_path / "cube_ascii.stl"
    path.write_text(ascii_cube(side))
    mesh = gs.geometry.Mesh.from_stl(path, scale=scale)
    assert mesh.vertices.shape == (8, 3) and mesh.triangles.shape == (12, 3), (
        f"ASCII cube: {len(mesh.vertices)} vertices and {len(mesh.triangles)} triangles, "
        "expected 8 and 12"
    )
    size = side * scale
    np.testing.assert_allclose(mesh.vertices.min(axis=0), 0.0, atol=1e-12)
    np.testing.assert_allclose(mesh.vertices.max(axis=0), size, rtol=1e-7)
    corners = {tuple(np.round(v / size).astype(int)) for v in mesh.vertices}
    assert corners == {tuple(c) for c in CUBE.astype(int)}, f"cube corners {sorted(corners)}"
    # orientation kept: every triangle's normal points out of the cube
    p = triangle_corners(mesh)
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    outward = p.mean(axis=1) - size / 2
    assert np.all(np.einsum("ij,ij->i", normals, outward) > 0), "triangle orientation changed"
    # the surface is closed: every edge is shared by exactly two triangles
    edges = np.sort(mesh.triangles[:, [[0, 1], [1, 2], [2, 0]]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2), f"edge use counts {counts} (vertices not merged)"


def test_stl_millimetre_cube_is_a_working_wall(tmp_path: Path) -> None:
    """A cube read from an ASCII STL in mm (scale=1e-3) holds a sphere resting on its floor."""
    path = tmp_path / "box_mm.stl"
    path.write_text(ascii_cube(10.0, name="box in mm"))
    box = gs.geometry.Mesh.from_stl(path, scale=1e-3)
    sim = gs.Simulation(
        domain=gs.Box(lo=(-1e-3,) * 3, hi=(11e-3,) * 3),
        contact=gs.contact.HertzMindlin(restitution=0.3, friction=0.3),
        time_step=1e-5,
    )
    k = sim.add_wall(box)
    sim.add_particles(position=[(5e-3, 5e-3, R + 1e-5)], radius=R, material=MAT)
    sim.run(until=0.05)
    with sim.particles(writable=False) as p:
        z, v, m = float(p.position[0, 2]), float(np.linalg.norm(p.velocity[0])), float(p.mass[0])
    assert 0.99 * R < z < R and v < 1e-5, f"sphere on the 10 mm box floor: z = {z} m, |v| = {v}"
    np.testing.assert_allclose(k.force, [0, 0, -m * 9.81], rtol=1e-6, atol=1e-15)


def test_stl_in_millimetres_read_without_scale_is_refused(tmp_path: Path) -> None:
    """A 10 mm box at 100-110 mm read without scale=1e-3 lies at 100-110 m: far outside."""
    path = tmp_path / "box_mm.stl"
    gs.geometry.Mesh(vertices=CUBE * 10 + 100, triangles=CUBE_TRIANGLES).to_stl(path)
    sim = gs.Simulation(domain=gs.Box(lo=(0.099,) * 3, hi=(0.111,) * 3))
    with pytest.raises(ValueError) as err:
        sim.add_wall(gs.geometry.Mesh.from_stl(path))
    assert str(err.value) == (
        "Simulation.add_wall.wall must reach into the domain [(0.099, 0.099, 0.099), (0.111, "
        "0.111, 0.111)] m, got a Mesh with bounds [(100, 100, 100), (110, 110, 110)] m, entirely "
        "outside the domain where no particle can touch it; for an STL file in mm read it with "
        "Mesh.from_stl(path, scale=1e-3); pass check_placement=False to accept it"
    )
    assert sim.walls == []
    sim.add_wall(gs.geometry.Mesh.from_stl(path), check_placement=False)
    sim.add_wall(gs.geometry.Mesh.from_stl(path, scale=1e-3))
    assert len(sim.walls) == 2


def test_rectangle_outside_the_domain_is_refused_touching_is_not() -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
    far = gs.Rectangle(corner=(0, 0, 0.02), edge1=(0.01, 0, 0), edge2=(0, 0.01, 0))
    with pytest.raises(ValueError, match=r"got a Rectangle with bounds \[\(0, 0, 0.02\), "):
        sim.add_wall(far)
    lid = gs.Rectangle(corner=(0, 0, 0.01), edge1=(0.01, 0, 0), edge2=(0, 0.01, 0))
    sim.add_wall(lid)  # on the domain's face


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (
            {"wall": "floor"},
            "Simulation.add_wall.wall must be a Plane, Rectangle, Cylinder or Mesh "
            "(grainscale.geometry), got 'floor'",
        ),
        (
            {"servo": "x"},
            "Simulation.add_wall.servo must be a grainscale.geometry.Servo or None, got 'x'",
        ),
        (
            {"check_placement": "no"},
            "Simulation.add_wall.check_placement must be True or False, got 'no'",
        ),
    ],
)
def test_add_wall_checks_its_argument_types_first(arguments, message) -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
    floor = gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=MAT)
    with pytest.raises(ValueError) as err:
        sim.add_wall(**({"wall": floor} | arguments))
    assert str(err.value) == message
    assert sim.walls == [] and sim.materials == []


def test_outlet_outside_the_domain_is_refused() -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
    far = gs.Box(lo=(1, 1, 1), hi=(1.02, 1.02, 1.02))
    with pytest.raises(ValueError) as err:
        sim.add_outlet(gs.insert.Outlet(far))
    assert str(err.value) == (
        "Outlet.region must meet the simulation domain [(0, 0, 0), (0.01, 0.01, 0.01)] m, got a "
        "Box with bounds [(1, 1, 1), (1.02, 1.02, 1.02)] m, entirely outside it: the outlet "
        "could never remove a particle"
    )
    assert sim.outlets == []
    below = gs.Box(lo=(-1, -1, -1), hi=(1, 1, 0.002))  # may reach beyond the domain
    sim.add_outlet(gs.insert.Outlet(below))


# --------------------------------------------------------------------------------------------
# VTK output of mesh walls
# --------------------------------------------------------------------------------------------


def read_ascii_vtp_mesh(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Points (V, 3) and triangles (T, 3) of an ASCII VTK PolyData surface."""
    root = ET.parse(path).getroot()
    piece = root.find("PolyData/Piece")
    assert piece is not None, f"{path}: no PolyData/Piece"
    points = piece.find("Points/DataArray")
    conn = piece.find("Polys/DataArray[@Name='connectivity']")
    assert points is not None and conn is not None, f"{path}: no Points or Polys connectivity"
    assert points.get("format") == "ascii", f"{path}: Points not ASCII"
    pts = np.array((points.text or "").split(), dtype=float).reshape(-1, 3)
    tri = np.array((conn.text or "").split(), dtype=np.int64).reshape(-1, 3)
    n_pts, n_polys = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfPolys"))
    assert pts.shape[0] == n_pts and tri.shape[0] == n_polys, f"{path}: counts inconsistent"
    return pts, tri


def read_pvd(path: Path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def plate(z: float = 0.0, half: float = 4e-3) -> tuple[np.ndarray, np.ndarray]:
    v = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def vtk_sim() -> gs.Simulation:
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01,) * 3, hi=(0.01,) * 3), gravity=(0, 0, 0), time_step=1e-5
    )
    sim.add_particles(position=[(0.0, 0.0, 5e-3)], radius=R, material=MAT)
    return sim


def test_vtk_writes_moving_mesh_every_snapshot(tmp_path: Path) -> None:
    sim = vtk_sim()
    v, t = plate(z=-5e-3)
    velocity = np.array([0.1, 0.0, 0.05])
    sim.add_wall(gs.geometry.Mesh(vertices=v, triangles=t, velocity=tuple(velocity)))
    sim.add_wall(gs.geometry.Mesh(vertices=v + [0, 0, 8e-3], triangles=t))  # static
    out = gs.io.VTK(tmp_path / "vtk", every_steps=100, binary=False)
    sim.output(out)
    sim.run(steps=400)

    particles = read_pvd(tmp_path / "vtk" / "particles.pvd")
    walls_pvd = tmp_path / "vtk" / "particles_walls.pvd"
    assert walls_pvd.exists(), (
        f"no walls .pvd; files: {sorted(p.name for p in out.directory.iterdir())}"
    )
    walls = read_pvd(walls_pvd)
    assert len(particles) == 5 and len(walls) == len(particles), (
        f"{len(walls)} wall snapshots for {len(particles)} particle snapshots (steps 0..400 / 100)"
    )
    files = sorted((tmp_path / "vtk").glob("particles_walls_*.vtp"))
    assert len(files) == len(walls), f"{len(files)} wall .vtp files, {len(walls)} in the .pvd"
    for time, name in walls:
        pts, tri = read_ascii_vtp_mesh(tmp_path / "vtk" / name)
        assert tri.shape == (4, 3) and pts.shape == (8, 3), f"{name}: {pts.shape}, {tri.shape}"
        moved = v + velocity * time
        np.testing.assert_allclose(
            pts[:4], moved, rtol=0, atol=1e-12, err_msg=f"{name}: moving mesh at t = {time} s"
        )
        np.testing.assert_allclose(
            pts[4:], v + [0, 0, 8e-3], rtol=0, atol=0, err_msg=f"{name}: static mesh moved"
        )
    first = read_ascii_vtp_mesh(tmp_path / "vtk" / walls[0][1])[0]
    last = read_ascii_vtp_mesh(tmp_path / "vtk" / walls[-1][1])[0]
    assert np.linalg.norm(last[:4] - first[:4]) > 0, "moving mesh written with unmoved vertices"


def test_vtk_writes_static_mesh_once(tmp_path: Path) -> None:
    sim = vtk_sim()
    v, t = plate(z=-5e-3)
    sim.add_wall(gs.geometry.Mesh(vertices=v, triangles=t))
    out = gs.io.VTK(tmp_path / "vtk", every_steps=100, binary=False)
    sim.output(out)
    sim.run(steps=300)
    files = sorted((tmp_path / "vtk").glob("particles_walls_*.vtp"))
    walls = read_pvd(tmp_path / "vtk" / "particles_walls.pvd")
    assert len(files) == 1 and len(walls) == 1, (
        f"static mesh: {len(files)} .vtp files, {len(walls)} .pvd entries (expected 1)"
    )
    pts, tri = read_ascii_vtp_mesh(files[0])
    np.testing.assert_array_equal(pts, v)
    np.testing.assert_array_equal(tri, t)


def test_vtk_writes_every_wall_type_where_it_is(tmp_path: Path) -> None:
    """Planes clipped to the domain, rectangles, cylinders (an infinite one clipped to the box,
    a drum spinning about its axis stays in place) and meshes, each triangle tagged with its
    wall; a moving rectangle is written at every snapshot where it is then."""
    sim = vtk_sim()
    sim.add_wall(gs.Plane(point=(0, 0, -5e-3), normal=(0, 0, 1)))
    lid = sim.add_wall(
        gs.Rectangle(corner=(-4e-3, -4e-3, 8e-3), edge1=(8e-3, 0, 0), edge2=(0, 8e-3, 0))
    )
    sim.add_wall(
        gs.geometry.Cylinder(
            point=(0, 0, 0), axis=(0, 0, 1), radius=9e-3, angular_velocity=(0, 0, 5.0)
        )
    )
    sim.add_wall(
        gs.geometry.Cylinder(
            point=(0, 0, -9e-3), axis=(0, 0, 1), radius=1e-3, length=2e-3, inside=False
        )
    )
    v, t = plate(z=-7e-3)
    sim.add_wall(gs.geometry.Mesh(vertices=v, triangles=t))
    lid.set_motion(velocity=(0, 0, -0.1))
    sim.output(gs.io.VTK(tmp_path / "vtk", every_steps=100, binary=False))
    sim.run(steps=200)
    walls = read_pvd(tmp_path / "vtk" / "particles_walls.pvd")
    assert len(walls) == 3, f"{len(walls)} wall snapshots of a moving lid (expected 3)"
    for time, name in walls:
        pts, tri = read_ascii_vtp_mesh(tmp_path / "vtk" / name)
        root = ET.parse(tmp_path / "vtk" / name).getroot()
        tag = root.find("PolyData/Piece/CellData/DataArray[@Name='wall']")
        assert tag is not None
        wall = np.array((tag.text or "").split(), dtype=int)
        counts = np.bincount(wall, minlength=5)
        segments = gs.io.wall_surfaces.SEGMENTS
        assert counts.tolist() == [2, 2, 2 * segments, 2 * segments, 2], counts
        floor = pts[np.unique(tri[wall == 0])]
        np.testing.assert_allclose(floor[:, 2], -5e-3, rtol=0, atol=1e-15)
        np.testing.assert_allclose(np.ptp(floor[:, :2], axis=0), 0.02, rtol=1e-12)  # the box
        top = pts[np.unique(tri[wall == 1])]
        np.testing.assert_allclose(top[:, 2], 8e-3 - 0.1 * time, rtol=0, atol=1e-12)
        drum = pts[np.unique(tri[wall == 2])]
        np.testing.assert_allclose(np.hypot(drum[:, 0], drum[:, 1]), 9e-3, rtol=1e-12)
        np.testing.assert_allclose(np.sort(np.unique(drum[:, 2]))[[0, -1]], [-0.01, 0.01])
        post = pts[np.unique(tri[wall == 3])]
        np.testing.assert_allclose(np.sort(np.unique(post[:, 2])), [-9e-3, -7e-3], atol=1e-15)


def test_plane_clipped_to_the_box_is_the_cut_polygon() -> None:
    box = gs.Box(lo=(0, 0, 0), hi=(1, 1, 1))
    pts, tri = gs.io.wall_surfaces.plane_in_box((0.5, 0.5, 0.5), (1, 1, 1), box)
    assert len(pts) == 6 and len(tri) == 4  # a regular hexagon
    np.testing.assert_allclose(pts.sum(axis=1), 1.5, atol=1e-14)
    area = (
        0.5
        * np.linalg.norm(
            np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]), axis=1
        ).sum()
    )
    np.testing.assert_allclose(area, 3 * np.sqrt(3) / 4, rtol=1e-12)  # side sqrt(2)/2
    assert len(gs.io.wall_surfaces.plane_in_box((0, 0, 2), (0, 0, 1), box)[0]) == 0  # misses


# --------------------------------------------------------------------------------------------
# motion bookkeeping and reported loads
# --------------------------------------------------------------------------------------------


def test_rotating_mesh_vertices_follow_exact_rotation() -> None:
    sim = vtk_sim()
    v, t = plate(z=-5e-3)
    w, origin = 3.0, np.array([1e-3, -2e-3, 0.0])
    k = sim.add_wall(
        gs.geometry.Mesh(vertices=v, triangles=t, angular_velocity=(0, 0, w), origin=tuple(origin))
    )
    sim.run(steps=1000)
    angle = w * sim.time
    rot = np.array(
        [[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0], [0, 0, 1]]
    )
    expected = origin + (v - origin) @ rot.T
    got = sim.mesh_walls()[0]["vertices"]
    assert sim.mesh_walls()[0]["index"] == k.index and sim.mesh_walls()[0]["moving"]
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_set_wall_motion_translates_mesh_and_reports_velocity() -> None:
    sim = vtk_sim()
    v, t = plate(z=-5e-3)
    k = sim.add_wall(gs.geometry.Mesh(vertices=v, triangles=t))
    assert not sim.mesh_walls()[0]["moving"]
    k.set_motion(velocity=(0.0, 0.2, 0.0))
    np.testing.assert_array_equal(k.velocity, [0.0, 0.2, 0.0])
    sim.run(steps=500)
    got = sim.mesh_walls()[0]["vertices"]
    np.testing.assert_allclose(got, v + [0, 0.2 * sim.time, 0], rtol=0, atol=1e-12)
    k.set_motion(velocity=(0.0, 0.0, 0.0))
    before = got.copy()
    sim.run(steps=100)
    np.testing.assert_array_equal(sim.mesh_walls()[0]["vertices"], before)


@pytest.mark.parametrize("kind", ["plane", "mesh"])
def test_wall_torque_of_resting_sphere_is_lever_arm_cross_weight(kind: str) -> None:
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01, -0.01, -0.002), hi=(0.01, 0.01, 0.01)),
        contact=gs.contact.HertzMindlin(restitution=0.3, friction=0.3),
        time_step=1e-5,
    )
    ref = np.array([1e-3, 2e-3, 0.0])  # plane point / mesh origin (torque reference)
    if kind == "plane":
        k = sim.add_wall(gs.Plane(point=tuple(ref), normal=(0, 0, 1)))
    else:
        v, t = plate(z=0.0, half=8e-3)
        k = sim.add_wall(gs.geometry.Mesh(vertices=v, triangles=t, origin=tuple(ref)))
    at = np.array([4e-3, -3e-3])
    sim.add_particles(position=[(at[0], at[1], R)], radius=R, material=MAT)
    sim.run(until=0.03)
    with sim.particles(writable=False) as p:
        m = float(p.mass[0])
        x = np.array(p.position[0])
    weight = np.array([0.0, 0.0, -m * 9.81])
    np.testing.assert_allclose(k.force, weight, rtol=1e-6, atol=1e-15)
    contact = np.array([x[0], x[1], 0.0])
    expected = np.cross(contact - ref, weight)
    np.testing.assert_allclose(
        k.torque,
        expected,
        rtol=0,
        atol=1e-6 * np.linalg.norm(expected),
        err_msg=f"{kind}: wall torque about {ref} of a sphere resting at {contact}",
    )


# --------------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("factory", "message"),
    [
        (
            lambda: gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=-1),
            "Cylinder.radius must be positive and finite (m), got -1",
        ),
        (
            lambda: gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 0), radius=1),
            "Cylinder.axis must be a non-zero vector",
        ),
        (
            lambda: gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=1, length=0),
            "Cylinder.length must be positive and finite (m), got 0",
        ),
        (
            lambda: gs.geometry.Mesh(vertices=CUBE, triangles=[[0, 1, 8]]),
            "Mesh.triangles must hold vertex indices in [0, 8), got range [0, 8]",
        ),
        (
            lambda: gs.geometry.Mesh(vertices=CUBE, triangles=[[0, -1, 2]]),
            "Mesh.triangles must hold vertex indices in [0, 8)",
        ),
        (
            lambda: gs.geometry.Mesh(vertices=CUBE[:, :2], triangles=[[0, 1, 2]]),
            "Mesh.vertices must have shape (N, 3), got (8, 2)",
        ),
        (
            lambda: gs.geometry.Mesh(vertices=CUBE, triangles=np.zeros((0, 3), int)),
            "Mesh.triangles must be a (T, 3) array, T > 0",
        ),
        (
            lambda: gs.geometry.Servo(gain=1e-3, max_speed=0.1),
            "Servo needs exactly one of target_force or target_stress",
        ),
        (
            lambda: gs.geometry.Servo(target_force=1, target_stress=1, gain=1e-3, max_speed=0.1),
            "Servo needs exactly one of target_force or target_stress",
        ),
        (
            lambda: gs.geometry.Servo(target_force=1, gain=0, max_speed=0.1),
            "Servo.gain must be positive and finite",
        ),
        (
            lambda: gs.geometry.Servo(target_force=1, gain=1e-3, max_speed=-1),
            "Servo.max_speed must be positive and finite",
        ),
        (
            lambda: gs.geometry.Servo(target_force=1, gain=1e-3, max_speed=1, integral_gain=-2),
            "Servo.integral_gain must be non-negative and finite, got -2",
        ),
    ],
)
def test_wall_parameter_validation(factory, message: str) -> None:
    with pytest.raises(ValueError) as err:
        factory()
    assert message in str(err.value), f"message {str(err.value)!r} lacks {message!r}"


def servo_sim() -> gs.Simulation:
    return gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), time_step=1e-5)


@pytest.mark.parametrize(
    ("wall", "servo", "message"),
    [
        (
            gs.Plane(point=(0, 0, 0.01), normal=(0, 0, -1)),
            gs.geometry.Servo(target_stress=1e3, gain=1e-3, max_speed=0.1),
            "Servo.area must be given",
        ),
        (
            gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=0.005),
            gs.geometry.Servo(target_force=1.0, gain=1e-3, max_speed=0.1),
            "Servo.direction must be given for Cylinder walls",
        ),
        (
            gs.geometry.Mesh(vertices=CUBE * 0.01, triangles=CUBE_TRIANGLES),
            gs.geometry.Servo(target_force=1.0, gain=1e-3, max_speed=0.1),
            "Servo.direction must be given for Mesh walls",
        ),
    ],
)
def test_servo_needs_area_or_direction(wall, servo, message: str) -> None:
    sim = servo_sim()
    with pytest.raises(ValueError, match=message.replace(".", r"\.")):
        sim.add_wall(wall, servo=servo)


def test_rejected_servo_leaves_no_wall_behind() -> None:
    """add_wall(wall, servo) that raises must not leave the wall (without its servo) in the
    simulation: parameters are validated before anything is set."""
    sim = servo_sim()
    bad = gs.geometry.Servo(target_stress=1e3, gain=1e-3, max_speed=0.1)  # Plane: no area
    with pytest.raises(ValueError, match="Servo.area"):
        sim.add_wall(gs.Plane(point=(0, 0, 0.01), normal=(0, 0, -1)), servo=bad)
    walls = sim.engine.diagnostics()["walls"]
    assert walls == 0, f"the rejected wall was added anyway: {walls} wall(s) in the core"


def test_servo_stress_on_plane_with_area_and_rectangle_default_area() -> None:
    servo = gs.geometry.Servo(target_stress=2e3, gain=1e-3, max_speed=0.1, area=4e-4)
    assert servo.force_for(gs.Plane(point=(0, 0, 0), normal=(0, 0, -1))) == pytest.approx(0.8)
    rect = gs.Rectangle(corner=(0, 0, 0), edge1=(0, 0.02, 0), edge2=(0.01, 0, 0))
    plain = gs.geometry.Servo(target_stress=2e3, gain=1e-3, max_speed=0.1)
    assert plain.force_for(rect) == pytest.approx(2e3 * 2e-4)
    np.testing.assert_allclose(plain.direction_for(rect), [0, 0, -1])


def test_wall_handle_reads_and_sets_what_the_index_methods_did() -> None:
    """add_wall returns a handle: force, torque, position, velocity, motion, servo and its
    integral, the same values as the deprecated index methods (which warn)."""
    sim = servo_sim()
    floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    assert isinstance(floor, gs.WallHandle) and floor.index == 0 and sim.walls == [floor]
    floor.set_motion(velocity=(0, 0, 0.01), angular_velocity=(0, 0, 2.0), origin=(0, 0, 0))
    m = floor.motion
    assert m.velocity.tolist() == [0, 0, 0.01] and m.angular_velocity.tolist() == [0, 0, 2.0]
    floor.set_motion(velocity=(0, 0, 0))  # None keeps the rest
    assert floor.motion.angular_velocity.tolist() == [0, 0, 2.0]
    servo = gs.geometry.Servo(target_force=1.0, gain=1e-3, max_speed=0.1, integral_gain=0.1)
    floor.servo = servo
    assert floor.servo is servo
    sim.run(steps=50, progress=False)
    assert floor.velocity[2] > 0  # nothing pushes back: the servo drives the wall in
    with pytest.warns(DeprecationWarning, match=r"wall_force\(index\) is deprecated.*wall.force"):
        np.testing.assert_array_equal(sim.wall_force(0), floor.force)
    with pytest.warns(DeprecationWarning, match="wall.position"):
        np.testing.assert_array_equal(sim.wall_position(floor), floor.position)
    with pytest.warns(DeprecationWarning, match="wall.servo_integral"):
        assert sim.wall_servo_integral(0) == floor.servo_integral != 0
    with pytest.warns(DeprecationWarning, match="wall.servo = servo"):
        sim.set_wall_servo(0, None)
    assert floor.servo is None and floor.servo_integral == 0
    with pytest.raises(ValueError, match="WallHandle.servo must be a gs.Servo or None, got 3"):
        floor.servo = 3
    with pytest.raises(ValueError, match=r"WallHandle.set_motion.velocity"):
        floor.set_motion(velocity=(0, 1))


def test_wall_index_out_of_range() -> None:
    sim = servo_sim()
    with (
        pytest.warns(DeprecationWarning),
        pytest.raises(ValueError, match=r"wall index must be in \[0, 0\), got 0"),
    ):
        sim.wall_force(0)
    with (
        pytest.warns(DeprecationWarning),
        pytest.raises(ValueError, match=r"wall index must be in \[0, 0\), got 3"),
    ):
        sim.set_wall_motion(3, velocity=(0, 0, 1))
