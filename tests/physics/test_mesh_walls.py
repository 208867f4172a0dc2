"""Walls (DESIGN.md 2.5): triangle meshes against the analytic plane, cylinders, servo, motion.

* A flat triangulated floor (regular grid, irregular Delaunay triangulation with a hub vertex
  shared by 7 triangles) must give the same force and torque history as gs.Plane, step by step,
  for spheres sliding and rolling across edges and over vertices (friction on, tangential and
  rolling history handed over between triangles) and for normal impacts on a face, an edge and a
  vertex: the surface is touched once, never twice.
* Edge of a convex ridge and vertex of a lone triangle: the Hertz law with the distance to the
  closest point (CASES.md A1 with R* = r, m* = m, E* = E/(1 - nu^2) for a rigid wall).
* Static equilibria with closed forms (mesh floor, closed mesh box corner, inside a vertical
  cylinder, on the crest of a horizontal outside cylinder).
* Servo-controlled lid; prescribed motion (translating plane, spinning mesh turntable, drum).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
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


# --------------------------------------------------------------------------------------------
# 1. sliding and rolling across edges and vertices: mesh floor == analytic plane
# --------------------------------------------------------------------------------------------

SLIDE_DT = 1e-5
SLIDE_STEPS = 3000


def slide_paths(mesh: gs.geometry.Mesh) -> list[tuple[tuple, tuple, tuple]]:
    """(start, velocity, angular velocity) of the sliding spheres, one per region of the floor
    (they never meet). Travel in SLIDE_STEPS: at most 0.45 m/s x 0.03 s = 9 h."""
    # a vertex of valence >= 6 near (10 h, 10 h) for a path along a generic direction
    near = np.nonzero(np.linalg.norm(mesh.vertices[:, :2] - [10 * H, 10 * H], axis=1) < 2 * H)[0]
    hub = int(max(near, key=lambda k: valence(mesh, int(k))))
    assert valence(mesh, hub) >= 6, f"no vertex of valence >= 6 near (10 h, 10 h): {near}"
    hx, hy = mesh.vertices[hub, :2]
    c, s = math.cos(2.2), math.sin(2.2)
    return [
        # starts exactly over the vertex at the origin (hub), spinning about z
        ((0.0, 0.0), (0.35, 0.20), (0.0, 0.0, 60.0)),
        # along (1, 1): over grid vertices, across diagonals at their middle; topspin
        ((-12 * H, 2 * H), (0.30, 0.30), (-200.0, 200.0, 0.0)),
        # along the grid line y = -6 h, through grid vertices
        ((-13 * H, -6 * H), (0.40, 0.0), (0.0, 0.0, 0.0)),
        # generic direction across edges, with back spin
        ((5.37 * H, -15.21 * H), (-0.10, 0.45), (300.0, 0.0, 0.0)),
        # generic direction passing over vertex `hub` after about 0.024 s
        ((hx - 6 * H * c, hy - 6 * H * s), (0.4 * c, 0.4 * s), (0.0, 0.0, -40.0)),
        # rolling without slip from the start: the tangential spring stays below the Coulomb
        # limit, so its history (handed over at every edge) sets the force
        ((-4 * H, -10.7 * H), (0.25, -0.05), (0.05 / R, 0.25 / R, 0.0)),
    ]


def slide_sim(wall, paths, law) -> tuple[gs.Simulation, np.ndarray]:
    sim = gs.Simulation(
        domain=gs.Box(lo=(-FLOOR_HALF,) * 2 + (-0.01,), hi=(FLOOR_HALF,) * 2 + (0.02,)),
        contact=law,
        gravity=(0.0, 0.0, -G),
        time_step=SLIDE_DT,
        record_contacts=True,
    )
    sim.add_wall(wall)
    z = R - static_overlap(MASS * G)
    ids = sim.add_particles(
        position=[(x, y, z) for (x, y), _, _ in paths],
        radius=R,
        material=MAT,
        velocity=[(vx, vy, 0.0) for _, (vx, vy), _ in paths],
        angular_velocity=[w for _, _, w in paths],
    )
    return sim, ids


@pytest.mark.parametrize("floor", ["grid", "irregular"])
@pytest.mark.parametrize("rolling", [None, "epsd"])
def test_sliding_rolling_on_mesh_matches_plane(floor, rolling):
    mesh = grid_floor() if floor == "grid" else irregular_floor()[0]
    hub_valence = valence(mesh, int(nearest_vertex(mesh, np.zeros(3))[0]))
    assert hub_valence >= 6, f"{floor} floor: vertex at the origin has valence {hub_valence}"
    law = gs.contact.HertzMindlin(
        restitution=0.5,
        friction=0.3,
        rolling=gs.contact.EPSD(0.05, 0.3) if rolling == "epsd" else None,
    )
    paths = slide_paths(mesh)
    plane, ids = slide_sim(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)), paths, law)
    tri, _ = slide_sim(mesh, paths, law)
    f_scale, t_scale = MASS * G, MASS * G * R
    worst, first = 0.0, None
    count_mismatch = []
    for step in range(1, SLIDE_STEPS + 1):
        plane.run(steps=1)
        tri.run(steps=1)
        a = by_id(plane, "force", "torque", "position")
        b = by_id(tri, "force", "torque", "position")
        for i in (int(k) for k in ids):
            df = np.linalg.norm(a["force"][i] - b["force"][i]) / f_scale
            dt = np.linalg.norm(a["torque"][i] - b["torque"][i]) / t_scale
            worst = max(worst, df, dt)
            if max(df, dt) > HISTORY_TOL and first is None:
                x = b["position"][i]
                k, dv = nearest_vertex(mesh, x)
                first = (
                    f"step {step}, particle {i} at ({x[0]:.6e}, {x[1]:.6e}) m, {dv:.3e} m from "
                    f"vertex {k} (valence {valence(mesh, k)}): |dF| = {df:.3e} m g, "
                    f"|dT| = {dt:.3e} m g r; plane F = {a['force'][i]} N, mesh F = "
                    f"{b['force'][i]} N; contacts of this particle: plane "
                    f"{contacts_per_particle(plane).get(i, 0)}, mesh "
                    f"{contacts_per_particle(tri).get(i, 0)}"
                )
        if plane.num_contacts() != tri.num_contacts():
            count_mismatch.append(step)
    assert first is None and not count_mismatch, (
        f"{floor} floor, rolling={rolling}: mesh and plane force/torque histories differ by up "
        f"to {worst:.3e} (gate {HISTORY_TOL}); first at {first}; contact counts differ at "
        f"{len(count_mismatch)} of {SLIDE_STEPS} steps {count_mismatch[:5]}..."
    )
    dfw = np.linalg.norm(plane.wall_force(0) - tri.wall_force(0)) / (len(ids) * f_scale)
    dtw = np.linalg.norm(plane.wall_torque(0) - tri.wall_torque(0)) / (len(ids) * f_scale * 0.03)
    assert dfw <= HISTORY_TOL and dtw <= HISTORY_TOL, (
        f"{floor} floor: wall force differs by {dfw:.3e} x N m g, wall torque by {dtw:.3e}"
    )
    # the spheres really travelled across several triangles (and stayed apart)
    end = by_id(tri, "position")["position"]
    for i, ((x0, y0), _, _) in zip(ids, paths, strict=True):
        travelled = math.hypot(end[int(i)][0] - x0, end[int(i)][1] - y0)
        assert travelled > 4 * H, f"sphere {int(i)} travelled only {travelled:.3e} m"
    assert tri.num_contacts() == len(ids), f"{tri.num_contacts()} contacts at the end"


# --------------------------------------------------------------------------------------------
# 2. normal impacts
# --------------------------------------------------------------------------------------------

V0 = 0.5  # impact speed, m/s


def hertz_closed_form(v0: float) -> tuple[float, float, float]:
    """(delta_max, F_max, t_c) of the elastic Hertz impact on a rigid wall (CASES.md A1)."""
    dmax = (15.0 * MASS * v0**2 / (16.0 * E_STAR * math.sqrt(R))) ** 0.4
    return dmax, K_HERTZ * dmax**1.5, 2.0 * 1.471638 * dmax / v0


def impact(wall, target, direction, restitution: float, steps_per_contact: int = 400):
    """Sphere touching ``target`` (the wall point it hits) at t = 0, moving at V0 along
    -``direction``; no gravity, no friction. Records every step."""
    _, _, tc = hertz_closed_form(V0)
    dt = tc / steps_per_contact
    n = np.asarray(direction, float) / np.linalg.norm(direction)
    x0 = np.asarray(target, float) + R * n
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.03, -0.03, -0.03), hi=(0.03, 0.03, 0.03)),
        contact=gs.contact.HertzMindlin(restitution=restitution, friction=0.0),
        gravity=(0.0, 0.0, 0.0),
        time_step=dt,
        record_contacts=True,
    )
    sim.add_wall(wall)
    sim.add_particles(position=[x0], radius=R, material=MAT, velocity=[-V0 * n])
    rec = {k: [] for k in ("x", "v", "force", "overlap", "count")}
    for _ in range(int(2.5 * steps_per_contact)):
        sim.run(steps=1)
        with sim.particles(writable=False) as p:
            rec["x"].append(np.array(p.position[0]))
            rec["v"].append(np.array(p.velocity[0]))
            rec["force"].append(np.array(p.force[0]))
        c = sim.contacts()
        rec["count"].append(sim.num_contacts())
        rec["overlap"].append(float(c["overlap"].sum()))
    out = {k: np.array(v) for k, v in rec.items()}
    out["n"] = n
    out["dt"] = dt
    return out


def _compare_to_plane(name: str, got: dict, ref: dict) -> None:
    dmax, fmax, _ = hertz_closed_form(V0)
    assert got["count"].max() <= 1, (
        f"{name}: {got['count'].max()} contacts at step {int(np.argmax(got['count'])) + 1} "
        "(one surface touched twice)"
    )
    np.testing.assert_array_equal(
        got["count"], ref["count"], err_msg=f"{name}: contact count per step differs from plane"
    )
    df = np.abs(got["force"] - ref["force"]).max() / fmax
    do = np.abs(got["overlap"] - ref["overlap"]).max() / dmax
    assert df <= HISTORY_TOL and do <= HISTORY_TOL, (
        f"{name}: force history differs from the plane by {df:.3e} F_max, overlap by "
        f"{do:.3e} delta_max (gate {HISTORY_TOL}); step of worst force "
        f"{int(np.argmax(np.abs(got['force'] - ref['force']).max(axis=1))) + 1}"
    )


@pytest.fixture(scope="module")
def plane_impacts():
    return {
        e: impact(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)), (0.0, 0.0, 0.0), (0, 0, 1), e)
        for e in (1.0, 0.5)
    }


def _impact_targets():
    irregular, hub = irregular_floor()
    h = H
    return {
        "grid-face": (grid_floor(), (h / 3, h / 4, 0.0)),
        "grid-edge-axis": (grid_floor(), (0.5 * h, 0.0, 0.0)),
        "grid-edge-diagonal": (grid_floor(), (0.5 * h, 0.5 * h, 0.0)),
        "grid-vertex": (grid_floor(), (0.0, 0.0, 0.0)),
        "irregular-hub-vertex": (irregular, tuple(irregular.vertices[hub])),
    }


@pytest.mark.parametrize("restitution", [1.0, 0.5])
@pytest.mark.parametrize("where", list(_impact_targets()))
def test_normal_impact_on_flat_mesh_matches_plane(where, restitution, plane_impacts):
    mesh, target = _impact_targets()[where]
    got = impact(mesh, target, (0, 0, 1), restitution)
    ref = plane_impacts[restitution]
    assert ref["count"].max() == 1 and ref["count"][-1] == 0, "plane reference impact incomplete"
    _compare_to_plane(f"{where}, e = {restitution}", got, ref)
    v_out = got["v"][-1, 2]
    assert abs(v_out / V0 - restitution) <= 1e-3, (
        f"{where}: restitution {v_out / V0:.6f}, prescribed {restitution}"
    )


def ridge_mesh(half: float = 5e-3) -> gs.geometry.Mesh:
    """Two triangles meeting at 90 deg along the y axis (a convex roof, ridge at z = 0)."""
    v = np.array([[0, -half, 0], [0, half, 0], [half, 0, -half], [-half, 0, -half]], float)
    return gs.geometry.Mesh(vertices=v, triangles=np.array([[0, 1, 2], [1, 0, 3]]))


def lone_triangle(side: float = 5e-3) -> gs.geometry.Mesh:
    v = np.array([[0, 0, 0], [side, 0, 0], [0, side, 0]], float)
    return gs.geometry.Mesh(vertices=v, triangles=np.array([[0, 1, 2]]))


@pytest.mark.parametrize(
    ("name", "make", "target", "direction"),
    [
        ("ridge edge (bisector)", ridge_mesh, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
        ("ridge edge (off middle)", ridge_mesh, (0.0, 1.3e-3, 0.0), (0.0, 0.0, 1.0)),
        ("lone triangle vertex", lone_triangle, (0.0, 0.0, 0.0), (-1.0, -1.0, -1.0)),
        ("lone triangle vertex (in plane)", lone_triangle, (0.0, 0.0, 0.0), (-1.0, -2.0, 0.0)),
    ],
)
def test_impact_on_edge_and_vertex_follows_hertz_with_closest_point(name, make, target, direction):
    res = impact(make(), target, direction, restitution=1.0)
    dmax, fmax, tc = hertz_closed_form(V0)
    n = res["n"]
    dist = np.linalg.norm(res["x"] - np.asarray(target), axis=1)
    overlap = R - dist
    touching = overlap > 0
    assert res["count"].max() == 1, f"{name}: up to {res['count'].max()} contacts (expected 1)"
    np.testing.assert_array_equal(
        res["count"], touching.astype(int), err_msg=f"{name}: contact count vs geometric overlap"
    )
    # force along the line to the closest point, magnitude K delta^1.5 at every step
    expected = K_HERTZ * np.clip(overlap, 0, None)[:, None] ** 1.5 * n
    per_step = np.abs(res["force"] - expected).max(axis=1)
    dev = per_step.max() / fmax
    assert dev <= 1e-9, (
        f"{name}: force deviates from (4/3) E* sqrt(r) delta^1.5 along the closest-point "
        f"direction by {dev:.3e} F_max (worst step {int(np.argmax(per_step)) + 1})"
    )
    assert abs(overlap.max() / dmax - 1) <= 5e-3, (
        f"{name}: delta_max {overlap.max():.6e} m, A1 {dmax:.6e} m"
    )
    f_n = res["force"] @ n
    assert abs(f_n.max() / fmax - 1) <= 5e-3, f"{name}: F_max {f_n.max():.6e} N, A1 {fmax:.6e} N"
    k = int(np.nonzero(~touching & (np.arange(len(touching)) > np.argmax(touching)))[0][0])
    t_end = res["dt"] * (k + overlap[k - 1] / (overlap[k - 1] - overlap[k]))
    assert abs(t_end / tc - 1) <= 5e-3, f"{name}: t_c = {t_end:.6e} s, A1 {tc:.6e} s"
    v_out = float(res["v"][-1] @ n)
    assert abs(v_out / V0 - 1) <= 1e-4, f"{name}: v_out/v_in = {v_out / V0:.8f} (elastic: 1)"
    # no force perpendicular to the approach line: it bounced straight back
    lateral = res["v"][-1] - v_out * n
    assert np.linalg.norm(lateral) <= 1e-9 * V0, f"{name}: lateral exit velocity {lateral} m/s"


def low_pyramid(tilt_deg: float, rim: float = 5e-3) -> gs.geometry.Mesh:
    """Convex hexagonal fan: apex at the origin, 6 rim vertices at radius ``rim``, each face
    sloping down by about ``tilt_deg`` (a gently curved, faceted surface as in CAD meshes)."""
    drop = rim * math.tan(math.radians(tilt_deg))
    v = [[0.0, 0.0, 0.0]] + [
        [rim * math.cos(k * math.pi / 3), rim * math.sin(k * math.pi / 3), -drop] for k in range(6)
    ]
    tris = [[0, 1 + k, 1 + (k + 1) % 6] for k in range(6)]
    return gs.geometry.Mesh(vertices=np.array(v), triangles=np.array(tris))


@pytest.mark.parametrize("offset", [1e-5, 3e-5])
@pytest.mark.parametrize("tilt_deg", [0.05, 0.2, 0.5])
def test_near_vertex_of_convex_faceted_surface_single_contact(tilt_deg, offset):
    """A sphere over a face, ``offset`` from the apex of a convex fan of non-coplanar faces: the
    surface lies below the face's plane, so its closest point is the foot on that face — one
    contact, Hertz with that distance. (Faces of the fan that share only the apex with it come
    within the sphere, near their edges through the apex.)"""
    mesh = low_pyramid(tilt_deg)
    a, b, c = mesh.vertices[mesh.triangles[0]]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    foot = a + offset * np.array([math.cos(math.radians(10)), math.sin(math.radians(10)), 0.0])
    foot -= ((foot - a) @ n) * n  # on face 0, near the apex
    delta = 1e-6
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01,) * 3, hi=(0.01,) * 3),
        contact=gs.contact.HertzMindlin(restitution=1.0, friction=0.0),
        gravity=(0.0, 0.0, 0.0),
        time_step=1e-7,
        record_contacts=True,
    )
    sim.add_wall(mesh)
    sim.add_particles(position=[foot + (R - delta) * n], radius=R, material=MAT)
    sim.run(steps=1)
    with sim.particles(writable=False) as p:
        x, force = np.array(p.position[0]), np.array(p.force[0])
    overlap = R - (x - a) @ n
    expected = K_HERTZ * overlap**1.5 * n
    err = np.linalg.norm(force - expected) / np.linalg.norm(expected)
    assert sim.num_contacts() == 1 and err <= 1e-9, (
        f"faces tilted {tilt_deg} deg, sphere {offset:.1e} m from the apex: "
        f"{sim.num_contacts()} contacts (expected 1), force {force} N vs Hertz with the distance "
        f"to the face {expected} N (|F| / K delta^1.5 = "
        f"{np.linalg.norm(force) / np.linalg.norm(expected):.4f})"
    )


# --------------------------------------------------------------------------------------------
# 3. rest: mesh floor, closed mesh box corner, inside a cylinder
# --------------------------------------------------------------------------------------------

SETTLE_DT = 1e-5


def settle(sim: gs.Simulation, until: float, every: int = 1) -> dict[int, int]:
    """Run to ``until``; returns the largest number of contacts seen per particle."""
    most: dict[int, int] = {}
    while sim.time < until - 0.5 * SETTLE_DT:
        sim.run(steps=every)
        for i, c in contacts_per_particle(sim).items():
            most[i] = max(most.get(i, 0), c)
    return most


def check_rest(name: str, sim: gs.Simulation, gravity: np.ndarray, n_walls: int) -> None:
    with sim.particles(writable=False) as p:
        speed = np.linalg.norm(p.velocity, axis=1)
        spin = np.linalg.norm(p.angular_velocity, axis=1) * p.radius
        weight = float(p.mass.sum()) * gravity
        ids = np.array(p.id)
    k = int(np.argmax(np.maximum(speed, spin)))
    assert speed.max() < 1e-6 and spin.max() < 1e-6, (
        f"{name}: not at rest at t = {sim.time} s: particle {ids[k]} has |v| = {speed[k]:.3e} "
        f"m/s, |w| r = {spin[k]:.3e} m/s (gate 1e-6)"
    )
    total = sum(sim.wall_force(k) for k in range(n_walls))
    err = np.linalg.norm(total - weight) / np.linalg.norm(weight)
    assert err <= 1e-6, (
        f"{name}: sum of wall forces {total} N, weight m g = {weight} N (rel. error {err:.3e})"
    )


def test_rest_on_mesh_floor_face_edge_vertex():
    mesh = grid_floor(half=0.01)
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01, -0.01, -0.005), hi=(0.01, 0.01, 0.01)),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.3),
        time_step=SETTLE_DT,
        record_contacts=True,
    )
    sim.add_wall(mesh)
    near = 0.3 * math.sqrt(2 * R * static_overlap(MASS * G))  # inside the contact disc
    where = {
        "face": (-4 * H + H / 3, -4 * H + H / 4),
        "edge": (4 * H + 0.4 * H, -4 * H),
        "vertex": (-4 * H, 4 * H),
        "near vertex (on a grid line)": (4 * H - near, 4 * H),
        "near vertex (inside a face)": (near, 0.3 * near),
    }
    ids = sim.add_particles(
        position=[(x, y, R + 2e-5) for x, y in where.values()], radius=R, material=MAT
    )
    most = settle(sim, 0.05)
    final = contacts_per_particle(sim)
    wrong = [
        f"sphere {int(i)} on the {name} at ({xy[0]:.6e}, {xy[1]:.6e}) m: "
        f"{final.get(int(i), 0)} contacts at the end, up to {most.get(int(i), 0)} while settling"
        for (name, xy), i in zip(where.items(), ids, strict=True)
        if final.get(int(i)) != 1 or most.get(int(i)) != 1
    ]
    assert not wrong, "expected exactly 1 contact per sphere: " + "; ".join(wrong)
    check_rest("mesh floor", sim, np.array([0, 0, -G]), 1)
    delta = static_overlap(MASS * G)
    c = sim.contacts()
    assert np.allclose(c["overlap"], delta, rtol=1e-6), (
        f"overlaps {c['overlap']} m, static Hertz {delta:.6e} m"
    )


def test_rest_in_corner_of_closed_mesh_box():
    side = 0.01
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.001,) * 3, hi=(side + 0.001,) * 3),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.3),
        gravity=tuple(-G / math.sqrt(3) * np.ones(3)),
        time_step=SETTLE_DT,
        record_contacts=True,
    )
    sim.add_wall(box_mesh(0.0, side))
    sim.add_particles(position=[(R + 2e-5,) * 3], radius=R, material=MAT)
    most = settle(sim, 0.05)
    gravity = -G / math.sqrt(3) * np.ones(3)
    check_rest("mesh box corner", sim, gravity, 1)
    c = sim.contacts()
    assert len(c["overlap"]) == 3 and most.get(0) == 3, (
        f"sphere in the box corner: {len(c['overlap'])} contacts at the end, up to "
        f"{most.get(0)} while settling (expected the 3 faces); normals {c['normal']}"
    )
    normals = np.sort(np.round(c["normal"], 9), axis=0)
    assert np.allclose(np.abs(c["normal"]).sum(axis=1), 1.0, atol=1e-9) and np.allclose(
        np.abs(c["normal"]).sum(axis=0), 1.0, atol=1e-9
    ), f"contact normals {normals} are not the three face normals"
    assert np.ptp(c["overlap"]) <= 1e-9 * c["overlap"].max(), (
        f"corner overlaps not symmetric: {c['overlap']} m"
    )
    # force on the wall per face ~ m g / sqrt(3) (friction may hold a small symmetric residual)
    delta = static_overlap(MASS * G / math.sqrt(3))
    assert np.allclose(c["overlap"], delta, rtol=0.05), (
        f"corner overlaps {c['overlap']} m, static Hertz under m g/sqrt(3): {delta:.6e} m"
    )


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_rest_inside_vertical_cylinder_with_floor(friction):
    rc, tilt = 5e-3, math.radians(30.0)
    gravity = G * np.array([math.sin(tilt), 0.0, -math.cos(tilt)])
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.006, -0.006, -0.001), hi=(0.006, 0.006, 0.01)),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=friction),
        gravity=tuple(gravity),
        time_step=SETTLE_DT,
        record_contacts=True,
    )
    cyl = sim.add_wall(gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=rc))
    floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    sim.add_particles(position=[(rc - R - 2e-5, 0.0, R + 2e-5)], radius=R, material=MAT)
    most = settle(sim, 0.05)
    check_rest("inside cylinder", sim, gravity, 2)
    c = sim.contacts()
    assert sorted(int(j) for j in c["id_j"]) == [-1 - floor, -1 - cyl] and most.get(0) == 2, (
        f"inside cylinder: contacts with {c['id_j']} (expected floor and cylinder once each), up "
        f"to {most.get(0)} while settling"
    )
    f_cyl, f_floor = sim.wall_force(cyl), sim.wall_force(floor)
    w = MASS * G
    normals = {int(j): n for j, n in zip(c["id_j"], c["normal"], strict=True)}
    assert np.allclose(normals[-1 - cyl], [-1, 0, 0], atol=1e-12) and np.allclose(
        normals[-1 - floor], [0, 0, 1], atol=1e-12
    ), f"contact normals {normals} (expected -x from the cylinder, +z from the floor)"
    if friction > 0:
        return  # with friction the split between the two walls is statically indeterminate
    assert np.allclose(f_cyl, [w * math.sin(tilt), 0, 0], atol=1e-6 * w) and np.allclose(
        f_floor, [0, 0, -w * math.cos(tilt)], atol=1e-6 * w
    ), (
        f"cylinder carries {f_cyl} N (expected m g sin = {w * math.sin(tilt):.6e} N along x), "
        f"floor {f_floor} N (expected -m g cos = {-w * math.cos(tilt):.6e} N along z)"
    )


# --------------------------------------------------------------------------------------------
# 4. on the crest of a horizontal outside cylinder
# --------------------------------------------------------------------------------------------


def test_rest_on_crest_of_outside_cylinder_static_hertz_overlap():
    rc = 4e-3
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.006, -0.006, -0.006), hi=(0.006, 0.006, 0.008)),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.3),
        time_step=SETTLE_DT,
        record_contacts=True,
    )
    cyl = sim.add_wall(
        gs.geometry.Cylinder(point=(-0.006, 0, 0), axis=(1, 0, 0), radius=rc, inside=False)
    )
    sim.add_particles(position=[(0.0, 0.0, rc + R + 2e-5)], radius=R, material=MAT)
    settle(sim, 0.05)
    check_rest("crest of outside cylinder", sim, np.array([0, 0, -G]), 1)
    with sim.particles(writable=False) as p:
        x = np.array(p.position[0])
    delta = static_overlap(MASS * G)  # (3 m g / (4 E* sqrt(r)))^(2/3)
    got = rc + R - x[2]
    assert abs(got / delta - 1) <= 1e-6, (
        f"overlap on the crest {got:.9e} m, static Hertz (R* = r) {delta:.9e} m "
        f"(rel. {got / delta - 1:+.3e})"
    )
    assert abs(x[0]) <= 1e-12 and abs(x[1]) <= 1e-12, f"sphere left the crest: {x}"
    assert np.allclose(sim.wall_force(cyl), [0, 0, -MASS * G], rtol=1e-6, atol=1e-12)


# --------------------------------------------------------------------------------------------
# 5. servo-controlled lid
# --------------------------------------------------------------------------------------------


def test_servo_lid_reaches_and_holds_target_stress():
    n, nz, spacing = 6, 8, 2.1e-3
    side = n * spacing
    top = nz * spacing + 0.3e-3
    box = gs.Box(lo=(0, 0, 0), hi=(side, side, top + 2e-3))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.3),
        time_step=1e-5,
    )
    for wall in gs.geometry.box_walls(box):
        if wall.normal[2] >= 0:  # all but the top plane
            sim.add_wall(wall)
    stress = 1000.0
    servo = gs.geometry.Servo(target_stress=stress, gain=0.3, max_speed=0.02)
    lid = sim.add_wall(
        gs.Rectangle(corner=(0, 0, top), edge1=(0, side, 0), edge2=(side, 0, 0)), servo=servo
    )
    rng = np.random.default_rng(3)
    cells = np.stack(np.meshgrid(*(np.arange(k) for k in (n, n, nz)), indexing="ij"), -1)
    pos = (cells.reshape(-1, 3) + 0.5) * spacing + rng.uniform(-4e-5, 4e-5, (n * n * nz, 3))
    sim.add_particles(position=pos, radius=R, material=MAT)
    target = stress * side * side
    t, load, z = [], [], []
    while sim.time < 0.3 - 1e-9:
        sim.run(steps=20)
        t.append(sim.time)
        load.append(float(sim.wall_force(lid) @ [0, 0, 1]))
        z.append(float(sim.wall_position(lid)[2]))
    t, load, z = np.array(t), np.array(load), np.array(z)
    assert top - z[-1] > 1e-3, f"the lid moved only {top - z[-1]:.3e} m"
    window = t >= 0.2
    mean = load[window].mean()
    assert abs(mean / target - 1) <= 0.02, (
        f"mean lid load over t in [0.2, 0.3] s = {mean:.5f} N, target {target:.5f} N "
        f"({stress} Pa x {side * side:.4e} m^2), rel. {mean / target - 1:+.3e}"
    )
    first, second = np.array_split(load[window], 2)
    drift = (second.mean() - first.mean()) / target
    assert abs(drift) <= 0.005, f"lid load drifts by {drift:+.3e} x target over 0.1 s"
    dz = np.ptp(z[window])
    assert dz <= 1e-3 * R, f"lid still moving: z varies by {dz:.3e} m over the last 0.1 s"


# --------------------------------------------------------------------------------------------
# 6. prescribed motion
# --------------------------------------------------------------------------------------------


def test_moving_plane_position_and_push():
    v_wall = 0.2
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01, -0.01, -0.01), hi=(0.02, 0.01, 0.01)),
        contact=gs.contact.HertzMindlin(restitution=1.0, friction=0.0),
        gravity=(0.0, 0.0, 0.0),
        time_step=1e-6,
    )
    k = sim.add_wall(
        gs.Plane(point=(0.0, 1e-3, -2e-3), normal=(1, 0, 0), velocity=(v_wall, 0.0, 0.0))
    )
    sim.add_particles(position=[(R + 1e-3, 0.0, 0.0)], radius=R, material=MAT)
    sim.run(steps=10000)
    t = sim.time
    expected = np.array([v_wall * t, 1e-3, -2e-3])
    got = sim.wall_position(k)
    assert np.allclose(got, expected, rtol=1e-12, atol=1e-15), (
        f"wall position after t = {t} s: {got}, expected point + v t = {expected}"
    )
    assert np.allclose(sim.wall_velocity(k), [v_wall, 0, 0])
    with sim.particles(writable=False) as p:
        v = np.array(p.velocity[0])
        x = np.array(p.position[0])
    # elastic impact with an infinitely heavy wall: the sphere leaves at 2 v_wall
    assert abs(v[0] / (2 * v_wall) - 1) <= 1e-4 and abs(v[1]) + abs(v[2]) == 0, (
        f"pushed sphere velocity {v} m/s, expected ({2 * v_wall}, 0, 0)"
    )
    assert x[0] - R > got[0], "sphere behind the moving plane"


def test_spinning_mesh_turntable_drags_sphere_into_rolling_orbit():
    """A sphere at rest on a turntable spinning at W: friction brings the contact point to the
    surface velocity W x r_c (no slip) within a few steps; from then on, rolling without
    slipping, the centre moves on a circle about the axis at angular velocity 2 W / 7 (speed
    2/7 W rho), not with the table."""
    w_table = 5.0
    mesh = gs.geometry.Mesh(
        **{k: getattr(disc_mesh(0.02, 8, 6), k) for k in ("vertices", "triangles")},
        origin=(0.0, 0.0, 0.0),
        angular_velocity=(0.0, 0.0, w_table),
    )
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.025, -0.025, -0.005), hi=(0.025, 0.025, 0.01)),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        time_step=1e-5,
        record_contacts=True,
    )
    sim.add_wall(mesh)
    rho0 = 0.008
    sim.add_particles(position=[(rho0, 1e-3, R - static_overlap(MASS * G))], radius=R, material=MAT)
    sim.run(steps=1000)
    angles, times = [], []
    for _ in range(20):
        sim.run(steps=500)
        with sim.particles(writable=False) as p:
            x, v, w = (np.array(a[0]) for a in (p.position, p.velocity, p.angular_velocity))
        assert sim.num_contacts() == 1, f"{sim.num_contacts()} contacts with the turntable"
        contact = x - np.array([0, 0, x[2]])  # contact point at z = 0
        surface = np.cross([0, 0, w_table], contact)
        slip = v + np.cross(w, [0, 0, -x[2]]) - surface
        assert np.linalg.norm(slip) <= 0.02 * np.linalg.norm(surface), (
            f"t = {sim.time:.3f} s: contact point velocity differs from the table's "
            f"W x r = {surface} m/s by {slip} m/s"
        )
        rho = math.hypot(x[0], x[1])
        speed = math.hypot(v[0], v[1])
        assert abs(speed / (2 / 7 * w_table * rho) - 1) <= 0.02, (
            f"t = {sim.time:.3f} s: centre speed {speed:.5e} m/s, rolling on a turntable "
            f"2/7 W rho = {2 / 7 * w_table * rho:.5e} m/s"
        )
        angles.append(math.atan2(v[1], v[0]))
        times.append(sim.time)
    rate = np.polyfit(times, np.unwrap(angles), 1)[0]
    assert abs(rate / (2 / 7 * w_table) - 1) <= 0.02, (
        f"velocity direction turns at {rate:.5f} rad/s, expected 2 W / 7 = {2 / 7 * w_table:.5f}"
    )


def drum_sim(w_drum: float, rolling, gravity=(0.0, 0.0, -G)) -> tuple[gs.Simulation, int]:
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.012, -0.005, -0.012), hi=(0.012, 0.005, 0.012)),
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5, rolling=rolling),
        gravity=gravity,
        time_step=1e-5,
        record_contacts=True,
    )
    k = sim.add_wall(
        gs.geometry.Cylinder(
            point=(0, -0.005, 0), axis=(0, 1, 0), radius=0.01, angular_velocity=(0, w_drum, 0)
        )
    )
    return sim, k


def test_drum_spin_in_place_does_not_rebuild_lists():
    sim, _ = drum_sim(20.0, None, gravity=(0.0, 0.0, 0.0))
    sim.add_particles(position=[(0.0, 0.0, 0.0)], radius=R, material=MAT)
    sim.run(steps=20000)  # the drum surface travels 4 m: 4e4 skins
    assert sim._level.rebuilds <= 2, (
        f"{sim._level.rebuilds} list rebuilds for a drum spinning in place about its own axis"
    )


def test_drum_carries_sphere_up_to_rolling_friction_angle():
    """A sphere in a drum spinning at W rolls in place at the angle where friction balances the
    rolling resistance torque mu_r r F_n: tan(theta) = mu_r (contact lever r - delta/2)."""
    mu_r, w_drum = 0.2, 2.0
    sim, k = drum_sim(w_drum, gs.contact.CDT(mu_r))
    sim.add_particles(position=[(0.0, 0.0, -(0.01 - R))], radius=R, material=MAT)
    angles = []
    while sim.time < 2.0 - 1e-9:
        sim.run(steps=100)
        with sim.particles(writable=False) as p:
            x = np.array(p.position[0])
        angles.append(math.atan2(-x[0], -x[2]))  # up the side the drum surface rises on
    angles = np.array(angles)
    expected = math.atan(mu_r)
    late = angles[len(angles) // 2 :].mean()
    assert angles.max() > 0.5 * expected, f"sphere not carried up: max angle {angles.max():.4f}"
    assert abs(late / expected - 1) <= 0.05, (
        f"mean angle over the last second {math.degrees(late):.3f} deg, "
        f"atan(mu_r) = {math.degrees(expected):.3f} deg"
    )
    # rebuilds only from the sphere's own motion (it rocks about the equilibrium angle)
    assert sim._level.rebuilds <= 400, f"{sim._level.rebuilds} rebuilds in 2e5 steps"


def test_drum_equilibrium_angle_is_stationary():
    """Started at theta = atan(mu_r) with the no-slip spin, the sphere stays there."""
    mu_r, w_drum, rc = 0.2, 2.0, 0.01
    sim, _ = drum_sim(w_drum, gs.contact.EPSD(mu_r, 0.3))
    theta = math.atan(mu_r)
    radial = np.array([-math.sin(theta), 0.0, -math.cos(theta)])
    surface = np.cross([0, w_drum, 0], rc * radial)
    # v - r w x n = surface with v = 0 and n = -radial (from the wall to the centre)
    spin = -float(surface @ np.cross([0, 1, 0], -radial)) / R
    sim.add_particles(
        position=[(rc - R) * radial], radius=R, material=MAT, angular_velocity=[(0, spin, 0)]
    )
    sim.run(steps=100000)
    with sim.particles(writable=False) as p:
        x = np.array(p.position[0])
    got = math.atan2(-x[0], -x[2])
    assert abs(got - theta) <= 1e-3 * theta, (
        f"sphere at {math.degrees(got):.5f} deg after 1 s, equilibrium atan(mu_r) = "
        f"{math.degrees(theta):.5f} deg"
    )
    assert sim._level.rebuilds <= 2, f"{sim._level.rebuilds} rebuilds of a resting sphere"
