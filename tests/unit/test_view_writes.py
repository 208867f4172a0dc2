"""Particle arrays from a ``with sim.particles()`` block cannot change the engine unseen after
the block (issue 25): the arrays handed out become read-only, and a write through a slice taken
inside the block is caught before the engine next touches the particles."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)


def two_spheres() -> gs.Simulation:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), gravity=(0, 0, 0))
    sim.add_particles(
        position=[[0.003, 0.005, 0.005], [0.007, 0.005, 0.005]], radius=1e-3, material=GLASS
    )
    return sim


def test_arrays_handed_out_are_read_only_after_the_block() -> None:
    sim = two_spheres()
    with sim.particles() as p:
        velocity = p.velocity
        velocity[0, 0] = 0.1  # inside: seen
    with pytest.raises(ValueError, match="read-only"):
        velocity[1, 0] = -0.1
    sim.run(steps=10, progress=False)
    with sim.particles(writable=False) as p:
        assert p.velocity[:, 0].tolist() == [0.1, 0.0]


@pytest.mark.parametrize("field", ["position", "velocity", "angular_velocity"])
def test_a_write_through_a_slice_after_the_block_is_caught(field: str) -> None:
    sim = two_spheres()
    with sim.particles() as p:
        rows = getattr(p, field)[:1]  # a view of engine memory
    rows[0, 2] = 1e-4
    with pytest.raises(RuntimeError, match=f"{field} were written after their 'with sim.particles"):
        sim.run(steps=1, progress=False)
    sim.run(steps=1, progress=False)  # the engine took the change; it runs on


def test_reading_after_a_read_only_block_costs_no_check() -> None:
    sim = two_spheres()
    with sim.particles(writable=False) as p:
        kept = np.array(p.position)  # a copy is the user's own
    kept[0, 0] = 1.0
    sim.run(steps=1, progress=False)
    assert sim.step == 1
