"""grainscale.scaling: the factor tables against dimensional analysis, the mapping of every
parameter kind, the forces the engine produces with scaled parameters, and the error messages."""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs
from grainscale.contact import EEPA, EPSD, HertzMindlin, Linear, Pair
from grainscale.geometry import Cylinder, Mesh, Plane, Rectangle, Servo
from grainscale.scaling import (
    ParameterSet,
    Particles,
    build_simulation,
    factors,
    scale,
    similarity_exponents,
)

A = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3, name="a")
B = gs.Material(density=7800, youngs_modulus=2e8, poisson_ratio=0.29, name="b")
BOX = gs.Box(lo=(-0.1, 0, 0), hi=(0.1, 0.2, 0.3))

# Dimensions [L^a M^b T^c] of every tabulated quantity, and t: how a 2-D (per unit thickness)
# quantity differs, L^t (extensive quantities: -1; the servo gain, an inverse force: +1).
# With length x h, time x h and density x 1 (so mass = density L^3 x h^3) the exact factor is
# h^(a + 3b + c) in 3-D and h^(a + 3b + c + t) in 2-D (Feng & Owen 2014).
DIMENSIONS = {
    "radius": (1, 0, 0, 0),
    "overlap": (1, 0, 0, 0),
    "domain_length": (1, 0, 0, 0),
    "skin": (1, 0, 0, 0),
    "area": (2, 0, 0, -1),
    "time": (0, 0, 1, 0),
    "time_step": (0, 0, 1, 0),
    "density": (-3, 1, 0, 0),
    "mass": (0, 1, 0, -1),
    "inertia": (2, 1, 0, -1),
    "velocity": (1, 0, -1, 0),
    "characteristic_velocity": (1, 0, -1, 0),
    "angular_velocity": (0, 0, -1, 0),
    "wall_angular_velocity": (0, 0, -1, 0),
    "gravity": (1, 0, -2, 0),
    "force": (1, 1, -2, -1),
    "wall_force": (1, 1, -2, -1),
    "pull_off_force": (1, 1, -2, -1),
    "torque": (2, 1, -2, -1),
    "energy": (2, 1, -2, -1),
    "stress": (-1, 1, -2, 0),
    "cohesion_energy_density": (-1, 1, -2, 0),
    "surface_energy": (0, 1, -2, 0),
    "normal_stiffness": (0, 1, -2, -1),
    "tangential_stiffness": (0, 1, -2, -1),
    "rolling_stiffness": (2, 1, -2, -1),
    "damping_coefficient": (0, 1, -1, -1),
    "mass_rate": (0, 1, -1, -1),
    "servo_gain": (0, -1, 1, 1),
    "servo_integral_gain": (0, -1, 0, 1),
    "restitution": (0, 0, 0, 0),
    "friction": (0, 0, 0, 0),
    "rolling_friction": (0, 0, 0, 0),
    "rolling_damping": (0, 0, 0, 0),
    "poisson_ratio": (0, 0, 0, 0),
    "particle_count": (0, 0, 0, 0),
}


@pytest.mark.parametrize("dimension", [3, 2])
def test_exact_table_matches_dimensional_analysis(dimension: int) -> None:
    table = factors("exact", dimension)
    assert set(table) == set(DIMENSIONS)
    for name, (a, b, c, t) in DIMENSIONS.items():
        expected = a + 3 * b + c + (t if dimension == 2 else 0)
        assert table[name] == expected, f"{name} ({dimension}-D)"


def test_exact_table_matches_design_list() -> None:
    """DESIGN.md section 3 (3-D / 2-D): mass h^3/h^2, inertia h^5/h^4, force h^2/h, ..."""
    listed = {
        "mass": (3, 2),
        "inertia": (5, 4),
        "force": (2, 1),
        "torque": (3, 2),
        "normal_stiffness": (1, 0),
        "damping_coefficient": (2, 1),
        "energy": (3, 2),
        "pull_off_force": (2, 1),
        "gravity": (-1, -1),
        "angular_velocity": (-1, -1),
        "time_step": (1, 1),
        "skin": (1, 1),
        "surface_energy": (1, 1),
        "cohesion_energy_density": (0, 0),
    }
    for name, (p3, p2) in listed.items():
        assert (factors("exact", 3)[name], factors("exact", 2)[name]) == (p3, p2), name


@pytest.mark.parametrize("dimension", [3, 2])
def test_exact_scaling_preserves_every_similarity_number(dimension: int) -> None:
    assert all(p == 0 for p in similarity_exponents("exact", dimension).values())


@pytest.mark.parametrize("scheme", ["exact", "cg", "sakai", "spa"])
def test_2d_tables_drop_one_power_for_extensive_quantities(scheme: str) -> None:
    t3, t2 = factors(scheme, 3), factors(scheme, 2)
    for name, (_, _, _, t) in DIMENSIONS.items():
        # cg/sakai/spa keep system quantities fixed (wall force, mass rate, area, servo gain)
        if factors(scheme, 3)[name] == 0 and name in ("wall_force", "mass_rate", "area"):
            continue
        if name in ("servo_gain", "servo_integral_gain") and t3[name] == 0:
            continue
        if name == "particle_count":  # h^-3 spheres, h^-2 discs per unit thickness
            assert t2[name] == t3[name] * 2 / 3
            continue
        assert t2[name] == t3[name] + t, f"{scheme}: {name}"


def _eepa_reference(**law: float) -> ParameterSet:
    eepa = EEPA(
        loading_stiffness=1e4,
        unloading_ratio=3.0,
        adhesive_stiffness=50.0,
        pull_off_force=-1e-4,
        pairs={(A, B): Pair(loading_stiffness=2e4, pull_off_force=-3e-4, adhesive_stiffness=10.0)},
        **law,
    )
    return ParameterSet(
        domain=BOX,
        contact=eepa,
        time_step=1e-6,
        skin=1e-4,
        size=gs.dist.Uniform(1e-3, 2e-3),
        materials=(A, B),
    )


def test_cg_eepa_stiffness_linear_and_pull_off_quadratic() -> None:
    """Thakur et al. 2016: k1, k2 (= ratio k1), k_t (= 2/7 k1) ~ h; f0 ~ h^2; k_adh (chi = 1)
    ~ h; materials, gravity, domain unchanged; time step and skin ~ h."""
    h = 3.0
    ref = _eepa_reference()
    s = scale(ref, h, "cg")
    law = s.params.contact
    assert isinstance(law, EEPA)
    assert law.loading_stiffness == pytest.approx(1e4 * h, rel=1e-15)
    assert law.unloading_ratio == 3.0
    assert law.adhesive_stiffness == pytest.approx(50.0 * h, rel=1e-15)
    assert law.pull_off_force == pytest.approx(-1e-4 * h**2, rel=1e-15)
    pair = law.pairs[(A, B)]
    assert pair.loading_stiffness == pytest.approx(2e4 * h, rel=1e-15)
    assert pair.pull_off_force == pytest.approx(-3e-4 * h**2, rel=1e-15)
    assert pair.adhesive_stiffness == pytest.approx(10.0 * h, rel=1e-15)
    assert s.params.materials == (A, B)
    assert s.params.gravity == ref.gravity and s.params.domain == ref.domain
    assert s.params.time_step == pytest.approx(h * 1e-6) and s.params.skin == pytest.approx(
        h * 1e-4
    )
    assert s.params.size == gs.dist.Uniform(h * 1e-3, h * 2e-3)
    assert s.factors["youngs_modulus"] == 1.0
    # k_adh in N/m^chi scales as h^(2 - chi); a Pair takes chi from the law
    chi2 = scale(_eepa_reference(adhesion_exponent=2.0), h, "cg").params.contact
    assert chi2.adhesive_stiffness == 50.0 and chi2.pairs[(A, B)].adhesive_stiffness == 10.0
    # with exponent 1.5, k1 in N/m^1.5 scales as h^(2 - 1.5)
    s15 = scale(_eepa_reference(exponent=1.5), h, "cg")
    assert s15.params.contact.loading_stiffness == pytest.approx(1e4 * math.sqrt(h), rel=1e-15)


def test_2d_modulus_keeps_the_3d_laws_consistent() -> None:
    """Discs of unit thickness with the 3-D Hertz formula: F = 4/3 E* sqrt(R d) d grows as h^2
    at E fixed, the 2-D table wants force per thickness x h, so E carries 1/h."""
    for scheme in ("exact", "cg"):
        s = scale(ParameterSet(domain=BOX, materials=(A,)), 2.0, scheme, dimension=2)
        assert s.factors["youngs_modulus"] == 0.5
        assert s.params.materials[0].youngs_modulus == A.youngs_modulus / 2
        assert scale(ParameterSet(domain=BOX), 2.0, scheme).factors["youngs_modulus"] == 1.0


def test_cg_linear_spring_and_rolling() -> None:
    law = Linear(normal_stiffness=1e4, tangential_stiffness=3e3, rolling=EPSD(0.1, 0.3))
    s = scale(ParameterSet(domain=BOX, contact=law), 4.0, "cg")
    assert s.params.contact.normal_stiffness == 4e4
    assert s.params.contact.tangential_stiffness == 1.2e4
    assert s.params.contact.rolling == EPSD(0.1, 0.3)  # rolling models are invariant


def test_broken_similarities_per_scheme() -> None:
    hertz = ParameterSet(domain=BOX)
    assert scale(hertz, 2.0, "exact").broken == []
    cg = {b.name: b for b in scale(hertz, 2.0, "cg").broken}
    assert set(cg) == {"froude", "size_ratio", "inertial_number", "time_ratio"}
    assert cg["froude"].exponent == -1 and cg["froude"].factor == 0.5
    assert cg["inertial_number"].factor == 2.0
    cohesive = {b.name for b in scale(_eepa_reference(), 2.0, "cg").broken}
    assert "bond" in cohesive
    no_gravity = ParameterSet(domain=BOX, gravity=(0, 0, 0))
    assert "froude" not in {b.name for b in scale(no_gravity, 2.0, "cg").broken}
    sakai = {b.name for b in scale(_eepa_reference(), 2.0, "sakai").broken}
    spa = {b.name for b in scale(_eepa_reference(), 2.0, "spa").broken}
    # Zhang et al. 2021: force ~ h^3 breaks the contact-force-to-stress ratio; SPA scales the
    # cohesion like the weight (h^3) and so keeps the Bond number, Sakai (h^2) does not.
    assert {"contact_stress", "relative_overlap", "bond"} <= sakai
    assert "contact_stress" in spa and "bond" not in spa


def test_representative_particle_schemes_scale_forces_by_h_cubed() -> None:
    h = 2.0
    lin = ParameterSet(domain=BOX, contact=Linear(normal_stiffness=1e4), time_step=1e-6)
    s = scale(lin, h, "sakai")
    assert s.params.contact.normal_stiffness == 1e4 * h**3
    assert s.params.time_step == 1e-6  # Sakai's Eq. 16: k and m both x h^3
    eepa = scale(_eepa_reference(), h, "sakai").params.contact
    assert eepa.pull_off_force == pytest.approx(-1e-4 * h**2)  # van der Waals: h^2
    assert scale(_eepa_reference(), h, "spa").params.contact.pull_off_force == pytest.approx(
        -1e-4 * h**3
    )
    # Hertz: E x h^(5/2), so that F = 4/3 E* sqrt(R* d) d is x h^3 at the same overlap; the
    # per-pair keys follow the new materials.
    hertz = ParameterSet(
        domain=BOX,
        contact=HertzMindlin(pairs={(A, None): Pair(friction=0.2)}),
        materials=(A,),
    )
    sh = scale(hertz, h, "sakai")
    (a2,) = sh.params.materials
    assert a2.youngs_modulus == pytest.approx(A.youngs_modulus * h**2.5)
    assert sh.params.contact.pairs == {(a2, None): Pair(friction=0.2)}


def _wall_force(params: ParameterSet) -> float:
    """Force (N, z) on the floor after one step of 1e-12 s: the particle moves by ~1e-16 of
    the overlap, and restitution 1 means no damping."""
    sim = build_simulation(params)
    sim.run(steps=1, progress=False)
    return float(sim.walls[0].force[2])


def _on_floor(
    law: gs.contact.ContactLaw,
    radius: float,
    overlap: float,
    sphere: gs.Material,
    floor: gs.Material,
) -> ParameterSet:
    p = Particles(np.array([[0.0, 0.1, radius - overlap]]), radius, sphere)
    return ParameterSet(
        domain=BOX,
        contact=law,
        gravity=(0.0, 0.0, 0.0),
        time_step=1e-12,
        skin=1e-4,
        walls=[Plane(point=(0, 0, 0), normal=(0, 0, 1), material=floor)],
        particles=[p],
    )


@pytest.mark.parametrize(
    "law",
    [
        HertzMindlin(restitution=1.0),
        Linear(restitution=1.0, characteristic_velocity=2.0),
        Linear(restitution=1.0, normal_stiffness=3e4),
        EEPA(restitution=1.0, pull_off_force=-1e-3),
        EEPA(restitution=1.0, loading_stiffness=5e4, pull_off_force=-1e-3),
        EEPA(restitution=1.0, exponent=1.5, loading_stiffness=5e5, pull_off_force=-1e-3),
    ],
    ids=["hertz", "linear_derived", "linear_given", "eepa_derived", "eepa_given", "eepa_n1.5"],
)
def test_engine_contact_force_scales_as_the_scheme_says(law: gs.contact.ContactLaw) -> None:
    """A sphere pressed into a floor, with the law and materials each scheme produces: exact and
    cg give F x h^2 at overlap x h, sakai F x h^3 at the same overlap (the pull-off force f0
    follows its own factor)."""
    r, d, h = 1e-3, 2e-5, 3.0
    f0 = getattr(law, "pull_off_force", 0.0)
    # the force on the floor is minus the force f0 + elastic on the particle
    f_ref = _wall_force(_on_floor(law, r, d, A, B)) + f0
    assert f_ref < 0
    for scheme in ("exact", "cg", "sakai", "spa"):
        table = factors(scheme)
        out = scale(ParameterSet(domain=BOX, contact=law, materials=(A, B)), h, scheme).params
        a2, b2 = out.materials
        f = _wall_force(_on_floor(out.contact, r * h, d * h ** table["overlap"], a2, b2))
        elastic = f + f0 * h ** table["pull_off_force"]
        assert elastic / f_ref == pytest.approx(h ** table["force"], rel=1e-12), scheme


def test_exact_maps_walls_servos_and_particles() -> None:
    h = 2.0
    mesh = Mesh(
        vertices=np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0.01]]),
        triangles=np.array([[0, 1, 2]]),
        angular_velocity=(0, 0, 4.0),
    )
    walls = [
        Plane(point=(0, 0, 0.01), normal=(0, 0, 1), velocity=(0, 0, 0.1)),
        Rectangle(corner=(0, 0, 0.2), edge1=(0.05, 0, 0), edge2=(0, 0.05, 0)),
        Cylinder(
            point=(0, 0.1, 0), axis=(0, 0, 1), radius=0.05, length=0.2, angular_velocity=(0, 0, 2.0)
        ),
        mesh,
    ]
    servos = {1: Servo(gain=1e-3, max_speed=0.05, target_force=10.0, integral_gain=0.5)}
    particles = Particles(
        np.array([[0.01, 0.02, 0.03]]),
        1e-3,
        A,
        velocity=np.array([[0.1, 0.2, 0.3]]),
        angular_velocity=np.array([[4.0, 0, 0]]),
    )
    ref = ParameterSet(domain=BOX, walls=walls, servos=servos, particles=[particles])
    out = scale(ref, h, "exact").params
    assert out.domain.lo == (-0.2, 0.0, 0.0) and out.domain.hi == (0.2, 0.4, 0.6)
    assert out.gravity == (0.0, 0.0, -9.81 / h)
    plane, rect, cyl, m = out.walls
    assert plane.point == (0, 0, 0.02) and plane.velocity == (0, 0, 0.1)
    assert rect.edge1 == (0.1, 0, 0) and rect.corner == (0, 0, 0.4)
    assert cyl.radius == 0.1 and cyl.length == 0.4 and cyl.angular_velocity == (0, 0, 1.0)
    np.testing.assert_array_equal(m.vertices, mesh.vertices * h)
    assert m.angular_velocity == (0, 0, 2.0) and m.origin == tuple(np.multiply(mesh.origin, h))
    servo = out.servos[1]
    assert servo.gain == 1e-3 / h**2 and servo.target_force == 40.0 and servo.max_speed == 0.05
    assert servo.integral_gain == 0.5 / h**3  # (m/s)/(N s): velocity / (force x time)
    p = out.particles[0]
    np.testing.assert_array_equal(p.position, particles.position * h)
    np.testing.assert_array_equal(p.radius, [2e-3])
    np.testing.assert_array_equal(p.velocity, particles.velocity)
    np.testing.assert_array_equal(p.angular_velocity, [[2.0, 0, 0]])
    # cg keeps the system: the same wall objects come back
    cg = scale(ParameterSet(domain=BOX, walls=walls, servos=servos), h, "cg").params
    assert all(a is b for a, b in zip(cg.walls, walls, strict=True))
    assert cg.servos[1] is servos[1]


def test_insertions_and_outlets() -> None:
    region = gs.Box(lo=(0, 0, 0), hi=(0.1, 0.1, 0.1))
    face = gs.insert.RectangleFace(corner=(0, 0, 0.2), edge1=(0.1, 0, 0), edge2=(0, 0.1, 0))
    ref = ParameterSet(
        domain=BOX,
        time_step=1e-6,
        insertions=[
            gs.insert.Pack(region, radius=1e-3, material=A, count=800, velocity=(0, 0, -1)),
            gs.insert.Stream(face, mass_rate=0.5, radius=1e-3, material=A, every=1e-3, start=0.1),
        ],
        outlets=[gs.insert.Outlet(region, every=10)],
    )
    exact = scale(ref, 2.0, "exact").params
    pack, stream = exact.insertions
    assert pack.count == 800 and pack.region.hi == (0.2, 0.2, 0.2)
    assert pack.radius == gs.dist.Monodisperse(2e-3) and pack.velocity == (0, 0, -1)
    assert stream.mass_rate == 2.0 and stream.every == 2e-3 and stream.start == 0.2
    assert stream.face.corner == (0, 0, 0.4) and stream.face.edge1 == (0.2, 0, 0)
    assert exact.outlets[0].every == 10 and exact.outlets[0].region.hi == (0.2, 0.2, 0.2)
    cg = scale(ref, 2.0, "cg").params
    pack, stream = cg.insertions
    assert pack.count == 100 and pack.region is region  # h^-3 as many in the same region
    assert stream.mass_rate == 0.5 and stream.every == 1e-3 and stream.face is face
    assert stream.radius == gs.dist.Monodisperse(2e-3)
    assert cg.outlets[0].every == 5  # the same process interval at twice the time step
    with pytest.raises(ValueError, match=r"Pack\.count must stay >= 1 after scaling"):
        scale(ref, 20.0, "cg")


@pytest.mark.parametrize(
    "dist",
    [
        gs.dist.Monodisperse(1e-3),
        gs.dist.Uniform(1e-3, 2e-3),
        gs.dist.Normal(1e-3, 1e-4),
        gs.dist.LogNormal(1e-3, 0.2),
        gs.dist.Discrete((1e-3, 2e-3), (1, 8), fractions="mass"),
    ],
)
def test_size_distributions_scale_by_h(dist: gs.dist.Distribution) -> None:
    out = scale(ParameterSet(domain=BOX, size=dist), 2.5, "cg").params.size
    assert type(out) is type(dist)
    assert out.mean_radius == pytest.approx(2.5 * dist.mean_radius, rel=1e-12)
    assert out.std_radius == pytest.approx(2.5 * dist.std_radius, rel=1e-12, abs=1e-18)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (
            lambda: scale(ParameterSet(domain=BOX), 2.0, "magic"),
            r"scaling\.scheme must be one of exact, cg, sakai, spa, got 'magic'",
        ),
        (
            lambda: scale(ParameterSet(domain=BOX), 0.0),
            r"scale\.h must be positive and finite, got 0\.0",
        ),
        (
            lambda: scale(ParameterSet(domain=BOX), -2),
            r"scale\.h must be positive and finite, got -2",
        ),
        (
            lambda: scale(ParameterSet(domain=BOX), float("nan")),
            r"scale\.h must be positive and finite, got nan",
        ),
        (
            lambda: scale(ParameterSet(domain=BOX), "two"),
            r"scale\.h must be a positive number, got 'two'",
        ),
        (
            lambda: scale(ParameterSet(domain=BOX), 2.0, dimension=1),
            r"scaling\.dimension must be 3 or 2, got 1",
        ),
        (lambda: factors("exact", 4), r"scaling\.dimension must be 3 or 2, got 4"),
        (
            lambda: scale("params", 2.0),
            r"scale\.params must be a scaling\.ParameterSet, got 'params'",
        ),
        (
            lambda: ParameterSet(domain=BOX, contact="hertz"),
            r"ParameterSet\.contact must be HertzMindlin, Linear or EEPA, got str",
        ),
        (
            lambda: ParameterSet(domain=(0, 1)),
            r"ParameterSet\.domain must be a grainscale\.Box, got \(0, 1\)",
        ),
        (
            lambda: ParameterSet(domain=BOX, time_step=-1.0),
            r"ParameterSet\.time_step must be positive and finite, got -1\.0",
        ),
        (
            lambda: ParameterSet(
                domain=BOX, servos={0: Servo(gain=1, max_speed=1, target_force=1)}
            ),
            r"ParameterSet\.servos must map wall indices in \[0, 0\) to Servo, got 0",
        ),
        (
            lambda: Particles(np.zeros((1, 3)), -1e-3, A),
            r"Particles\.radius must be positive and finite \(m\), got -0\.001",
        ),
        (
            lambda: build_simulation("params"),
            r"build_simulation\.params must be a ParameterSet, got 'params'",
        ),
    ],
)
def test_error_messages(call, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ValueError, match=message):
        call()


def test_cg_refuses_to_map_individual_particles() -> None:
    ref = ParameterSet(domain=BOX, particles=[Particles(np.zeros((1, 3)), 1e-3, A)])
    with pytest.raises(ValueError, match=r"scale\.params\.particles must be empty for scheme 'cg'"):
        scale(ref, 2.0, "cg")


@pytest.mark.parametrize("module", ["table", "transform"])
def test_docstring_examples(module: str) -> None:
    import doctest
    import importlib

    result = doctest.testmod(importlib.import_module(f"grainscale.scaling.{module}"))
    assert result.attempted > 0 and result.failed == 0
