"""Checkpoint/restart: N steps + checkpoint + restart + N steps equals 2N steps, exactly."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
STEEL = gs.Material(density=7800.0, youngs_modulus=2e8, poisson_ratio=0.3, name="steel")
FIELDS = ("position", "velocity", "angular_velocity", "force", "torque", "radius", "id")


def plate() -> gs.geometry.Mesh:
    """A triangulated floor plate, 4 x 4 squares."""
    n, half = 4, 0.012
    xs = np.linspace(-half, half, n + 1) + 0.01
    gx, gy = np.meshgrid(xs, xs, indexing="ij")
    vertices = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)
    tris = []
    for i in range(n):
        for j in range(n):
            a = i * (n + 1) + j
            tris += [[a, a + n + 1, a + 1], [a + 1, a + n + 1, a + n + 2]]
    return gs.geometry.Mesh(vertices, np.array(tris), material=STEEL)


def build(law: object) -> gs.Simulation:
    box = gs.Box(lo=(0, 0, -0.002), hi=(0.02, 0.02, 0.04), periodic=(True, False, False))
    sim = gs.Simulation(domain=box, time_step=1e-5, skin=2e-4, contact=law)
    sim.add_wall(plate())
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 1, 0)))
    sim.add_wall(gs.Plane(point=(0, 0.02, 0), normal=(0, -1, 0), material=GLASS))
    lid = gs.Rectangle(corner=(0, 0, 0.03), edge1=(0.02, 0, 0), edge2=(0, 0.02, 0))
    servo = gs.geometry.Servo(target_stress=200.0, gain=0.05, max_speed=0.05, integral_gain=0.1)
    sim.add_wall(lid, servo=servo)
    return sim


def populated(law: object) -> gs.Simulation:
    sim = build(law)
    rng = np.random.default_rng(1)
    r = rng.uniform(0.6e-3, 1.0e-3, 150)
    region = gs.Box(lo=(0, 0, 0.0), hi=(0.02, 0.02, 0.029))
    pos = gs.insert.random_in_box(region, r, seed=2)
    sim.add_particles(position=pos, radius=r, material=GLASS, velocity=(0.0, 0.0, -0.5))
    return sim


def snapshot(sim: gs.Simulation) -> dict[str, np.ndarray]:
    with sim.particles(writable=False) as p:
        out = {k: getattr(p, k).copy() for k in FIELDS}
    for k in range(4):
        out[f"wall{k}"] = np.concatenate(
            [sim.walls[k].force, sim.walls[k].torque, sim.walls[k].position]
        )
    out["servo_integral"] = np.array([sim.walls[3].servo_integral])  # the lid's PI state
    out["time"] = np.array([sim.time, sim.step])
    return out


LAWS = [
    gs.contact.HertzMindlin(restitution=0.5, friction=0.5, rolling=gs.contact.EPSD(0.1, 0.3)),
    gs.contact.Linear(normal_stiffness=500.0, restitution=0.6, tangential_history="incremental"),
    gs.contact.EEPA(adhesive_stiffness=50.0, pull_off_force=-2e-5, rolling=gs.contact.CDT(0.05)),
]


@pytest.mark.parametrize("law", LAWS, ids=["hertz+epsd", "linear", "eepa+cdt"])
def test_restart_is_bit_identical(tmp_path, law):
    steps = 4000
    straight = populated(law)
    straight.run(steps=steps)
    straight.run(steps=steps)
    expected = snapshot(straight)

    first = populated(law)
    first.run(steps=steps)
    path = tmp_path / "state.h5"
    first.checkpoint(path)

    again = build(law)
    again.restart(path)
    again.run(steps=steps)
    got = snapshot(again)
    assert straight.num_contacts() > 30  # a bed with contact histories
    for key, value in expected.items():
        assert np.array_equal(got[key], value), f"{key} differs after restart"


def test_mismatched_setup_is_refused(tmp_path):
    sim = populated(LAWS[0])
    sim.run(steps=10)
    path = tmp_path / "state.h5"
    sim.checkpoint(path)
    other = build(LAWS[1])
    with pytest.raises(ValueError, match="checkpoint was written for the set-up 'law=hertz\\+epsd"):
        other.restart(path)
    fewer_walls = gs.Simulation(
        domain=gs.Box(lo=(0, 0, -0.002), hi=(0.02, 0.02, 0.04), periodic=(True, False, False)),
        time_step=1e-5,
        contact=LAWS[0],
    )
    with pytest.raises(ValueError, match="walls=4"):
        fewer_walls.restart(path)


def test_corrupt_files_give_clear_errors(tmp_path):
    bad = tmp_path / "not_hdf5.h5"
    bad.write_bytes(b"this is not an HDF5 file")
    with pytest.raises(ValueError, match="must be a readable HDF5 file"):
        build(LAWS[0]).restart(bad)

    import h5py

    sim = populated(LAWS[0])
    sim.run(steps=10)
    path = tmp_path / "state.h5"
    sim.checkpoint(path)
    with h5py.File(path, "a") as f:
        del f["rank_0/reals/particles/mass"]
    with pytest.raises(
        ValueError, match=r"state.h5.*datasets missing or added: reals/particles/mass"
    ):
        build(LAWS[0]).restart(path)

    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f.attrs["format"] = "something else"
    with pytest.raises(ValueError, match="not a grainscale checkpoint"):
        build(LAWS[0]).restart(other)


def test_restart_with_default_skin_and_time_step(tmp_path):
    def bare() -> gs.Simulation:
        sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.04)))
        sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
        return sim

    a = bare()
    a.add_particles(position=[[0.01, 0.01, 0.0105]], radius=1e-3, material=GLASS)
    a.run(steps=300)
    path = tmp_path / "state.h5"
    a.checkpoint(path)
    b = bare()
    b.restart(path)
    assert b.time_step == a.time_step and b.skin == a.skin
    a.run(steps=300)
    b.run(steps=300)
    assert np.array_equal(snapshot_particles(a), snapshot_particles(b))


def snapshot_particles(sim: gs.Simulation) -> np.ndarray:
    with sim.particles(writable=False) as p:
        return np.concatenate([p.position.ravel(), p.velocity.ravel(), p.force.ravel()])


def test_restart_checks_domain_law_parameters_and_says_what_wins(tmp_path):
    """A restart into another domain, or with other parameters of the same law, is refused
    before anything changes; a time step set on the simulation is replaced by the
    checkpoint's, with a warning saying so."""
    sim = populated(LAWS[0])
    sim.run(steps=10)
    path = tmp_path / "state.h5"
    sim.checkpoint(path)

    wider = gs.Simulation(
        domain=gs.Box(lo=(0, 0, -0.002), hi=(0.03, 0.02, 0.04), periodic=(True, False, False)),
        time_step=1e-5,
        contact=LAWS[0],
    )
    for wall in build(LAWS[0]).walls:
        wider.add_wall(wall.geometry, servo=wall.servo)
    with pytest.raises(ValueError, match=r"state.h5.*domain \[lo, hi, periodic\]"):
        wider.restart(path)
    assert wider.num_particles == 0

    stickier = gs.contact.HertzMindlin(
        restitution=0.5, friction=0.8, rolling=gs.contact.EPSD(0.1, 0.3)
    )
    with pytest.raises(ValueError, match=r"contact law .*friction=0\.5.*friction=0\.8"):
        build(stickier).restart(path)

    other_step = build(LAWS[0])
    other_step.time_step = 5e-6
    with pytest.warns(UserWarning, match=r"time step 1e-05 s replaces the time step 5e-06 s"):
        other_step.restart(path)
    assert other_step.time_step == 1e-5


def bare() -> gs.Simulation:
    """A box with a floor; no time step, no skin given."""
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.04)))
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
    return sim


def dropped(sim: gs.Simulation) -> gs.Simulation:
    sim.add_particles(position=[[0.01, 0.01, 0.0105], [0.0125, 0.01, 0.004]], radius=1e-3,
                      material=GLASS)  # fmt: skip
    return sim


def test_a_checkpoint_before_the_first_run_chooses_the_defaults_and_restarts_exactly(tmp_path):
    """Before the first run a checkpoint chooses the time step and skin not given, as run()
    would: the run continues as without the checkpoint, and the restart as the run."""
    a = dropped(bare())
    path = tmp_path / "new.h5"
    a.checkpoint(path)
    assert a.time_step is not None and a.time_step > 0
    b = bare()
    b.restart(path)
    assert b.time_step == a.time_step and b.skin == a.skin
    never = dropped(bare())
    for sim in (a, b, never):
        sim.run(steps=300)
    assert np.array_equal(snapshot_particles(a), snapshot_particles(b))
    assert np.array_equal(snapshot_particles(a), snapshot_particles(never))
    with pytest.raises(ValueError, match="Simulation.time_step must be given when there are no"):
        bare().checkpoint(tmp_path / "empty.h5")


def test_an_unwritable_checkpoint_path_is_named(tmp_path):
    sim = dropped(bare())
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    target = blocker / "out" / "c.h5"
    with pytest.raises(
        ValueError,
        match=r"Simulation.checkpoint.path must be a file path that can be written, got "
        rf"'{target}' \(NotADirectoryError: ",
    ) as info:
        sim.checkpoint(target)
    assert isinstance(info.value.__cause__, OSError)
    with pytest.raises(ValueError, match=rf"got '{tmp_path}' \((IsADirectoryError|OSError)"):
        sim.checkpoint(tmp_path)  # written, then it cannot replace a directory
    assert not Path(f"{tmp_path}.tmp").exists()  # the temporary file is removed


def test_a_restart_into_a_populated_simulation_warns_of_the_particles_it_replaces(tmp_path):
    sim = populated(LAWS[0])
    sim.run(steps=10)
    path = tmp_path / "state.h5"
    sim.checkpoint(path)
    other = build(LAWS[0])
    other.add_particles(position=[[0.01, 0.01, 0.02]], radius=1e-3, material=GLASS)
    with pytest.warns(
        UserWarning,
        match=r"Simulation.restart replaced the 1 particle\(s\) this simulation held with the "
        r"150 of the checkpoint '.*state.h5'",
    ):
        other.restart(path)
    assert other.num_particles == 150


def test_restart_compares_the_walls_geometry_as_constructed(tmp_path):
    """A wall set up elsewhere (or of another kind, or another mesh) is refused, naming the
    wall and both set-ups; a moving wall's position is state (the servo lid has moved since it
    was constructed: test_restart_is_bit_identical restores it)."""
    sim = populated(LAWS[0])
    sim.run(steps=10)
    path = tmp_path / "state.h5"
    sim.checkpoint(path)
    assert sim.walls[3].position[2] != 0.03  # the lid moved
    box = gs.Box(lo=(0, 0, -0.002), hi=(0.02, 0.02, 0.04), periodic=(True, False, False))

    def variant(k: int, wall: object) -> gs.Simulation:
        other = gs.Simulation(domain=box, time_step=1e-5, skin=2e-4, contact=LAWS[0])
        for j, w in enumerate(build(LAWS[0]).walls):
            other.add_wall(wall if j == k else w.geometry, servo=w.servo)
        return other

    side = build(LAWS[0]).walls[1].geometry
    moved = variant(1, dataclasses.replace(side, point=(0.0, 0.001, 0.0)))
    with pytest.raises(
        ValueError,
        match=r"state.h5.*checkpoint wall 1 was set up as Plane\(point=\(0.0, 0.0, 0.0\), "
        r"normal=\(0.0, 1.0, 0.0\), material=rigid\), this simulation's wall 1 is "
        r"Plane\(point=\(0.0, 0.001, 0.0\), normal=\(0.0, 1.0, 0.0\), material=rigid\)",
    ):
        moved.restart(path)
    assert moved.num_particles == 0 and moved.step == 0
    lower = gs.geometry.Mesh(plate().vertices - (0, 0, 1e-4), plate().triangles, STEEL)
    with pytest.raises(ValueError, match=r"checkpoint wall 0 was set up as Mesh\(vertices=<"):
        variant(0, lower).restart(path)
    rectangle = gs.Rectangle(corner=(0, 0, 0), edge1=(0.02, 0, 0), edge2=(0, 0, 0.04))
    with pytest.raises(ValueError, match=r"wall 1 is Rectangle\(corner="):
        variant(1, rectangle).restart(path)
    same = variant(1, gs.Plane(point=[0, 0, 0], normal=[0, 2, 0]))  # the same, given otherwise
    same.restart(path)
    assert same.num_particles == 150
