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


def test_refused_writes_say_which_field_and_why() -> None:
    sim = two_spheres()
    with sim.particles() as p:
        kept = p.position
        with pytest.raises(ValueError) as err:
            p.radius[0] = 2e-3
        assert str(err.value).startswith(
            "ParticleView.radius is read-only: only position, velocity, angular_velocity can be "
            "written"
        )
        with pytest.raises(ValueError, match="^ParticleView.force is read-only"):
            p.force[:, 2] += 1.0
    with pytest.raises(ValueError) as err:
        kept[0, 0] = 0.004
    assert str(err.value) == (
        "ParticleView.position is read-only: its 'with sim.particles()' block has ended (arrays "
        "from a block are valid only inside it); write inside a new block"
    )
    with pytest.raises(ValueError, match="^ParticleView.position is read-only: its 'with"):
        kept[:, 1] *= 2  # a slice taken after the block, written in place
    with pytest.raises(ValueError, match="^ParticleView.position is read-only: its 'with"):
        kept.fill(0.0)
    with sim.particles(writable=False) as p:
        with pytest.raises(ValueError) as err:
            p.velocity[0, 0] = 1.0
    assert str(err.value) == (
        "ParticleView.velocity is read-only: the block was opened with "
        "sim.particles(writable=False); open it with writable=True to write"
    )
    sim.run(steps=1, progress=False)  # nothing was written
    with sim.particles(writable=False) as p:
        assert p.position[:, 0].tolist() == [0.003, 0.007]


def test_the_arrays_stay_zero_copy_views() -> None:
    sim = two_spheres()
    with sim.particles() as p:
        a, b = p.position, p.position[:, 0]
        a[1, 0] = 0.0075
        assert b[1] == 0.0075 and np.shares_memory(a, b)
        assert isinstance(a, np.ndarray) and repr(b) == "array([0.003 , 0.0075])"
        assert type(np.asarray(a)) is np.ndarray and np.shares_memory(np.asarray(a), a)
        a += 0.0  # in-place operators work inside a writable block
    with sim.particles(writable=False) as p:
        assert p.position[1, 0] == 0.0075


def test_assigning_a_field_copies_the_values_in() -> None:
    sim = two_spheres()
    with sim.particles() as p:
        p.velocity = [[0.1, 0, 0], [0, 0, 0]]
        p.angular_velocity = (0, 0, 1.0)  # one vector for every particle
        with pytest.raises(ValueError, match=r"^ParticleView.velocity must have shape \(3,\)"):
            p.velocity = np.zeros((3, 3))
        with pytest.raises(ValueError, match=r"^ParticleView.position must be finite, got nan"):
            p.position = [[np.nan, 0, 0], [0, 0, 0]]
        with pytest.raises(ValueError, match="^ParticleView.radius is read-only"):
            p.radius = [2e-3, 2e-3]
        with pytest.raises(AttributeError):
            p.positon = np.zeros((2, 3))  # a typo makes no new attribute
    with sim.particles(writable=False) as p:
        assert p.velocity.tolist() == [[0.1, 0, 0], [0, 0, 0]]
        assert p.angular_velocity[:, 2].tolist() == [1.0, 1.0]
        with pytest.raises(ValueError, match="^ParticleView.velocity is read-only: the block"):
            p.velocity = np.zeros((2, 3))
    with pytest.raises(RuntimeError, match="used outside its 'with sim.particles"):
        p.velocity = np.zeros((2, 3))
