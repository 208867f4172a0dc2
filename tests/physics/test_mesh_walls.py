"""Walls (DESIGN.md 2.5): triangle meshes against the analytic plane, and cylinders.

* A flat triangulated floor (regular grid, irregular Delaunay triangulation with a hub vertex
  shared by 7 triangles) must give the same force and torque history as gs.Plane, step by step,
  for spheres sliding and rolling across edges and over vertices (friction on, tangential and
  rolling history handed over between triangles) and for normal impacts on a face, an edge and a
  vertex: the surface is touched once, never twice.
* Edge of a convex ridge and vertex of a lone triangle: the Hertz law with the distance to the
  closest point (CASES.md A1 with R* = r, m* = m, E* = E/(1 - nu^2) for a rigid wall).
* Static equilibria with closed forms (mesh floor, closed mesh box corner, inside a vertical
  cylinder, on the crest of a horizontal outside cylinder).

Servo control and prescribed motion are in test_wall_motion.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from wall_meshes import (
    E_STAR,
    FLOOR_HALF,
    HISTORY_TOL,
    K_HERTZ,
    MASS,
    MAT,
    G,
    H,
    R,
    box_mesh,
    by_id,
    contacts_per_particle,
    grid_floor,
    irregular_floor,
    nearest_vertex,
    static_overlap,
    valence,
)

import grainscale as gs

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
    dfw = np.linalg.norm(plane.walls[0].force - tri.walls[0].force) / (len(ids) * f_scale)
    dtw = np.linalg.norm(plane.walls[0].torque - tri.walls[0].torque) / (len(ids) * f_scale * 0.03)
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
    total = sum(w.force for w in sim.walls[:n_walls])
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
    # With friction the rest state depends on the path (the springs stick where they are), so
    # the faces' rounding differences survive: 0.8e-9 and 1.4e-9 of the overlap with two
    # orderings of the same arithmetic; without friction the three overlaps are equal bit for bit.
    assert np.ptp(c["overlap"]) <= 1e-8 * c["overlap"].max(), (
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
    assert (
        sorted(int(j) for j in c["id_j"]) == [-1 - floor.index, -1 - cyl.index] and most.get(0) == 2
    ), (
        f"inside cylinder: contacts with {c['id_j']} (expected floor and cylinder once each), up "
        f"to {most.get(0)} while settling"
    )
    f_cyl, f_floor = cyl.force, floor.force
    w = MASS * G
    normals = {int(j): n for j, n in zip(c["id_j"], c["normal"], strict=True)}
    assert np.allclose(normals[-1 - cyl.index], [-1, 0, 0], atol=1e-12) and np.allclose(
        normals[-1 - floor.index], [0, 0, 1], atol=1e-12
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
    assert np.allclose(cyl.force, [0, 0, -MASS * G], rtol=1e-6, atol=1e-12)
