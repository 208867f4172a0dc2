"""Exact scaling (CASES.md E1) of the set-up operations: packing and stream insertion with every
size distribution, outlets, and moving walls (translating rectangle, spinning cylinder, rotating
mesh paddle). The engine draws, places, moves and deletes through ratios only, so a system
scaled by h = 2 with gs.scaling.scale must be the reference scaled bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs
from grainscale.contact import EPSD, HertzMindlin
from grainscale.geometry import Cylinder, Mesh, Plane, Rectangle
from grainscale.insert import Outlet, Pack, RectangleFace, Stream
from grainscale.scaling import ParameterSet, build_simulation, scale

SOFT = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="soft")
DISTRIBUTIONS = {
    "uniform": gs.dist.Uniform(1.0e-3, 1.6e-3),
    "normal": gs.dist.Normal(1.3e-3, 1.5e-4),
    "lognormal": gs.dist.LogNormal(1.3e-3, 0.15),
    "discrete": gs.dist.Discrete((1.0e-3, 1.5e-3), (1, 2), fractions="mass"),
}


def _paddle() -> Mesh:
    """A low blade stirring the bottom of the drum, rotating about the drum axis."""
    v = np.array([[0.0, -0.002, 0.0015], [0.015, -0.002, 0.0015], [0.015, -0.002, 0.006]])
    return Mesh(
        vertices=v,
        triangles=np.array([[0, 1, 2]]),
        angular_velocity=(0, 0, 6.0),
        origin=(0.0, 0.0, 0.0),
    )


def reference(dist: gs.dist.Distribution) -> ParameterSet:
    drum = Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=0.02, angular_velocity=(0, 0, 3.0))
    lid = Rectangle(
        corner=(-0.02, -0.02, 0.045), edge1=(0.04, 0, 0), edge2=(0, 0.04, 0), velocity=(0, 0, -0.05)
    )
    return ParameterSet(
        domain=gs.Box(lo=(-0.021, -0.021, 0.0), hi=(0.021, 0.021, 0.05)),
        contact=HertzMindlin(restitution=0.5, friction=0.5, rolling=EPSD(0.1, 0.3)),
        gravity=(0.0, 0.0, -9.81),
        time_step=5e-6,
        skin=2e-4,
        walls=[Plane(point=(0, 0, 0), normal=(0, 0, 1)), drum, lid, _paddle()],
        insertions=[
            Pack(
                gs.Box(lo=(-0.012, -0.012, 0.008), hi=(0.012, 0.012, 0.024)),
                radius=dist,
                material=SOFT,
                volume_fraction=0.25,
                velocity=(0, 0, -0.5),
                seed=4,
            ),
            Stream(
                RectangleFace(corner=(-0.01, -0.01, 0.04), edge1=(0.02, 0, 0), edge2=(0, 0.02, 0)),
                mass_rate=0.02,
                radius=dist,
                material=SOFT,
                velocity=(0, 0, -0.3),
                seed=9,
                every=2e-3,
            ),
        ],
        outlets=[Outlet(gs.Box(lo=(-0.003, -0.003, 0.0), hi=(0.003, 0.003, 0.003)), every=5)],
    )


def _particle_arrays(sim: gs.Simulation) -> dict[str, np.ndarray]:
    with sim.particles(writable=False) as p:
        order = np.argsort(p.id)
        names = ("id", "position", "velocity", "angular_velocity", "force")
        return {n: np.array(getattr(p, n)[order]) for n in names}


def _state(sim: gs.Simulation) -> dict[str, np.ndarray]:
    out = _particle_arrays(sim)
    out["paddle"] = sim.mesh_walls()[0]["vertices"]
    out["lid"] = sim.walls[2].position
    return out


@pytest.mark.parametrize("name", list(DISTRIBUTIONS))
def test_insertion_outlets_and_moving_walls_scale_bit_for_bit(name: str) -> None:
    h = 2.0
    ref = reference(DISTRIBUTIONS[name])
    a, b = build_simulation(ref), build_simulation(scale(ref, h, "exact").params)
    exponent = {
        "id": 0,
        "position": 1,
        "velocity": 0,
        "force": 2,
        "angular_velocity": -1,
        "paddle": 1,
        "lid": 1,
    }
    contacts = 0
    for _ in range(3):
        a.run(steps=2000, progress=False)
        b.run(steps=2000, progress=False)
        sa, sb = _state(a), _state(b)
        contacts = max(contacts, a.num_contacts())
        assert sa["id"].shape == sb["id"].shape, f"{name}: particle counts differ"
        for key, p in exponent.items():
            np.testing.assert_array_equal(sb[key], sa[key] * h**p, err_msg=f"{name}: {key}")
    assert contacts > 20
    assert a.streams[0].inserted_count > 0 and a.outlets[0].removed_count > 0
    assert a.streams[0].inserted_mass * h**3 == b.streams[0].inserted_mass


def test_periodic_box_scales_bit_for_bit() -> None:
    """Particles crossing periodic sides (wrapping and ghost images) under exact scaling."""
    h = 2.0
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.03), periodic=(True, True, False))
    ref = ParameterSet(
        domain=box,
        contact=HertzMindlin(restitution=0.5, friction=0.5),
        time_step=5e-6,
        skin=2e-4,
        walls=[Plane(point=(0, 0, 0), normal=(0, 0, 1))],
        insertions=[
            Pack(
                gs.Box(lo=(0, 0, 0.001), hi=(0.02, 0.02, 0.02)),
                radius=DISTRIBUTIONS["uniform"],
                material=SOFT,
                volume_fraction=0.3,
                velocity=(1.0, 0.5, -0.3),
                seed=1,
            )
        ],
    )
    a, b = build_simulation(ref), build_simulation(scale(ref, h, "exact").params)
    crossed = 0
    for _ in range(3):
        x0 = _particle_arrays(a)["position"][:, 0]
        a.run(steps=1000, progress=False)
        b.run(steps=1000, progress=False)
        sa, sb = _particle_arrays(a), _particle_arrays(b)
        crossed += int(np.sum(sa["position"][:, 0] < x0 - 0.01))  # wrapped across x = 0.02
        for key, p in (("position", 1), ("velocity", 0), ("force", 2)):
            np.testing.assert_array_equal(sb[key], sa[key] * h**p, err_msg=key)
    assert crossed > 10 and a.num_contacts() > 20
