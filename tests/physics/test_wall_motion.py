"""Walls (DESIGN.md 2.5) under control: a servo-controlled lid reaching and holding its target
stress; prescribed motion (a translating plane, a spinning mesh turntable, a drum carrying a
sphere up to its rolling-friction angle)."""

from __future__ import annotations

import math

import numpy as np
from wall_meshes import (
    MASS,
    MAT,
    G,
    R,
    disc_mesh,
    static_overlap,
)

import grainscale as gs

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
        load.append(float(lid.force @ [0, 0, 1]))
        z.append(float(lid.position[2]))
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
    got = k.position
    assert np.allclose(got, expected, rtol=1e-12, atol=1e-15), (
        f"wall position after t = {t} s: {got}, expected point + v t = {expected}"
    )
    assert np.allclose(k.velocity, [v_wall, 0, 0])
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
    rebuilds = sim.engine.diagnostics()["rebuilds"]
    assert rebuilds <= 2, (
        f"{rebuilds} list rebuilds for a drum spinning in place about its own axis"
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
    assert sim.engine.diagnostics()["rebuilds"] <= 400, (
        f"{sim.engine.diagnostics()['rebuilds']} rebuilds in 2e5 steps"
    )


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
    assert sim.engine.diagnostics()["rebuilds"] <= 2, (
        f"{sim.engine.diagnostics()['rebuilds']} rebuilds of a resting sphere"
    )
