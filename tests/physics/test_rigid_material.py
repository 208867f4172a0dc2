"""Rigid wall materials (Material(youngs_modulus=inf)): the contact mechanics of a wall without
a material, with the wall's own interaction values and pair entries."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import grainscale as gs

R = 1e-3
GRAIN = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="grain")
STEEL = gs.Material(density=7800.0, youngs_modulus=math.inf, poisson_ratio=0.3, name="steel")
SMOOTH = gs.Material(density=7800.0, youngs_modulus=math.inf, poisson_ratio=0.3, name="smooth")
FRICTION = 0.5
V0 = 0.1  # m/s, initial sliding speed


def test_rigid_material_wall_is_the_rigid_wall_bit_for_bit() -> None:
    """An oblique, spinning impact and the bounces after it: a wall with a rigid material and a
    wall without a material give identical particle and wall histories."""

    def run(material: gs.Material | None) -> np.ndarray:
        sim = gs.Simulation(
            domain=gs.Box(lo=(-0.02, -0.02, -0.001), hi=(0.02, 0.02, 0.02)),
            contact=gs.contact.HertzMindlin(
                restitution=0.5, friction=FRICTION, rolling=gs.contact.EPSD(0.1, 0.3)
            ),
            time_step=2e-7,
        )
        floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=material))
        sim.add_particles(
            position=[(0.0, 0.0, 1.2 * R)],
            radius=R,
            material=GRAIN,
            velocity=(0.3, 0.1, -0.5),
            angular_velocity=(20.0, -50.0, 5.0),
        )
        rows = []
        for _ in range(40):
            sim.run(steps=500, progress=False)
            with sim.particles(writable=False) as p:
                rows.append(
                    np.concatenate(
                        [p.position[0], p.velocity[0], p.angular_velocity[0], floor.force]
                    )
                )
        return np.array(rows)

    rigid, material = run(None), run(STEEL)
    assert np.any(rigid[:, 11] != 0)  # the sphere hit the floor
    assert np.array_equal(material, rigid)


def test_pair_entries_key_each_rigid_wall_material() -> None:
    """Two rigid floors side by side, a pair entry makes one frictionless: a sphere sliding on it
    keeps its speed, one sliding on the other (friction 0.5) ends rolling at 5/7 of it (a solid
    sphere, I = 2/5 m r^2: m v + I w / r is conserved about the contact point)."""
    law = gs.contact.HertzMindlin(
        restitution=0.5, friction=FRICTION, pairs={(GRAIN, SMOOTH): gs.contact.Pair(friction=0.0)}
    )
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.01, -0.03, -0.001), hi=(0.03, 0.03, 0.01)),
        contact=law,
        time_step=1e-6,
    )
    span = (0.0, 0.06, 0.0)
    sim.add_wall(
        gs.Rectangle(corner=(-0.01, -0.03, 0), edge1=(0.02, 0, 0), edge2=span, material=SMOOTH)
    )
    sim.add_wall(
        gs.Rectangle(corner=(0.01, -0.03, 0), edge1=(0.02, 0, 0), edge2=span, material=STEEL)
    )
    overlap = (
        GRAIN.density * 4 / 3 * math.pi * R**3 * 9.81 * 3 / (4 * 1e7 / (1 - 0.09) * math.sqrt(R))
    ) ** (2 / 3)  # Hertz overlap at rest
    sim.add_particles(
        position=[(0.0, -0.02, R - overlap), (0.02, -0.02, R - overlap)],
        radius=R,
        material=GRAIN,
        velocity=(0.0, V0, 0.0),
    )
    sim.run(steps=40_000, progress=False)  # 40 ms, > 2 V0 / (7 mu g) = 5.8 ms of sliding
    with sim.particles(writable=False) as p:
        order = np.argsort(p.position[:, 0])
        v = p.velocity[order, 1]
    assert v[0] == pytest.approx(V0, rel=1e-6), f"on the frictionless floor: {v[0]} m/s"
    assert v[1] / V0 == pytest.approx(5 / 7, abs=0.01), f"on the rough floor: {v[1] / V0}"


def test_rigid_materials_are_for_walls_only() -> None:
    assert STEEL.rigid and not GRAIN.rigid
    with pytest.raises(ValueError, match=r"Material\.youngs_modulus must be positive"):
        gs.Material(density=1.0, youngs_modulus=-math.inf, poisson_ratio=0.3)
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), time_step=1e-6)
    message = "Simulation.add_particles.material must be deformable (finite youngs_modulus), got"
    with pytest.raises(ValueError, match=re.escape(message)):
        sim.add_particles(position=[(0.005, 0.005, 0.005)], radius=R, material=STEEL)
    with pytest.raises(ValueError, match=r"Pack\.material must be deformable"):
        sim.insert(
            gs.insert.Pack(
                gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)),
                radius=R,
                material=STEEL,
                count=3,
                seed=1,
            )
        )
    with pytest.raises(ValueError, match=r"rayleigh_time\.material must be deformable"):
        gs.timestep.rayleigh_time(STEEL, R)
    assert sim.num_particles == 0


def test_rigid_material_wall_restarts(tmp_path) -> None:
    def build() -> gs.Simulation:
        sim = gs.Simulation(
            domain=gs.Box(lo=(-0.01, -0.01, -0.001), hi=(0.01, 0.01, 0.01)),
            contact=gs.contact.HertzMindlin(restitution=0.5, friction=FRICTION),
            time_step=1e-6,
        )
        sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=STEEL))
        return sim

    sim = build()
    sim.add_particles(position=[(0.0, 0.0, 2 * R)], radius=R, material=GRAIN)
    sim.run(steps=3000, progress=False)
    sim.checkpoint(tmp_path / "state.h5")
    sim.run(steps=3000, progress=False)
    again = build()
    again.restart(tmp_path / "state.h5")
    again.run(steps=3000, progress=False)
    with sim.particles(writable=False) as a, again.particles(writable=False) as b:
        assert np.array_equal(a.position, b.position) and np.array_equal(a.velocity, b.velocity)
