"""Strict types and shapes at the public entry points (issue 25): no silent coercion of
strings, bools, complex numbers or extra dimensions; non-finite values named with their index."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
GOOD = [[0.005, 0.005, 0.005]]


def sim() -> gs.Simulation:
    return gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))


@pytest.mark.parametrize(
    ("position", "message"),
    [
        ([["0.005", "0.005", "0.005"]], r"position must be an array of real numbers, got dtype <U"),
        (
            [[0.005 + 0j, 0.005, 0.005]],
            "position must be an array of real numbers, got dtype complex",
        ),
        ([[True, False, True]], "position must be an array of real numbers, got dtype bool"),
        (np.zeros((1, 3, 1)), r"position must have shape \(N, 3\) or \(3,\), got \(1, 3, 1\)"),
        ([[0.005, 0.005]], r"position must have shape \(N, 3\) or \(3,\), got \(1, 2\)"),
        ([[0.005, np.inf, 0.005]], r"position must be finite, got inf at index \(0, 1\)"),
        (
            [[0.005, 0.005, 0.005], [0.002, 0.002]],
            "position must be an array of real numbers, got dtype object",
        ),
    ],
)
def test_add_particles_refuses_what_is_not_an_array_of_positions(position, message) -> None:
    s = sim()
    with pytest.raises(ValueError, match=f"Simulation.add_particles.{message}"):
        s.add_particles(position=position, radius=1e-3, material=GLASS)
    assert s.num_particles == 0


@pytest.mark.parametrize(
    ("radius", "message"),
    [
        ("1e-3", "radius must be an array of real numbers"),
        (True, "radius must be an array of real numbers, got dtype bool"),
        (1e-3 + 0j, "radius must be an array of real numbers, got dtype complex"),
        ([1e-3, 1e-3], r"radius must have shape \(\) or \(1,\), got \(2,\)"),
        (np.nan, "radius must be finite, got nan"),
    ],
)
def test_add_particles_refuses_bad_radii(radius, message) -> None:
    with pytest.raises(ValueError, match=f"Simulation.add_particles.{message}"):
        sim().add_particles(position=GOOD, radius=radius, material=GLASS)


def test_velocities_are_checked_with_their_index() -> None:
    with pytest.raises(
        ValueError, match=r"add_particles.velocity must be finite, got nan at index \(1, 2\)"
    ):
        sim().add_particles(
            position=[[0.003, 0.005, 0.005], [0.007, 0.005, 0.005]],
            radius=1e-3,
            material=GLASS,
            velocity=[[0, 0, 0], [0, 0, np.nan]],
        )
    with pytest.raises(
        ValueError, match=r"angular_velocity must have shape \(3,\) or \(1, 3\), got \(1, 3, 1\)"
    ):
        sim().add_particles(
            position=GOOD, radius=1e-3, material=GLASS, angular_velocity=np.zeros((1, 3, 1))
        )


@pytest.mark.parametrize("value", ["2500", True, 2500 + 0j, [2500.0]])
def test_scalar_parameters_take_real_numbers_only(value) -> None:
    with pytest.raises(ValueError, match="Material.density must be a positive number"):
        gs.Material(density=value, youngs_modulus=1e7, poisson_ratio=0.3)


@pytest.mark.parametrize("value", [("0", "0", "1"), (0, 0, True), (0, 0, 1j), ((0, 0, 1),)])
def test_vectors_take_three_real_numbers_only(value) -> None:
    with pytest.raises(ValueError, match="Simulation.gravity must be a finite 3-vector of numbers"):
        gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), gravity=value)


def test_numpy_scalars_and_integers_are_real_numbers() -> None:
    m = gs.Material(density=np.float32(2500), youngs_modulus=np.int64(10**7), poisson_ratio=0.3)
    s = sim()
    ids = s.add_particles(
        position=np.array(GOOD, dtype=np.float32), radius=np.float64(1e-3), material=m
    )
    assert list(ids) == [0]


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "must be a readable ASCII or binary STL file"),
        (b"hello world, not an stl" * 3, "triangles with finite coordinates"),
        (np.random.default_rng(1).bytes(5000), "must be a readable ASCII or binary STL file"),
    ],
)
def test_damaged_stl_files_are_refused_naming_the_file(tmp_path, content, message) -> None:
    path = tmp_path / "damaged.stl"
    path.write_bytes(content)
    with pytest.raises(ValueError, match=r"^Mesh.from_stl.path must ") as err:
        gs.geometry.Mesh.from_stl(path)
    assert message in str(err.value) and "damaged.stl" in str(err.value)
    with pytest.raises(ValueError, match="Mesh.from_stl.path must be an existing STL file"):
        gs.geometry.Mesh.from_stl(tmp_path / "missing.stl")
