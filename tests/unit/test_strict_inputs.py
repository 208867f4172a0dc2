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


# --------------------------------------------------------------------------- flags (bools)

FLAGS = [
    (lambda v: gs.contact.HertzMindlin(limit_force=v), "HertzMindlin.limit_force"),
    (lambda v: gs.contact.Linear(tangential_damping=v), "Linear.tangential_damping"),
    (
        lambda v: gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=0.01, inside=v),
        "Cylinder.inside",
    ),
    (lambda v: gs.Guards(enabled=v), "Guards.enabled"),
    (lambda v: gs.Exchange(mass_flux_correction=v), "Exchange.mass_flux_correction"),
    (lambda v: gs.Simulation(domain=BOX, force_time_step=v), "Simulation.force_time_step"),
    (lambda v: gs.Simulation(domain=BOX, quiet=v), "Simulation.quiet"),
    (lambda v: gs.Simulation(domain=BOX, record_contacts=v), "Simulation.record_contacts"),
    (lambda v: gs.io.VTK("vtk_out", every_steps=5, binary=v), "VTK.binary"),
    (lambda v: gs.io.VTK("vtk_out", every_steps=5, resume=v), "VTK.resume"),
    (lambda v: gs.io.ContactNetwork("net_out", every_steps=5, walls=v), "ContactNetwork.walls"),
]
BOX = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01))


@pytest.mark.parametrize(("make", "name"), FLAGS)
@pytest.mark.parametrize("value", ["no", 0, 1, None, 1.0])
def test_flags_take_bools_only(make, name, value) -> None:
    """A string such as 'no' was taken for its truth value (True)."""
    with pytest.raises(ValueError) as err:
        make(value)
    assert str(err.value) == f"{name} must be True or False, got {value!r}"


@pytest.mark.parametrize(("make", "name"), FLAGS)
def test_flags_take_python_and_numpy_bools(make, name) -> None:
    make(np.bool_(False))
    make(True)


def test_hierarchy_force_time_step_is_a_flag() -> None:
    base = gs.scaling.ParameterSet(domain=BOX)
    with pytest.raises(
        ValueError, match="^Hierarchy.force_time_step must be True or False, got 'no'"
    ):
        gs.Hierarchy(base=base, levels=[gs.Level(cg=1)], force_time_step="no")


def test_flags_are_stored_as_python_bools() -> None:
    law = gs.contact.HertzMindlin(limit_force=np.bool_(True))
    assert law.limit_force is True
    sim = gs.Simulation(domain=BOX, record_contacts=np.True_)
    assert sim.record_contacts is True
    with pytest.raises(ValueError, match="Simulation.record_contacts must be True or False"):
        sim.record_contacts = "yes"


# --------------------------------------------------------------------------- real numbers


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: gs.Material(density=2500, youngs_modulus="1e7", poisson_ratio=0.3),
            "Material.youngs_modulus must be positive (Pa; inf for a rigid wall material), "
            "got '1e7'",
        ),
        (
            lambda: gs.Material(density=2500, youngs_modulus=True, poisson_ratio=0.3),
            "Material.youngs_modulus must be positive (Pa; inf for a rigid wall material), "
            "got True",
        ),
        (
            lambda: gs.contact.EEPA(unloading_ratio="3"),
            "EEPA.unloading_ratio must be a number >= 1 (k2/k1), got '3'",
        ),
        (
            lambda: gs.contact.EEPA(unloading_ratio=0.5),
            "EEPA.unloading_ratio must be >= 1 (k2/k1) and finite, got 0.5",
        ),
        (
            lambda: gs.contact.EEPA(pull_off_force="-1e-4"),
            "EEPA.pull_off_force must be a finite number (N), got '-1e-4'",
        ),
        (lambda: gs.contact.EEPA(exponent=True), "EEPA.exponent must be 1 or 1.5, got True"),
        (
            lambda: gs.contact.Pair(unloading_ratio="3"),
            "Pair.unloading_ratio must be a number >= 1 (k2/k1), got '3'",
        ),
        (
            lambda: gs.contact.Pair(pull_off_force=np.inf),
            "Pair.pull_off_force must be finite (N), got inf",
        ),
        (
            lambda: gs.geometry.Servo(gain=1e-2, max_speed=0.05, target_force="10"),
            "Servo.target_force must be a finite number (N), got '10'",
        ),
        (
            lambda: gs.geometry.Servo(gain=1e-2, max_speed=0.05, target_force=np.nan),
            "Servo.target_force must be finite (N), got nan",
        ),
        (
            lambda: gs.geometry.Servo(gain=1e-2, max_speed=0.05, target_stress=True),
            "Servo.target_stress must be a finite number (Pa), got True",
        ),
        (
            lambda: gs.Simulation(domain=BOX, thermo_every=True),
            "Simulation.thermo_every must be a positive integer, got True",
        ),
        (
            lambda: gs.Simulation(domain=BOX, thermo_every="10"),
            "Simulation.thermo_every must be a positive integer, got '10'",
        ),
    ],
)
def test_numbers_are_real_numbers_only(make, message) -> None:
    with pytest.raises(ValueError) as err:
        make()
    assert str(err.value) == message


def test_rigid_modulus_and_integral_floats_still_work() -> None:
    assert gs.Material(density=2500, youngs_modulus=np.inf, poisson_ratio=0.3).rigid
    assert gs.contact.EEPA(unloading_ratio=np.float32(3), exponent=1.5).unloading_ratio == 3
    assert gs.Simulation(domain=BOX, thermo_every=100.0).thermo_every == 100


@pytest.mark.parametrize(
    ("periodic", "shown"),
    [("yes", "'yes'"), (None, "None"), ((True, False), "(True, False)"), ((1, 0, 0), "(1, 0, 0)")],
)
def test_box_periodic_takes_a_bool_or_three(periodic, shown) -> None:
    with pytest.raises(ValueError) as err:
        gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic=periodic)
    assert str(err.value) == (
        f"Box.periodic must be True, False or three of them (x, y, z), got {shown}"
    )
    assert gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic=True).periodic == (True, True, True)
    box = gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic=np.array([True, False, True]))
    assert box.periodic == (True, False, True)


# --------------------------------------------------------------------------- run()


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"steps": True}, "Simulation.run.steps must be a non-negative integer, got True"),
        ({"steps": "100"}, "Simulation.run.steps must be a non-negative integer, got '100'"),
        ({"steps": 10.5}, "Simulation.run.steps must be a non-negative integer, got 10.5"),
        ({"until": "1e-4"}, "Simulation.run.until must be a finite number (s), got '1e-4'"),
        ({"until": np.nan}, "Simulation.run.until must be finite (s), got nan"),
        ({"steps": 1, "progress": "no"}, "Simulation.run.progress must be True or False, got 'no'"),
        (
            {"steps": 2**63},
            "Simulation.run.steps must end the run at step 2**62 at most (the step counter is an "
            "int64), got 9223372036854775808 from step 0",
        ),
        (
            {"until": 1e300},
            "Simulation.run.until must be reachable within 2**62 steps (the step counter is an "
            "int64), got 1e+300 s: 1e+305 steps of 1e-05 s from t = 0 s",
        ),
    ],
)
def test_run_refuses_what_it_cannot_run(arguments, message) -> None:
    s = sim()
    s.time_step = 1e-5
    s.add_particles(position=GOOD, radius=1e-3, material=GLASS)
    with pytest.raises(ValueError) as err:
        s.run(**({"progress": False} | arguments))
    assert str(err.value) == message
    assert s.step == 0
    s.run(steps=np.int64(2), progress=np.False_)
    s.run(steps=1e1, progress=False)  # an integral float
    assert s.step == 12


def test_a_mass_float64_cannot_hold_is_refused_naming_the_radius() -> None:
    s = sim()
    with pytest.raises(ValueError) as err:
        s.add_particles(position=[GOOD[0]] * 2, radius=[1e-3, 1e-200], material=GLASS)
    assert str(err.value).startswith(
        "Simulation.add_particles.radius must give a mass and moment of inertia that float64 "
        "holds as normal numbers (between 2.23e-308 and 1.8e+308), got 1e-200 m at index 1: "
        "mass 0 kg"
    )
    # tiny but representable: the engine copes (with the placement checks off)
    s.add_particles(position=GOOD, radius=1e-30, material=GLASS, check_placement=False)


def binary_stl(count: int, triangles: int) -> bytes:
    one = np.array([0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0], "<f4").tobytes() + b"\0\0"
    return b"\0" * 80 + count.to_bytes(4, "little") + one * triangles


def test_a_binary_stl_shorter_than_its_header_says_is_refused(tmp_path) -> None:
    path = tmp_path / "short.stl"
    path.write_bytes(binary_stl(5, 2))
    with pytest.raises(ValueError) as err:
        gs.geometry.Mesh.from_stl(path)
    assert str(err.value) == (
        "Mesh.from_stl.path must be a binary STL file of 84 + 50 x 5 = 334 bytes (its header "
        f"claims 5 triangles), got {path!r} of 184 bytes (numpy-stl read 2 triangles): it is "
        "truncated or damaged"
    )
    path.write_bytes(binary_stl(2, 2))
    assert len(gs.geometry.Mesh.from_stl(path).triangles) == 2


def test_an_stl_of_degenerate_triangles_only_is_refused(tmp_path) -> None:
    path = tmp_path / "flat.stl"
    path.write_text(
        "solid s\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
        "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
        "vertex 2 0 0\nendloop\nendfacet\nendsolid s\n"
    )
    with pytest.raises(ValueError) as err:
        gs.geometry.Mesh.from_stl(path)
    assert str(err.value) == (
        f"Mesh.from_stl.path must hold at least one triangle of non-zero area, got {path!r}: "
        "every one of its 2 triangle(s) is degenerate (zero area: repeated or collinear "
        "vertices)"
    )
