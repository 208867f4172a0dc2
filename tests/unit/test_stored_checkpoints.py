"""Checkpoints written by an earlier grainscale keep restarting, bit for bit.

``tests/data/checkpoints`` holds, per case, a checkpoint (``*.h5``) and the state the run that
wrote it reached a fixed number of steps later (``*_after.npz``). Each test restarts from the
stored file, runs the same steps and requires every array to equal the stored one exactly: a
change that alters what a checkpoint means, or the arithmetic of a step, fails here. The files
were written by the code of commit b8c2bc7, before the top floors' redesign (issue 24); rewrite
them only for a deliberate change of the physics, with

    PYTHONPATH=python python tests/unit/test_stored_checkpoints.py --write

or, to keep the old checkpoint and renew only the state its run reaches,
``--write-after``. ``hierarchy_after.npz`` was renewed so (issue 28) when the flux insertion
began to place fine grains only where the coarse material reaches (no wall between them): the
stored run's fine level placed some grains where that rule now refuses them; and again when a
face began to give up for the interval once four grains in a row find no room (not 32). Both
``*_after.npz`` were renewed so (issue 27) when the contact laws began to multiply by
reciprocals instead of dividing (a few ulps in every contact force).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs

DATA = Path(__file__).resolve().parents[1] / "data" / "checkpoints"
GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
SIZE = gs.dist.Uniform(0.95e-3, 1.05e-3)
STEPS = 10000  # simulation: steps before and after the checkpoint
INTERVALS = 20  # hierarchy: exchange intervals after it


def bed() -> gs.Simulation:
    """A periodic box with a floor and a lid moving down under PI servo control (it has not
    reached the bed yet: its state is the integral and the position); Hertz-Mindlin with
    rolling resistance, so that the contacts carry tangential and rolling histories."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.016, 0.016, 0.03), periodic=(True, True, False))
    law = gs.contact.HertzMindlin(restitution=0.5, friction=0.5, rolling=gs.contact.EPSD(0.1, 0.3))
    sim = gs.Simulation(domain=box, time_step=1e-5, skin=2e-4, contact=law)
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    lid = gs.Rectangle(corner=(0, 0, 0.006), edge1=(0, 0.016, 0), edge2=(0.016, 0, 0))
    servo = gs.geometry.Servo(target_stress=150.0, gain=0.05, max_speed=0.05, integral_gain=0.1)
    sim.add_wall(lid, servo=servo)
    return sim


def filled_bed() -> gs.Simulation:
    sim = bed()
    r = np.random.default_rng(3).uniform(0.6e-3, 0.9e-3, 120)
    pos = gs.insert.random_in_box(gs.Box(lo=(0, 0, 0.001), hi=(0.016, 0.016, 0.0055)), r, seed=4)
    sim.add_particles(position=pos, radius=r, material=GLASS, velocity=(0.0, 0.0, -0.3))
    return sim


def hierarchy() -> gs.Hierarchy:
    """A stream poured into a 40 x 40 x 80 mm box, h = 2, with h = 1 in a box at its floor."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.04, 0.08))
    face = gs.insert.DiscFace(centre=(0.02, 0.02, 0.075), normal=(0, 0, -1), radius=0.012)
    stream = gs.insert.Stream(
        face, mass_rate=0.08, radius=SIZE, material=GLASS, velocity=(0, 0, -1.0), seed=7
    )
    base = gs.scaling.ParameterSet(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        walls=tuple(gs.geometry.box_walls(box, GLASS)),
        insertions=(stream,),
        size=SIZE,
    )
    region = gs.Box(lo=(0.008, 0.008, 0.0), hi=(0.032, 0.032, 0.03))
    return gs.Hierarchy(
        base=base,
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=region)],
        exchange=gs.Exchange(every=1e-3),
    )


def bed_state(sim: gs.Simulation) -> dict[str, np.ndarray]:
    fields = ("id", "position", "velocity", "angular_velocity", "force", "torque")
    with sim.particles(writable=False) as p:
        out = {k: getattr(p, k).copy() for k in fields}
    out["lid"] = np.concatenate([sim.walls[1].force, sim.walls[1].position])
    out["lid_servo_integral"] = np.array([sim.walls[1].servo_integral])
    out["time"] = np.array([sim.time, sim.step])
    return out


def hierarchy_state(h: gs.Hierarchy) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    for k in range(len(h.sims)):
        g = h.level(k).gather(("position", "velocity", "angular_velocity"))
        out.update({f"level{k}_{name}": np.asarray(v) for name, v in g.items()})
    b = h.mass_balance()
    out["books"] = np.array([b["initial"], b["inserted"], b["discharged"], b["unaccounted"]])
    out["time"] = np.array([h.time])
    return out


def assert_same(got: dict[str, np.ndarray], stored: Path) -> None:
    with np.load(stored) as expected:
        assert sorted(got) == sorted(expected.files)
        for key in expected.files:
            assert np.array_equal(got[key], expected[key]), f"{key} differs from {stored.name}"


def test_a_stored_simulation_checkpoint_restarts_bit_identically():
    sim = bed()
    sim.restart(DATA / "bed.h5")
    sim.run(steps=STEPS)
    assert sim.num_particles == 120
    assert_same(bed_state(sim), DATA / "bed_after.npz")


def test_a_stored_hierarchy_checkpoint_restarts_bit_identically():
    h = hierarchy()
    h.restart(DATA / "hierarchy.h5")
    h.run(intervals=INTERVALS)
    assert h.level(1).num_particles > 0
    assert_same(hierarchy_state(h), DATA / "hierarchy_after.npz")


def test_stored_files_predate_the_walls_record_and_still_restart():
    """The stored files were written before the set-up record held the walls' geometry (and a
    hierarchy's levels): they restart (above), compared by what they hold."""
    import h5py

    with h5py.File(DATA / "bed.h5", "r") as f:
        assert "walls" not in json.loads(f.attrs["python_state"]).get("setup", {})
    with h5py.File(DATA / "hierarchy.h5", "r") as f:
        assert "levels" not in json.loads(f.attrs["hierarchy_state"])


def test_a_checkpoint_of_the_other_kind_names_the_restart_to_use():
    with pytest.raises(
        ValueError,
        match=r"hierarchy.h5'\) is a hierarchy checkpoint \(written by Hierarchy.checkpoint, 2 "
        r"levels\), not a simulation checkpoint: continue it with Hierarchy.restart",
    ):
        bed().restart(DATA / "hierarchy.h5")
    h = hierarchy()
    with pytest.raises(
        ValueError,
        match=r"bed.h5'\) is a simulation checkpoint \(written by Simulation.checkpoint\), not a "
        r"hierarchy checkpoint: continue it with Simulation.restart",
    ):
        h.restart(DATA / "bed.h5")
    assert h.time == 0 and h.level(0).num_particles == 0


def write() -> None:
    """Writes the stored checkpoints and the states their runs reach (see the module's text)."""
    DATA.mkdir(parents=True, exist_ok=True)
    sim = filled_bed()
    sim.run(steps=STEPS)
    sim.checkpoint(DATA / "bed.h5")
    sim.run(steps=STEPS)
    np.savez(DATA / "bed_after.npz", **bed_state(sim))
    h = hierarchy()
    h.run(until=0.09)
    h.checkpoint(DATA / "hierarchy.h5")
    h.run(intervals=INTERVALS)
    np.savez(DATA / "hierarchy_after.npz", **hierarchy_state(h))


def write_after() -> None:
    """Renews only the states the stored checkpoints' runs reach (see the module's text)."""
    sim = bed()
    sim.restart(DATA / "bed.h5")
    sim.run(steps=STEPS)
    np.savez(DATA / "bed_after.npz", **bed_state(sim))
    h = hierarchy()
    h.restart(DATA / "hierarchy.h5")
    h.run(intervals=INTERVALS)
    np.savez(DATA / "hierarchy_after.npz", **hierarchy_state(h))


if __name__ == "__main__":
    if sys.argv[1:] == ["--write"]:
        write()
    elif sys.argv[1:] == ["--write-after"]:
        write_after()
    else:
        sys.exit(__doc__)
