"""Property-based fuzzing of the public API (issue 25, hypothesis).

Every public constructor and method is called with arbitrary values — numbers of every sign and
size, NaN and infinities, bools, strings, None, complex numbers, nested lists and arrays of odd
shapes — and must either work or raise a clear ValueError, TypeError or RuntimeError; the
interpreter never dies. The default profile adds about a minute to ``make test``; set
``GRAINSCALE_FUZZ=long`` for a longer search.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import grainscale as gs

LONG = os.environ.get("GRAINSCALE_FUZZ") == "long"
settings.register_profile(
    "grainscale",
    max_examples=5000 if LONG else 1500,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    derandomize=not LONG,  # the default run is reproducible
)
settings.load_profile("grainscale")

CLEAR = (ValueError, TypeError, RuntimeError)
GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
BOX = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01))

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.sampled_from([0, 1, -1, 1e-3, 0.3, 0.5, 1.0, 2500.0, 1e7]),
)
junk = st.one_of(
    st.none(),
    st.booleans(),
    st.text(max_size=5),
    st.complex_numbers(max_magnitude=1e3),
    st.just(object()),
)
scalars = st.one_of(numbers, numbers, junk)


def arrays(*shape: int) -> st.SearchStrategy[Any]:
    """Arrays near the wanted shape: right, wrong, ragged, of numbers or junk."""
    sizes = st.sampled_from(sorted({0, 1, 2, 3, 4, *shape}))
    flat = st.lists(st.one_of(numbers, junk), min_size=0, max_size=12)
    return st.one_of(
        st.lists(st.lists(numbers, min_size=0, max_size=4), min_size=0, max_size=4),
        st.tuples(sizes, sizes).flatmap(
            lambda nm: st.lists(
                st.floats(-0.05, 0.05), min_size=nm[0] * nm[1], max_size=nm[0] * nm[1]
            ).map(lambda v, nm=nm: np.array(v).reshape(nm))
        ),
        flat,
        scalars,
    )


vectors = st.one_of(st.tuples(numbers, numbers, numbers), arrays(3), scalars)


def works_or_clear(call: Any, *args: Any, **kwargs: Any) -> Any:
    try:
        return call(*args, **kwargs)
    except CLEAR:
        return None


@given(density=scalars, youngs_modulus=scalars, poisson_ratio=scalars, name=scalars)
def test_material(density, youngs_modulus, poisson_ratio, name) -> None:
    works_or_clear(
        gs.Material,
        density=density,
        youngs_modulus=youngs_modulus,
        poisson_ratio=poisson_ratio,
        name=name,
    )


@given(lo=vectors, hi=vectors, periodic=st.one_of(st.tuples(*[st.booleans()] * 3), scalars))
def test_box(lo, hi, periodic) -> None:
    works_or_clear(gs.Box, lo=lo, hi=hi, periodic=periodic)


@given(
    point=vectors,
    normal=vectors,
    axis=vectors,
    radius=scalars,
    length=scalars,
    edge=vectors,
)
def test_walls(point, normal, axis, radius, length, edge) -> None:
    works_or_clear(gs.Plane, point=point, normal=normal)
    works_or_clear(gs.Rectangle, corner=point, edge1=edge, edge2=normal)
    works_or_clear(gs.geometry.Cylinder, point=point, axis=axis, radius=radius, length=length)
    works_or_clear(gs.geometry.Mesh, vertices=arrays_example(point), triangles=[[0, 1, 2]])


def arrays_example(value: Any) -> Any:
    return [value, value, value]


@given(
    restitution=scalars,
    friction=scalars,
    stiffness=scalars,
    rolling=st.one_of(st.none(), st.tuples(scalars, scalars)),
    pull_off=scalars,
)
def test_contact_laws(restitution, friction, stiffness, rolling, pull_off) -> None:
    roll = None if rolling is None else works_or_clear(gs.contact.EPSD, *rolling)
    works_or_clear(
        gs.contact.HertzMindlin, restitution=restitution, friction=friction, rolling=roll
    )
    works_or_clear(
        gs.contact.Linear, normal_stiffness=stiffness, restitution=restitution, friction=friction
    )
    works_or_clear(gs.contact.EEPA, adhesive_stiffness=stiffness, pull_off_force=pull_off)


@given(lo=scalars, hi=scalars, mean=scalars, std=scalars)
def test_size_distributions(lo, hi, mean, std) -> None:
    works_or_clear(gs.dist.Uniform, lo, hi)
    works_or_clear(gs.dist.Normal, mean, std)
    works_or_clear(gs.dist.Monodisperse, lo)
    works_or_clear(gs.dist.LogNormal, lo, std)
    works_or_clear(gs.dist.Discrete, [lo, hi], [mean, std])


@given(
    gravity=vectors,
    time_step=scalars,
    skin=scalars,
    thermo_every=scalars,
    dimension=scalars,
)
def test_simulation_options(gravity, time_step, skin, thermo_every, dimension) -> None:
    works_or_clear(
        gs.Simulation,
        domain=BOX,
        gravity=gravity,
        time_step=time_step,
        skin=skin,
        thermo_every=thermo_every,
        dimension=dimension,
        quiet=True,
    )


@settings(max_examples=1000 if LONG else 300)
@given(
    position=arrays(2, 3),
    radius=st.one_of(scalars, arrays(2)),
    velocity=st.one_of(st.none(), arrays(2, 3), vectors),
    steps=st.one_of(st.integers(-5, 40), junk, st.floats(-10, 40)),
    until=st.one_of(st.floats(-1.0, 1e-4), st.just(float("nan")), junk),
)
def test_particles_and_runs(position, radius, velocity, steps, until) -> None:
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.05, -0.05, -0.05), hi=(0.05, 0.05, 0.05)),
        time_step=1e-6,
        quiet=True,
    )
    sim.add_wall(gs.Plane(point=(0, 0, -0.04), normal=(0, 0, 1), material=GLASS))
    works_or_clear(
        sim.add_particles, position=position, radius=radius, material=GLASS, velocity=velocity
    )
    works_or_clear(sim.run, steps=steps, progress=False)
    works_or_clear(
        sim.run, until=until if not isinstance(until, float) else min(until, 1e-4), progress=False
    )
    with sim.particles(writable=False) as p:
        assert np.all(np.isfinite(p.position)) or len(p) == 0


@given(count=scalars, fraction=scalars, rate=scalars, speed=vectors, every=scalars)
def test_insertion_operations(count, fraction, rate, speed, every) -> None:
    region = BOX
    works_or_clear(
        gs.insert.Pack,
        region=region,
        radius=1e-3,
        count=count,
        volume_fraction=fraction,
        material=GLASS,
    )
    face = gs.insert.DiscFace(centre=(0.005, 0.005, 0.009), normal=(0, 0, -1), radius=0.004)
    works_or_clear(
        gs.insert.Stream, face, mass_rate=rate, radius=5e-4, material=GLASS, velocity=speed
    )
    works_or_clear(gs.insert.Outlet, region=region, every=every)


@given(gain=scalars, speed=scalars, force=scalars, velocity=vectors, spin=vectors, origin=vectors)
def test_wall_motion_and_servos(gain, speed, force, velocity, spin, origin) -> None:
    sim = gs.Simulation(domain=BOX, quiet=True)
    wall = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    works_or_clear(wall.set_motion, velocity=velocity, angular_velocity=spin, origin=origin)
    servo = works_or_clear(gs.geometry.Servo, gain=gain, max_speed=speed, target_force=force)
    if servo is not None:
        works_or_clear(setattr, wall, "servo", servo)
    works_or_clear(sim.run, steps=2, progress=False)
    assert np.all(np.isfinite(wall.position))


@given(
    displacement=scalars,
    overlap=scalars,
    enabled=scalars,
    policy=st.one_of(st.sampled_from(["warn", "error", "ignore"]), scalars),
    timeout=scalars,
)
def test_guards_policies_and_timeout(displacement, overlap, enabled, policy, timeout) -> None:
    guards = works_or_clear(
        gs.Guards, max_step_displacement=displacement, max_overlap=overlap, enabled=enabled
    )
    works_or_clear(gs.Simulation, domain=BOX, guards=guards, lost_particles=policy, quiet=True)
    before = gs.parallel.timeout()
    try:
        works_or_clear(gs.parallel.set_timeout, timeout)
        assert gs.parallel.timeout() >= 0
    finally:
        gs.parallel.set_timeout(before)


@given(cg=scalars, lo=vectors, hi=vectors, gain=scalars, cell=scalars, scheme=scalars)
def test_hierarchy_levels(cg, lo, hi, gain, cell, scheme) -> None:
    region = works_or_clear(gs.Box, lo=lo, hi=hi)
    exchange = works_or_clear(gs.Exchange, cell_size=cell, velocity_gain=gain)
    level = works_or_clear(gs.Level, cg=cg, region=region, exchange=exchange)
    base = gs.scaling.ParameterSet(domain=BOX, size=gs.dist.Monodisperse(2e-4), materials=(GLASS,))
    if level is not None:
        works_or_clear(gs.Hierarchy, base=base, levels=[gs.Level(cg=2.0), level], scheme=scheme)
    works_or_clear(gs.scaling.scale, base, h=cg, scheme=scheme)
    works_or_clear(gs.scaling.level_parameters, base, cg, region=(lo, hi), time_step=gain)


@given(spacing=scalars, count=scalars, jitter=scalars, seed=scalars, every=scalars, step=scalars)
def test_placement_helpers_and_outputs(spacing, count, jitter, seed, every, step) -> None:
    works_or_clear(gs.insert.lattice, BOX, spacing=spacing, count=count, jitter=jitter, seed=seed)
    works_or_clear(gs.insert.random_in_box, BOX, radius=spacing, count=count, seed=seed)
    works_or_clear(gs.io.VTK, "unused", every=every, every_steps=step)
    works_or_clear(gs.timestep.rayleigh_time, GLASS, radius=spacing)


@settings(max_examples=1000 if LONG else 300)
@given(
    ids=st.one_of(arrays(3), st.lists(st.integers(-5, 50), max_size=5)),
    fields=st.one_of(st.lists(st.sampled_from(["position", "id", "mass", "x", ""])), scalars),
    every=scalars,
    threshold=scalars,
    path=st.one_of(st.just("missing.h5"), st.just(""), scalars),
)
def test_simulation_methods(ids, fields, every, threshold, path) -> None:
    sim = gs.Simulation(domain=BOX, time_step=1e-6, quiet=True)
    radius = np.full(8, 5e-4)
    sim.add_particles(position=gs.insert.lattice(BOX, 2e-3, count=8), radius=radius, material=GLASS)
    works_or_clear(sim.remove_particles, ids)
    works_or_clear(sim.gather, fields)
    works_or_clear(sim.balance, every=every, threshold=threshold)
    works_or_clear(sim.add_outlet, works_or_clear(gs.insert.Outlet, region=BOX, every=every))
    works_or_clear(sim.restart, path)
    works_or_clear(sim.run, steps=3, progress=False)
    assert sim.num_particles <= 8


@pytest.mark.parametrize("value", [np.nan, "0.1", True, 1j, [[0.1]], -1e300])
def test_the_fuzzed_paths_reject_the_usual_suspects_clearly(value) -> None:
    """A fixed set of the values the search explores, so that a regression fails the same way
    every time."""
    with pytest.raises(CLEAR):
        gs.Material(density=value, youngs_modulus=1e7, poisson_ratio=0.3)
