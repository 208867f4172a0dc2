"""Settings that would be ignored or fail late are refused: misspelt or unknown attributes of
Simulation and Hierarchy, set-up fixed at construction, a run up to a time already past, an
output directory that is a file. Gravity is a setting that acts from the next step."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)


def free_sphere(gravity: tuple[float, float, float]) -> gs.Simulation:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(1, 1, 1)), gravity=gravity, quiet=True)
    sim.add_particles(position=[[0.5, 0.5, 0.9]], radius=1e-3, material=GLASS)
    sim.time_step = 1e-5
    return sim


def test_misspelt_setting_is_refused_with_the_settable_names() -> None:
    sim = free_sphere((0, 0, -9.81))
    with pytest.raises(AttributeError, match="'time_stp'") as err:
        sim.time_stp = 1e-6  # type: ignore[attr-defined]
    assert "time_step" in str(err.value) and "gravity" in str(err.value)
    assert sim.time_step == 1e-5
    sim.quiet = False  # attributes of the simulation stay settable
    assert sim.quiet is False


@pytest.mark.parametrize("name", ["contact", "domain"])
def test_setup_fixed_at_construction_is_refused(name: str) -> None:
    sim = free_sphere((0, 0, -9.81))
    before = getattr(sim, name)
    box = gs.Box(lo=(0, 0, 0), hi=(2, 2, 2))
    value = gs.contact.HertzMindlin(friction=0.1) if name == "contact" else box
    with pytest.raises(AttributeError, match=f"Simulation.{name} is fixed at construction"):
        setattr(sim, name, value)
    assert getattr(sim, name) is before


def test_subclasses_outside_the_package_keep_their_freedom() -> None:
    class Mine(gs.Simulation):
        pass

    sim = Mine(domain=gs.Box(lo=(0, 0, 0), hi=(1, 1, 1)), quiet=True)
    sim.note = "free"  # type: ignore[attr-defined]
    assert sim.note == "free"  # type: ignore[attr-defined]


def test_gravity_changes_from_the_next_step() -> None:
    """Velocity Verlet is exact for a constant acceleration: v = g1 t1 + g2 t2."""
    sim = free_sphere((0, 0, -9.81))
    sim.run(steps=100, progress=False)
    sim.gravity = (1.0, 0.0, -1.62)
    assert sim.gravity == (1.0, 0.0, -1.62)
    sim.run(steps=200, progress=False)
    with sim.particles() as p:
        v = np.array(p.velocity[0])
    expected = np.array([0.0, 0.0, -9.81]) * 100 * 1e-5 + np.array([1.0, 0.0, -1.62]) * 200 * 1e-5
    np.testing.assert_allclose(v, expected, rtol=1e-12, atol=1e-15)
    with pytest.raises(ValueError, match="Simulation.gravity must be a finite 3-vector"):
        sim.gravity = (0, 0, float("nan"))  # type: ignore[assignment]
    assert sim.gravity == (1.0, 0.0, -1.62)


def test_run_until_a_time_already_past_is_refused() -> None:
    sim = free_sphere((0, 0, -9.81))
    sim.run(steps=10, progress=False)
    with pytest.raises(ValueError, match=r"Simulation.run.until must not lie before .* got 5e-05"):
        sim.run(until=5e-5, progress=False)
    sim.run(until=sim.time - 0.5e-5, progress=False)  # rounding of a computed time: no step
    assert sim.step == 10


@pytest.mark.parametrize(
    "make",
    [
        lambda d: gs.io.VTK(d, every_steps=1),
        lambda d: gs.io.Dump(d, every_steps=1),
        lambda d: gs.io.ContactNetwork(d, every_steps=1),
    ],
)
def test_output_directory_that_is_a_file_is_refused_when_made(
    tmp_path: Path, make: Callable[[Path], object]
) -> None:
    taken = tmp_path / "taken"
    taken.write_text("a file")
    for bad, why in [(taken, "a file of that name exists"), (taken / "sub", "is a file")]:
        with pytest.raises(ValueError, match=f"directory, got '{bad}': .*{why}"):
            make(bad)
    out = make(tmp_path / "new" / "dir")  # created when it first writes
    assert not (tmp_path / "new").exists() and out is not None
