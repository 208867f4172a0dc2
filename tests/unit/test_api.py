"""Python API behaviour: validation messages, views, ids, walls, time-step guard, outputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")


def small_sim(**kwargs) -> gs.Simulation:
    kwargs.setdefault("domain", gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)))
    kwargs.setdefault("time_step", 1e-5)
    return gs.Simulation(**kwargs)


@pytest.mark.parametrize(
    ("factory", "message"),
    [
        (
            lambda: gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.7),
            "Material.poisson_ratio must be in [0, 0.5), got 0.7",
        ),
        (
            lambda: gs.Material(density=-1, youngs_modulus=1e7, poisson_ratio=0.3),
            "Material.density must be positive and finite",
        ),
        (
            lambda: gs.Material(density=1, youngs_modulus=float("nan"), poisson_ratio=0.3),
            "Material.youngs_modulus must be positive (Pa; inf for a rigid wall material), got nan",
        ),
        (
            lambda: gs.contact.HertzMindlin(restitution=1.5),
            "HertzMindlin.restitution must be in [0, 1], got 1.5",
        ),
        (
            lambda: gs.contact.HertzMindlin(friction=-0.1),
            "HertzMindlin.friction must be non-negative and finite, got -0.1",
        ),
        (
            lambda: gs.contact.HertzMindlin(tangential_history="spring"),
            "HertzMindlin.tangential_history must be 'total' or 'incremental'",
        ),
        (lambda: gs.Box(lo=(0, 0, 0), hi=(1, -1, 1)), "Box.hi must be greater than Box.lo"),
        (lambda: gs.Plane(point=(0, 0, 0), normal=(0, 0, 0)), "Plane.normal must be a non-zero"),
        (
            lambda: gs.Rectangle(corner=(0, 0, 0), edge1=(1, 0, 0), edge2=(2, 0, 0)),
            "Rectangle.edge2 must be non-zero, not parallel to edge1",
        ),
        (lambda: small_sim(time_step=0), "Simulation.time_step must be positive and finite"),
        (lambda: small_sim(skin=-1e-3), "Simulation.skin must be positive and finite"),
        (lambda: small_sim(gravity=(0, 0)), "Simulation.gravity must be a finite 3-vector"),
        (lambda: small_sim(thermo_every=0), "Simulation.thermo_every must be a positive integer"),
    ],
)
def test_invalid_parameters_name_parameter_constraint_and_value(factory, message):
    with pytest.raises(ValueError) as err:
        factory()
    assert message in str(err.value)


def test_add_particles_validation():
    sim = small_sim()
    with pytest.raises(ValueError, match="add_particles.position must be inside the domain"):
        sim.add_particles(position=[[0.01, 0.01, 0.03]], radius=1e-3, material=GLASS)
    with pytest.raises(ValueError, match="add_particles.radius must be positive"):
        sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=-1e-3, material=GLASS)
    with pytest.raises(ValueError, match="add_particles.radius must have shape"):
        sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=[1e-3, 2e-3], material=GLASS)
    with pytest.raises(ValueError, match="velocity must have shape"):
        sim.add_particles(
            position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS, velocity=[1, 2]
        )
    with pytest.raises(ValueError, match="material must be a grainscale.Material"):
        sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material="glass")
    assert sim.num_particles == 0  # nothing half-added


def test_run_argument_validation():
    sim = small_sim()
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    with pytest.raises(ValueError, match="exactly one of steps or until"):
        sim.run()
    with pytest.raises(ValueError, match="exactly one of steps or until"):
        sim.run(steps=1, until=1.0)
    with pytest.raises(ValueError, match="Simulation.run.steps must be a non-negative integer"):
        sim.run(steps=-3)


def test_time_step_above_rayleigh_limit_is_refused_unless_forced():
    t_r = gs.timestep.rayleigh_time(GLASS, 1e-3)
    # closed form: pi r sqrt(rho/G) / (0.1631 nu + 0.8766)
    g = GLASS.shear_modulus
    assert t_r == pytest.approx(math.pi * 1e-3 * math.sqrt(2500 / g) / (0.1631 * 0.3 + 0.8766))
    sim = small_sim(time_step=0.5 * t_r)
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    with pytest.raises(ValueError, match=r"Simulation.time_step must be at most 0.3 x"):
        sim.run(steps=1)
    forced = small_sim(time_step=0.5 * t_r, force_time_step=True)
    forced.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    forced.run(steps=1)
    assert forced.step == 1


def test_default_time_step_and_skin_follow_particles():
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)))
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    sim.run(steps=1)
    assert sim.time_step == pytest.approx(0.2 * gs.timestep.rayleigh_time(GLASS, 1e-3))
    assert sim.skin == pytest.approx(0.1 * 2e-3)


def test_views_are_zero_copy_and_die_with_the_block():
    sim = small_sim(gravity=(0, 0, 0))
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    with sim.particles() as p:
        p.velocity[0] = (0.1, 0.0, 0.0)
        assert not p.radius.flags.writeable
        pos = p.position
    with pytest.raises(RuntimeError, match="outside its 'with sim.particles\\(\\)' block"):
        _ = p.position
    sim.run(steps=100)
    with sim.particles() as p:
        assert p.position[0, 0] == pytest.approx(0.01 + 0.1 * 100 * 1e-5, rel=1e-12)
        # the same memory: the array taken earlier sees the new value
        assert pos[0, 0] == p.position[0, 0]
    # growing the store must not invalidate memory held by an old view (no crash, stale data)
    sim.add_particles(
        position=gs.insert.lattice(gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.005)), 2.5e-3),
        radius=1e-3,
        material=GLASS,
    )
    assert np.isfinite(pos).all()


def test_read_only_view_rejects_writes():
    sim = small_sim()
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    with sim.particles(writable=False) as p, pytest.raises(ValueError):
        p.position[0, 0] = 0.0


def test_ids_are_never_reused_and_lost_particles_are_counted():
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02))
    sim = gs.Simulation(domain=box, time_step=1e-5, gravity=(0, 0, -9.81))
    ids = sim.add_particles(position=[[0.01, 0.01, 0.0015]], radius=1e-3, material=GLASS)
    assert list(ids) == [0]
    with pytest.warns(UserWarning, match=r"1 particle\(s\) left the domain .*global ids 0;"):
        sim.run(until=0.05)  # no floor: the particle falls out of the box
    assert sim.num_particles == 0
    assert sim.lost_particles == 1
    again = sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    assert list(again) == [1]


def test_run_until_reaches_time_and_periodic_axes_wrap():
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02), periodic=(True, False, False))
    sim = gs.Simulation(domain=box, time_step=1e-5, gravity=(0, 0, 0))
    sim.add_particles(
        position=[[0.019, 0.01, 0.01]], radius=1e-3, material=GLASS, velocity=(0.5, 0, 0)
    )
    sim.run(until=0.01)
    assert sim.step == 1000
    assert sim.time == pytest.approx(0.01, rel=1e-12)
    with sim.particles() as p:
        # 0.019 + 0.005 = 0.024 -> wrapped to 0.004 (wrapping happens at list rebuilds, so the
        # particle may still sit up to skin/2 beyond the face)
        x = p.position[0, 0]
    assert (x - 0.004) % 0.02 == pytest.approx(0.0, abs=1e-12) or abs(x - 0.024) < 1e-12
    assert sim.lost_particles == 0


def test_sphere_resting_on_plane_loads_the_wall_with_its_weight():
    sim = small_sim(
        contact=gs.contact.HertzMindlin(restitution=0.3, friction=0.5), record_contacts=True
    )
    floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    sim.add_particles(position=[[0.01, 0.01, 0.0012]], radius=1e-3, material=GLASS)
    sim.run(until=0.3)
    with sim.particles() as p:
        weight = p.mass[0] * 9.81
        assert abs(p.velocity[0, 2]) < 1e-6
    np.testing.assert_allclose(floor.force, [0, 0, -weight], rtol=1e-6, atol=1e-12)
    # torque about the wall's reference point (origin): r x F with r = contact point
    np.testing.assert_allclose(
        floor.torque, np.cross([0.01, 0.01, 0.0], [0, 0, -weight]), rtol=1e-6
    )
    assert sim.num_contacts() == 1
    c = sim.contacts()
    assert c["id_j"][0] == -1 - floor.index
    np.testing.assert_allclose(c["normal"][0], [0, 0, 1])


def test_moving_wall_pushes_particles():
    sim = small_sim(gravity=(0, 0, 0))
    piston = sim.add_wall(gs.Plane(point=(0, 0, 0.001), normal=(0, 0, 1), velocity=(0, 0, 0.2)))
    sim.add_particles(position=[[0.01, 0.01, 0.005]], radius=1e-3, material=GLASS)
    sim.run(until=0.05)
    assert piston.position[2] == pytest.approx(0.001 + 0.2 * 0.05)
    with sim.particles() as p:
        # hit by a wall moving at 0.2 m/s, the particle leaves faster than the wall
        assert p.velocity[0, 2] > 0.2


def test_rectangle_edge_contact_uses_the_closest_point():
    sim = small_sim(gravity=(0, 0, 0), contact=gs.contact.HertzMindlin(restitution=1.0))
    # rectangle in z = 0.01 spanning x in [0.005, 0.01]; the sphere comes at its edge x = 0.01
    sim.add_wall(gs.Rectangle(corner=(0.005, 0.0, 0.01), edge1=(0.005, 0, 0), edge2=(0, 0.02, 0)))
    sim.add_particles(
        position=[[0.0115, 0.01, 0.0115]],
        radius=1e-3,
        material=GLASS,
        velocity=(-0.1, 0.0, -0.1),
    )
    sim.run(until=0.03)
    with sim.particles() as p:
        v = p.velocity[0].copy()
    # elastic, frictionless bounce off an edge along the line to the edge: velocity reversed
    np.testing.assert_allclose(v, [0.1, 0.0, 0.1], rtol=1e-3, atol=1e-6)


def settled_bed() -> gs.Simulation:
    """A polydisperse bed settled with friction on a floor (deterministic)."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.016, 0.016, 0.03), periodic=(True, True, False))
    sim = gs.Simulation(
        domain=box,
        time_step=1e-5,
        skin=2e-4,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
    )
    rng = np.random.default_rng(7)
    r = rng.uniform(0.5e-3, 1.0e-3, 250)
    pos = gs.insert.random_in_box(gs.Box(lo=(0, 0, 0), hi=(0.016, 0.016, 0.03)), r, seed=3)
    sim.add_particles(position=pos, radius=r, material=GLASS)
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    sim.run(steps=15000)
    assert sim.num_contacts() > 300  # a bed with lasting contacts, so histories matter
    return sim


def state_by_id(sim: gs.Simulation) -> tuple[np.ndarray, np.ndarray]:
    with sim.particles(writable=False) as p:
        o = np.argsort(p.id)
        return p.position[o].copy(), p.angular_velocity[o].copy()


def test_results_do_not_depend_on_the_skin_contact_history_survives_rebuilds():
    a, b, lost = settled_bed(), settled_bed(), settled_bed()
    xa, _ = state_by_id(a)
    xb, _ = state_by_id(b)
    assert np.array_equal(xa, xb)  # deterministic
    b.skin = 1e-9  # from now on b rebuilds, re-sorts and carries histories every step
    lost.contact._apply_law(lost.engine.core)  # control: every contact history dropped once
    rebuilds = (a.engine.diagnostics()["rebuilds"], b.engine.diagnostics()["rebuilds"])
    for sim in (a, b, lost):
        sim.run(steps=2000)
    assert b.engine.diagnostics()["rebuilds"] - rebuilds[1] >= 2000
    assert a.engine.diagnostics()["rebuilds"] - rebuilds[0] < 20
    xa, wa = state_by_id(a)
    xb, wb = state_by_id(b)
    xl, wl = state_by_id(lost)
    # Only summation order differs between a and b: agreement to round-off.
    np.testing.assert_allclose(xb, xa, rtol=0, atol=1e-13)
    np.testing.assert_allclose(wb, wa, rtol=0, atol=1e-8 * np.abs(wa).max())
    # The control shows the check is sensitive: losing the springs once moves things a lot.
    assert np.abs(xl - xa).max() > 1e-7
    assert np.abs(wl - wa).max() > 1e-3 * np.abs(wa).max()


def test_unstable_run_raises_instead_of_crashing():
    sim = small_sim(gravity=(0, 0, 0), time_step=1e-5)
    sim.add_particles(  # nearly coincident on purpose: past the set-up check
        position=[[0.01, 0.01, 0.01], [0.0101, 0.01, 0.01]],
        radius=1e-3,
        material=GLASS,
        check_placement=False,
    )
    with sim.particles() as p:
        p.velocity[0] = (float("nan"), 0.0, 0.0)
    with pytest.raises(RuntimeError, match="non-finite position or velocity"):
        sim.run(steps=10)


def test_coincident_particles_do_not_produce_nan():
    sim = small_sim(gravity=(0, 0, 0), guards=False)  # the overlap guard would stop the run
    sim.add_particles(  # coincident on purpose: past the set-up check
        position=[[0.01, 0.01, 0.01]] * 2, radius=1e-3, material=GLASS, check_placement=False
    )
    sim.run(steps=1)
    with sim.particles() as p:
        assert np.isfinite(p.force).all()
        assert p.force[0, 2] != 0.0


def test_contacts_need_recording_switched_on():
    sim = small_sim()
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    sim.run(steps=1)
    with pytest.raises(RuntimeError, match="record_contacts=True"):
        sim.contacts()
    sim.record_contacts = True
    sim.run(steps=1)
    assert len(sim.contacts()["overlap"]) == 0


def test_unsupported_law_combination_lists_the_supported_ones():
    sim = small_sim()
    with pytest.raises(ValueError) as err:
        sim.engine.core.set_contact_law("jkr", "epsd", False, True, False)
    message = str(err.value)
    assert "contact law (normal+rolling) must be one of:" in message
    assert "got jkr+epsd" in message
    for name in gs.contact.supported_laws():
        assert name in message
