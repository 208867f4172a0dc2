"""Guarded runs (issue 25): the step-displacement, overlap and non-finite guards stop a run with
a message naming the particle, the step and a remedy; the emergency checkpoint; the report of
lost particles; guards that do not trip change no bit of the result."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
BOX = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02))


def launched_at_wall(**kwargs) -> gs.Simulation:
    """Particle 1 flies at 2 m/s towards a wall with a step 50 x too large (it moves 2 mm, two
    radii, per step, and would pass through the wall)."""
    sim = gs.Simulation(
        domain=BOX, gravity=(0, 0, 0), time_step=1e-3, force_time_step=True, **kwargs
    )
    sim.add_wall(gs.Plane(point=(0.015, 0, 0), normal=(-1, 0, 0), material=GLASS))
    sim.add_particles(position=[[0.005, 0.005, 0.01]], radius=1e-3, material=GLASS)
    sim.add_particles(
        position=[[0.005, 0.015, 0.01]], radius=1e-3, material=GLASS, velocity=(2.0, 0, 0)
    )
    return sim


def overlapping_pair(**kwargs) -> gs.Simulation:
    """Two particles created overlapping by 0.8 of their radius (past the set-up check)."""
    sim = gs.Simulation(domain=BOX, gravity=(0, 0, 0), time_step=1e-6, **kwargs)
    sim.add_particles(
        position=[[0.01, 0.01, 0.01], [0.0112, 0.01, 0.01]],
        radius=1e-3,
        material=GLASS,
        check_placement=False,
    )
    return sim


def settle_box(**kwargs) -> gs.Simulation:
    """80 polydisperse spheres dropped into a closed box of walls."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.012, 0.012, 0.02))
    sim = gs.Simulation(
        domain=box,
        time_step=5e-6,
        skin=2e-4,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        **kwargs,
    )
    for wall in gs.geometry.box_walls(box, GLASS):
        sim.add_wall(wall)
    rng = np.random.default_rng(3)
    r = rng.uniform(0.6e-3, 1.0e-3, 80)
    sim.add_particles(position=gs.insert.random_in_box(box, r, seed=5), radius=r, material=GLASS)
    return sim


def test_guards_validate_their_parameters():
    with pytest.raises(ValueError, match=r"Guards.max_step_displacement must be a positive"):
        gs.Guards(max_step_displacement=0)
    with pytest.raises(ValueError, match=r"Guards.max_overlap must be a positive"):
        gs.Guards(max_overlap=float("inf"))
    with pytest.raises(ValueError, match=r"Guards.max_overlap must be a positive"):
        gs.Guards(max_overlap="big")
    with pytest.raises(ValueError, match=r"Guards.enabled must be True or False"):
        gs.Guards(enabled=1)
    with pytest.raises(ValueError, match=r"Guards.emergency_checkpoint must be a file path"):
        gs.Guards(emergency_checkpoint=3)
    with pytest.raises(ValueError, match=r"Simulation.guards must be a grainscale.Guards"):
        gs.Simulation(domain=BOX, guards=0.5)
    with pytest.raises(ValueError, match=r"Simulation.lost_particles must be one of"):
        gs.Simulation(domain=BOX, lost_particles="silent")
    assert gs.Simulation(domain=BOX).guards == gs.Guards()
    assert not gs.Simulation(domain=BOX, guards=False).guards.enabled


def test_displacement_guard_names_particle_step_and_remedy():
    sim = launched_at_wall()
    with pytest.raises(RuntimeError) as err:
        sim.run(steps=20, progress=False)
    text = str(err.value)
    assert "particle 1 moved 0.002 m in step 1" in text
    assert "2 x its radius" in text and "limit 0.5 x the radius" in text
    assert "reduce the time step (now 0.001 s, smallest Rayleigh time" in text
    assert sim.step == 1  # stopped after the step that tripped, the step finished
    # a looser limit lets the same step pass; without guards the particle tunnels out unseen
    loose = launched_at_wall(guards=gs.Guards(max_step_displacement=3.0))
    loose.run(steps=1, progress=False)
    unguarded = launched_at_wall(guards=False, lost_particles="ignore")
    unguarded.run(steps=20, progress=False)
    assert unguarded.num_particles == 1 and unguarded.lost_particles == 1


def test_overlap_guard_names_the_pair():
    sim = overlapping_pair()
    with pytest.raises(RuntimeError) as err:
        sim.run(steps=1, progress=False)
    text = str(err.value)
    assert re.search(
        r"particle 0 overlaps particle 1 by 0\.7\d* x the smaller radius at step 1", text
    )
    assert "limit 0.5, Guards.max_overlap" in text and "check for initial overlaps" in text
    overlapping_pair(guards=gs.Guards(max_overlap=0.9)).run(steps=1, progress=False)


def test_wall_overlap_guard_names_the_wall():
    sim = gs.Simulation(domain=BOX, gravity=(0, 0, 0), time_step=1e-6)
    sim.add_wall(gs.Plane(point=(0, 0, 0.001), normal=(0, 0, 1), material=GLASS))
    sim.add_particles(
        position=[[0.01, 0.01, 0.0013]], radius=1e-3, material=GLASS, check_placement=False
    )
    with pytest.raises(
        RuntimeError, match=r"particle 0 overlaps wall 0 by 0\.[67]\d* x its radius"
    ):
        sim.run(steps=1, progress=False)


def test_non_finite_velocity_trips_at_once():
    sim = overlapping_pair(guards=gs.Guards(max_overlap=1.0))
    sim.run(steps=2, progress=False)
    with sim.particles() as p:
        p.velocity[0, 0] = np.nan
    with pytest.raises(RuntimeError) as err:
        sim.run(steps=10, progress=False)
    text = str(err.value)
    assert "particle 0 has a non-finite position or velocity at step 3" in text
    assert "reduce the time step" in text
    assert sim.step == 3


def test_emergency_checkpoint_is_written_and_restartable(tmp_path):
    path = tmp_path / "crash.h5"
    sim = launched_at_wall(guards=gs.Guards(emergency_checkpoint=path))
    sim.run(steps=0, progress=False)
    with pytest.raises(RuntimeError, match=r"Emergency checkpoint of this step written to"):
        sim.run(steps=20, progress=False)
    assert path.exists()
    again = gs.Simulation(
        domain=BOX,
        gravity=(0, 0, 0),
        time_step=1e-3,
        force_time_step=True,
        guards=False,
        lost_particles="ignore",
    )
    again.add_wall(gs.Plane(point=(0.015, 0, 0), normal=(-1, 0, 0), material=GLASS))
    again.restart(path)
    assert again.step == sim.step == 1
    with again.particles() as p, sim.particles() as q:
        np.testing.assert_array_equal(p.position, q.position)
        np.testing.assert_array_equal(p.velocity, q.velocity)
    again.time_step = 1e-5  # the remedy
    again.run(steps=5, progress=False)
    assert again.step == 6


def test_emergency_checkpoint_failure_is_reported(tmp_path):
    guards = gs.Guards(max_overlap=1.0, emergency_checkpoint=tmp_path / "x.h5")
    sim = overlapping_pair(guards=guards)
    sim.run(steps=2, progress=False)
    with sim.particles() as p:
        p.velocity[1, 2] = np.inf
    with pytest.raises(RuntimeError, match=r"non-finite.*emergency checkpoint .* failed"):
        sim.run(steps=5, progress=False)


def falling_out(policy: str | None) -> gs.Simulation:
    """Three particles fall through the open floor (no wall) of a closed box."""
    kwargs = {} if policy is None else {"lost_particles": policy}
    sim = gs.Simulation(domain=BOX, time_step=1e-5, **kwargs)
    sim.add_particles(position=[[0.005, 0.01, 0.01]], radius=1e-3, material=GLASS)
    sim.add_particles(
        position=[[0.01, 0.01, 0.002], [0.015, 0.01, 0.002]], radius=1e-3, material=GLASS
    )
    return sim


def test_lost_particles_warn_by_default_with_count_and_ids():
    sim = falling_out(None)
    assert sim.lost_particles_policy == "warn"
    with pytest.warns(UserWarning) as caught:
        sim.run(until=0.03, progress=False)
    texts = [str(w.message) for w in caught if "closed side" in str(w.message)]
    assert texts, "no lost-particle warning"
    assert "2 particle(s) left the domain through a closed side" in texts[0]
    assert "global ids 1, 2;" in texts[0]
    assert sim.lost_particles == 2
    assert "lost" in sim.thermo_log[-1] and sim.thermo_log[-1]["lost"] == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.run(steps=100, progress=False)  # nothing more lost: no warning


def test_lost_particles_error_and_ignore():
    sim = falling_out("error")
    with pytest.raises(RuntimeError, match=r"2 particle\(s\) left .* \(global ids 1, 2;"):
        sim.run(until=0.03, progress=False)
    quiet = falling_out("ignore")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quiet.run(until=0.03, progress=False)
    assert quiet.lost_particles == 2


def test_guards_change_no_bit_of_a_settle_run():
    on, off = settle_box(), settle_box(guards=False)
    on.run(steps=3000, progress=False)
    off.run(steps=3000, progress=False)
    assert on.lost_particles == 0
    with on.particles() as p, off.particles() as q:
        for field in ("position", "velocity", "angular_velocity", "force", "torque"):
            np.testing.assert_array_equal(getattr(p, field), getattr(q, field), err_msg=field)
    assert on.thermo()["kinetic_energy"] == off.thermo()["kinetic_energy"]


def test_a_wall_faster_than_the_guard_stops_the_run_before_it_starts():
    """A rectangle moving 2.5 radii per step would jump over the particles; a drum spinning
    about its own axis only moves its surface and is let through."""
    sim = gs.Simulation(domain=BOX, gravity=(0, 0, 0), time_step=5e-6, force_time_step=True)
    sim.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    lid = sim.add_wall(
        gs.Rectangle(corner=(0, 0, 0.015), edge1=(0.02, 0, 0), edge2=(0, 0.02, 0), material=GLASS)
    )
    lid.set_motion(velocity=(0, 0, -500.0))  # 2.5 mm per step
    message = (
        "guard stopped the run before step 0: wall 0 moves up to 0.0025 m per step (speed and "
        "rotation x dt 5e-06 s), more than max_step_displacement 0.5 x the smallest radius "
        "0.001 m: particles could pass through it unseen"
    )
    with pytest.raises(RuntimeError, match=re.escape(message)):
        sim.run(steps=1)
    assert sim.step == 0
    lid.set_motion(velocity=(0, 0, -50.0))  # 0.25 mm per step: within the guard
    sim.run(steps=1)
    lid.set_motion(velocity=(0, 0, 0))
    lid.servo = gs.geometry.Servo(target_force=1e-6, gain=1e-3, max_speed=200.0)
    sim.run(steps=1)  # a servo's max_speed is only a cap: its current speed counts

    drum = gs.Simulation(domain=BOX, gravity=(0, 0, 0), time_step=5e-6, force_time_step=True)
    drum.add_particles(position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS)
    drum.add_wall(
        gs.geometry.Cylinder(
            point=(0.01, 0.01, 0), axis=(0, 0, 1), radius=0.009, angular_velocity=(0, 0, 1e4)
        )
    )
    drum.run(steps=2)  # 0.45 mm of surface per step, but the drum stays in place
    assert drum.step == 2


def test_remedy_gives_the_rayleigh_time_of_a_particle_already_gone():
    """A sphere at 1e6 m/s leaves the domain in the step that trips the guard: the Rayleigh time
    of the remedy is its own (0.2 x it is the default step), not that of no particle (inf)."""
    sim = gs.Simulation(domain=BOX, gravity=(0, 0, 0))
    sim.add_particles(
        position=[[0.01, 0.01, 0.01]], radius=1e-3, material=GLASS, velocity=(1e6, 0, 0)
    )
    with pytest.raises(RuntimeError) as err:
        sim.run(steps=10, progress=False)
    t_r = gs.timestep.rayleigh_time(GLASS, 1e-3)
    assert sim.num_particles == 0
    assert f"smallest Rayleigh time {t_r:.6g} s) or check" in str(err.value)
