"""Contact-law API and composition (grainscale.contact, DESIGN.md 2.4).

* Every supported combination normal+rolling (hertz|linear|eepa x none|cdt|epsd|epsd2) settles
  150 polydisperse spheres in a closed box under gravity without blow-up: no lost particles,
  kinetic energy down by orders of magnitude, max overlap / radius < 5 %.
* Parameter validation: messages of the form "Owner.parameter must be ..., got ...".
* Mixing rules of the interaction properties (contact.py docstring): explicit Pair beats the
  material values beats the law value; two materials' values are averaged; a rigid wall uses
  the particle's value. Checked through law.interaction(a, b) and through behaviour (restitution
  of a bounce on a rigid wall and of a head-on sphere-sphere collision).
* Particle-particle and particle-wall contacts use the same law: the restitution of two equal
  spheres in the centre-of-mass frame equals that of a sphere on a rigid wall.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

import grainscale as gs
from grainscale.contact import CDT, EEPA, EPSD, EPSD2, HertzMindlin, Linear, Pair

SOFT = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="soft")
NORMALS = ("hertz", "linear", "eepa")
ROLLINGS = ("none", "cdt", "epsd", "epsd2")

TOL_E = 2e-3


def _rolling(name: str):
    return {"none": None, "cdt": CDT(0.1), "epsd": EPSD(0.1, 0.3), "epsd2": EPSD2(0.1)}[name]


def _law(normal: str, rolling: str = "none", **kw):
    roll = _rolling(rolling)
    if normal == "hertz":
        return HertzMindlin(rolling=roll, **kw)
    if normal == "linear":
        return Linear(rolling=roll, characteristic_velocity=1.0, **kw)
    return EEPA(rolling=roll, **kw)


# --------------------------------------------------------------------------- registry


def test_supported_laws_are_the_twelve_combinations():
    expected = {f"{n}+{r}" for n, r in itertools.product(NORMALS, ROLLINGS)}
    got = gs.contact.supported_laws()
    assert len(got) == len(set(got)) == 12, f"supported_laws() = {got}"
    assert set(got) == expected, f"missing {expected - set(got)}, unexpected {set(got) - expected}"


def test_python_laws_cover_every_supported_combination():
    names = set()
    for n, r in itertools.product(NORMALS, ROLLINGS):
        law = _law(n, r)
        names.add(f"{law._normal}+{law.rolling_name}")
    assert names == set(gs.contact.supported_laws())


# --------------------------------------------------------------------------- settle


SETTLE_BOX = gs.Box(lo=(0.0, 0.0, 0.0), hi=(10e-3, 10e-3, 40e-3))
SETTLE_N = 150
SETTLE_CHUNKS = 15
SETTLE_CHUNK_STEPS = 2000


@pytest.fixture(scope="module")
def settle_packing():
    rng = np.random.default_rng(7)
    radii = rng.uniform(0.8e-3, 1.2e-3, SETTLE_N)
    return gs.insert.random_in_box(SETTLE_BOX, radii, seed=11), radii


def _settle_law(normal: str, rolling: str, spring_rotation: str = "rescale"):
    kw = {"restitution": 0.5, "friction": 0.5, "spring_rotation": spring_rotation}
    if normal == "eepa":
        # Adhesive EEPA: k1 = 2 E* R* ~ 3e3 N/m, pull-off ~ 0.2 m g of a sphere.
        kw.update(unloading_ratio=3.0, adhesive_stiffness=100.0, pull_off_force=-2e-5)
    return _law(normal, rolling, **kw)


# Every law, and two with the springs only projected (LIGGGHTS' rotation) instead of rescaled.
SETTLE_CASES = [f"{n}+{r}" for n, r in itertools.product(NORMALS, ROLLINGS)] + [
    "hertz+epsd:project",
    "eepa+epsd2:project",
]


@pytest.mark.parametrize("name", SETTLE_CASES)
def test_every_law_settles(name, settle_packing):
    pos, radii = settle_packing
    law_name, _, spring_rotation = name.partition(":")
    normal, rolling = law_name.split("+")
    pad = 1e-3
    sim = gs.Simulation(
        domain=gs.Box(
            lo=tuple(x - pad for x in SETTLE_BOX.lo), hi=tuple(x + pad for x in SETTLE_BOX.hi)
        ),
        contact=_settle_law(normal, rolling, spring_rotation or "rescale"),
        thermo_every=10**9,
        quiet=True,
    )
    sim.add_particles(position=pos, radius=radii, material=SOFT)
    for wall in gs.geometry.box_walls(SETTLE_BOX):
        sim.add_wall(wall)
    energy, overlap = [], []
    for _ in range(SETTLE_CHUNKS):
        sim.run(steps=SETTLE_CHUNK_STEPS)
        th = sim.thermo()
        energy.append(th["kinetic_energy"])
        overlap.append(th["max_overlap_ratio"])
    with sim.particles() as p:
        v = np.array(p.velocity)
        x = np.array(p.position)
        m = np.array(p.mass)
    translational = 0.5 * float(np.sum(m * np.sum(v * v, axis=1)))
    history = " ".join(f"{e:.1e}" for e in energy)
    assert sim.lost_particles == 0 and sim.num_particles == SETTLE_N, (
        f"{name}: lost {sim.lost_particles} particles ({sim.num_particles} left)"
    )
    assert np.all(np.isfinite(x)) and SETTLE_BOX.contains(x).all(), f"{name}: particle escaped"
    peak = max(energy)
    assert energy[-1] < 1e-3 * peak, (
        f"{name}: kinetic energy did not decay by 3 orders: {history} J (per chunk)"
    )
    # Spin about a vertical contact normal is not resisted by any of the laws; translation is.
    assert translational < 1e-6 * peak, (
        f"{name}: translational kinetic energy {translational:.2e} J at the end, peak KE "
        f"{peak:.2e} J (history {history})"
    )
    assert max(overlap) < 0.05, f"{name}: max overlap / radius per chunk {overlap}"
    assert sim.num_contacts() >= SETTLE_N, f"{name}: only {sim.num_contacts()} contacts at rest"


# --------------------------------------------------------------------------- validation

M_A = gs.Material(density=1000.0, youngs_modulus=1e7, poisson_ratio=0.3, name="a")
M_B = gs.Material(density=2000.0, youngs_modulus=2e7, poisson_ratio=0.25, name="b")

INVALID = [
    (lambda: EEPA(unloading_ratio=0.5), r"EEPA\.unloading_ratio must be >= 1.*got 0\.5"),
    (lambda: EEPA(unloading_ratio=math.inf), r"EEPA\.unloading_ratio must be >= 1"),
    (lambda: EEPA(exponent=2), r"EEPA\.exponent must be 1 or 1\.5, got 2"),
    (lambda: EEPA(loading_stiffness=0.0), r"EEPA\.loading_stiffness must be positive"),
    (lambda: EEPA(adhesive_stiffness=-1.0), r"EEPA\.adhesive_stiffness must be non-negative"),
    (lambda: EEPA(pull_off_force=math.nan), r"EEPA\.pull_off_force must be finite"),
    (lambda: EEPA(adhesion_exponent=0.0), r"EEPA\.adhesion_exponent must be positive"),
    (lambda: Linear(normal_stiffness=-1), r"Linear\.normal_stiffness must be positive.*got -1"),
    (lambda: Linear(tangential_stiffness=0), r"Linear\.tangential_stiffness must be positive"),
    (lambda: Linear(characteristic_velocity=0), r"Linear\.characteristic_velocity must be"),
    (lambda: HertzMindlin(restitution=1.5), r"HertzMindlin\.restitution must be in \[0, 1\]"),
    (lambda: HertzMindlin(friction=-0.1), r"HertzMindlin\.friction must be non-negative"),
    (lambda: HertzMindlin(rolling=0.1), r"HertzMindlin\.rolling must be None, CDT, EPSD"),
    (lambda: HertzMindlin(tangential_history="x"), r"tangential_history must be 'total'"),
    (
        lambda: HertzMindlin(spring_rotation="keep"),
        r"HertzMindlin\.spring_rotation must be 'rescale' or 'project', got 'keep'",
    ),
    (lambda: EPSD(-0.1), r"EPSD\.rolling_friction must be non-negative.*got -0\.1"),
    (lambda: EPSD(0.1, -0.3), r"EPSD\.rolling_damping must be non-negative"),
    (lambda: CDT(-1), r"CDT\.rolling_friction must be non-negative"),
    (lambda: EPSD2(-1), r"EPSD2\.rolling_friction must be non-negative"),
    (lambda: Pair(restitution=2), r"Pair\.restitution must be in \[0, 1\], got 2"),
    (lambda: Pair(friction=-1), r"Pair\.friction must be non-negative"),
    (lambda: HertzMindlin(pairs={M_A: Pair()}), r"HertzMindlin\.pairs keys must be"),
    (lambda: HertzMindlin(pairs={(M_A, "wall"): Pair()}), r"HertzMindlin\.pairs keys must be"),
    (lambda: Linear(pairs={(M_A, M_B, None): Pair()}), r"Linear\.pairs keys must be"),
    (lambda: EEPA(pairs={(M_A, None): 0.5}), r"EEPA\.pairs values must be contact\.Pair"),
    (
        lambda: gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(1, 1, 1)), contact="hertz"),
        r"Simulation\.contact must be a grainscale\.contact law",
    ),
]


@pytest.mark.parametrize("make, message", INVALID, ids=[m for _, m in INVALID])
def test_invalid_parameters_are_refused(make, message):
    with pytest.raises(ValueError, match=message):
        make()


# A per-pair override of a law parameter must obey the same constraint as the law's own value
# (otherwise e.g. Pair(unloading_ratio=0.5) would give k2 < k1 for one material pair). It may be
# refused when the law is built or, at the latest, at the first run.
INVALID_PAIR_OVERRIDES = [
    (EEPA, "unloading_ratio", 0.5),
    (EEPA, "loading_stiffness", -1.0),
    (EEPA, "adhesive_stiffness", -1.0),
    (EEPA, "pull_off_force", math.nan),
    (EEPA, "adhesion_exponent", 0.0),
    (Linear, "normal_stiffness", -1.0),
    (Linear, "tangential_stiffness", -1.0),
    (Linear, "characteristic_velocity", 0.0),
]


@pytest.mark.parametrize(
    "law_cls, field, value", INVALID_PAIR_OVERRIDES, ids=[f for _, f, _ in INVALID_PAIR_OVERRIDES]
)
def test_invalid_pair_override_is_refused(law_cls, field, value):
    with pytest.raises(ValueError, match=field):
        law = law_cls(pairs={(M_A, None): Pair(**{field: value})})
        sim = gs.Simulation(
            domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)),
            contact=law,
            gravity=(0.0, 0.0, 0.0),
            time_step=1e-6,
        )
        sim.add_particles(position=[[0.005, 0.005, 0.002]], radius=1e-3, material=M_A)
        sim.add_wall(gs.geometry.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
        sim.run(steps=1)


# --------------------------------------------------------------------------- mixing rules


def test_mixing_rules_interaction_table():
    law = HertzMindlin(restitution=0.5, friction=0.4)
    plain = gs.Material(density=1000.0, youngs_modulus=1e7, poisson_ratio=0.3, name="plain")
    e6 = gs.Material(density=1000.0, youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.6)
    e8 = gs.Material(
        density=1000.0, youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.8, friction=0.2
    )

    def get(lw, a, b, key):
        return lw.interaction(a, b)[key]

    # 3. the law's value when no material sets one (also particle-rigid wall)
    assert get(law, plain, plain, "restitution") == 0.5
    assert get(law, plain, None, "restitution") == 0.5
    assert get(law, plain, None, "friction") == 0.4
    # 2. mean of the two materials' values; the one set when only one sets it
    assert get(law, e6, e8, "restitution") == pytest.approx(0.7, abs=1e-15)
    assert get(law, e8, e6, "restitution") == pytest.approx(0.7, abs=1e-15)
    assert get(law, e6, plain, "restitution") == 0.6
    assert get(law, e8, e6, "friction") == 0.2  # only e8 sets friction
    # a rigid wall has no material: the particle's value, in either argument order
    assert get(law, e8, None, "restitution") == 0.8
    assert get(law, None, e8, "restitution") == 0.8
    # a wall with its own material mixes like a particle
    assert get(law, e6, e8, "restitution") == get(law, e8, e6, "restitution")
    # 1. an explicit pair beats the materials; (a, b) and (b, a) are the same entry; unset
    #    Pair fields fall through to the lower rules
    over = HertzMindlin(
        restitution=0.5,
        friction=0.4,
        pairs={(e6, e8): Pair(restitution=0.9), (e8, None): Pair(friction=0.05)},
    )
    assert get(over, e6, e8, "restitution") == 0.9
    assert get(over, e8, e6, "restitution") == 0.9
    assert get(over, e6, e8, "friction") == 0.2
    assert get(over, e8, None, "friction") == 0.05
    assert get(over, e8, None, "restitution") == 0.8
    assert get(over, None, e8, "friction") == 0.05
    assert get(over, e6, e6, "restitution") == 0.6  # other pairs untouched


def test_mixing_rules_law_specific_fields():
    lin = Linear(
        normal_stiffness=1e5,
        restitution=0.5,
        pairs={(M_A, None): Pair(normal_stiffness=4e5, restitution=0.8)},
    )
    assert lin.interaction(M_A, M_A)["normal_stiffness"] == 1e5
    assert lin.interaction(M_A, None)["normal_stiffness"] == 4e5
    assert lin.interaction(None, M_A)["restitution"] == 0.8
    eepa = EEPA(
        pull_off_force=-1e-4,
        adhesive_stiffness=10.0,
        pairs={(M_A, M_B): Pair(pull_off_force=-3e-4, unloading_ratio=5.0)},
    )
    ab = eepa.interaction(M_B, M_A)
    assert (ab["pull_off_force"], ab["unloading_ratio"], ab["adhesive_stiffness"]) == (
        -3e-4,
        5.0,
        10.0,
    )
    aa = eepa.interaction(M_A, M_A)
    assert (aa["pull_off_force"], aa["unloading_ratio"]) == (-1e-4, 3.0)
    rolling = HertzMindlin(rolling=EPSD(0.1, 0.3))
    rough = gs.Material(density=1000.0, youngs_modulus=1e7, poisson_ratio=0.3, rolling_friction=0.2)
    assert rolling.interaction(M_A, None)["rolling_friction"] == 0.1
    assert rolling.interaction(M_A, None)["rolling_damping"] == 0.3
    assert rolling.interaction(rough, None)["rolling_friction"] == 0.2
    assert rolling.interaction(rough, M_A)["rolling_friction"] == 0.2


# --------------------------------------------------------------------------- behaviour

IMPACT_RADIUS = 1e-3
IMPACT_V0 = 0.5


def _bounce(run_impact, hertz_pair, law, material, other=None, steps_per_contact=1000):
    """Restitution of a Hertz-type impact (sphere on rigid plane, or on sphere ``other``)."""
    pair = hertz_pair(material, IMPACT_RADIUS, other)
    t_c = pair.contact_time(IMPACT_V0)
    res = run_impact(
        law,
        material,
        IMPACT_RADIUS,
        IMPACT_V0,
        time_step=t_c / steps_per_contact,
        duration=3.0 * t_c,
        other=other,
        record_windows=[],
    )
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, "bodies still touching at the end"
    return res.restitution


def test_pair_override_changes_wall_bounce(run_impact, hertz_pair):
    """Pair(restitution=0.8) on (material, None) -> e = 0.8 on the wall, 0.5 sphere-sphere."""
    law = HertzMindlin(restitution=0.5, friction=0.0, pairs={(SOFT, None): Pair(restitution=0.8)})
    e_wall = _bounce(run_impact, hertz_pair, law, SOFT)
    assert abs(e_wall - 0.8) <= TOL_E, f"sphere-wall e_out = {e_wall:.5f}, Pair says 0.8"
    e_pp = _bounce(run_impact, hertz_pair, law, SOFT, other=(SOFT, IMPACT_RADIUS))
    assert abs(e_pp - 0.5) <= TOL_E, f"sphere-sphere e_out = {e_pp:.5f}, law says 0.5"
    # key order (None, material) is the same entry
    law2 = HertzMindlin(restitution=0.5, friction=0.0, pairs={(None, SOFT): Pair(restitution=0.8)})
    e_wall2 = _bounce(run_impact, hertz_pair, law2, SOFT)
    assert abs(e_wall2 - e_wall) <= 1e-12, f"(None, m): {e_wall2:.8f} vs (m, None): {e_wall:.8f}"


def test_material_values_mix_in_behaviour(run_impact, hertz_pair):
    """Material(restitution) beats the law; a rigid wall uses the particle's value; two
    materials collide with the mean."""
    law = HertzMindlin(restitution=0.5, friction=0.0)
    m6 = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.6)
    m8 = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.8)
    e_wall = _bounce(run_impact, hertz_pair, law, m8)
    assert abs(e_wall - 0.8) <= TOL_E, f"m(e=0.8) on rigid wall: e_out = {e_wall:.5f}"
    e_mixed = _bounce(run_impact, hertz_pair, law, m6, other=(m8, IMPACT_RADIUS))
    assert abs(e_mixed - 0.7) <= TOL_E, f"m(0.6) vs m(0.8): e_out = {e_mixed:.5f}, mean 0.7"
    over = HertzMindlin(restitution=0.5, friction=0.0, pairs={(m6, m8): Pair(restitution=0.3)})
    e_over = _bounce(run_impact, hertz_pair, over, m6, other=(m8, IMPACT_RADIUS))
    assert abs(e_over - 0.3) <= TOL_E, f"Pair(0.3) beats materials: e_out = {e_over:.5f}"


def test_pair_override_of_linear_stiffness(run_impact):
    """Pair(normal_stiffness=4 k) for the wall halves the contact duration pi sqrt(m/k)."""
    k = 200.0
    mass = SOFT.density * 4.0 / 3.0 * math.pi * IMPACT_RADIUS**3
    t_c = math.pi * math.sqrt(mass / k)
    durations = {}
    for label, pairs in (("law", {}), ("pair", {(SOFT, None): Pair(normal_stiffness=4 * k)})):
        law = Linear(normal_stiffness=k, restitution=1.0, friction=0.0, pairs=pairs)
        res = run_impact(
            law, SOFT, IMPACT_RADIUS, IMPACT_V0, time_step=t_c / 1000, duration=1.5 * t_c
        )
        durations[label] = res.contact_end_time()
    assert abs(durations["law"] / t_c - 1.0) <= 2e-3, f"k: t_c = {durations['law']:.6e} s"
    ratio = durations["pair"] / durations["law"]
    assert abs(ratio - 0.5) <= 2e-3, f"Pair(4 k): t_c ratio {ratio:.5f}, expected 0.5"


def _pp_pw_laws():
    return {
        "hertz": (HertzMindlin(restitution=0.5, friction=0.0), None),
        "linear": (Linear(normal_stiffness=300.0, restitution=0.5, friction=0.0), 300.0),
        "linear_derived": (Linear(restitution=0.5, friction=0.0, characteristic_velocity=0.5), 0.0),
        "eepa": (EEPA(restitution=0.5, friction=0.0, unloading_ratio=1.0), -1.0),
    }


@pytest.mark.parametrize("name", list(_pp_pw_laws()))
def test_particle_and_wall_contacts_use_the_same_law(name, run_impact, hertz_pair):
    """Equal spheres head-on (centre-of-mass frame) and sphere on a rigid wall: same e.

    The time step is the same fraction of each pair's own contact time, so both runs integrate
    the same dimensionless equation: the two restitutions agree to round-off, and both are 0.5.
    """
    law, k = _pp_pw_laws()[name]
    results = {}
    for label, other in (("wall", None), ("sphere", (SOFT, IMPACT_RADIUS))):
        pair = hertz_pair(SOFT, IMPACT_RADIUS, other)
        if k is None:  # Hertz
            t_c = pair.contact_time(IMPACT_V0)
        elif k > 0:  # linear, given k
            t_c = math.pi * math.sqrt(pair.mass / k)
        elif k == 0:  # linear, k derived with v_c = v0: same delta_max as Hertz
            t_c = math.pi * pair.max_overlap(IMPACT_V0) / IMPACT_V0
        else:  # EEPA k1 = 2 E* R*
            t_c = math.pi * math.sqrt(pair.mass / (2.0 * pair.youngs * pair.radius))
        res = run_impact(
            law,
            SOFT,
            IMPACT_RADIUS,
            IMPACT_V0,
            time_step=t_c / 1000,
            duration=3.0 * t_c,
            other=other,
            record_windows=[],
        )
        assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, f"{name} {label}: still touching"
        results[label] = res.restitution
    e_w, e_s = results["wall"], results["sphere"]
    assert abs(e_w - 0.5) <= TOL_E and abs(e_s - 0.5) <= TOL_E, (
        f"{name}: e_out wall {e_w:.6f}, sphere-sphere {e_s:.6f}, expected 0.5"
    )
    assert abs(e_w - e_s) <= 1e-9, (
        f"{name}: sphere-sphere e_out {e_s:.12f} != sphere-wall e_out {e_w:.12f} "
        f"(diff {e_s - e_w:+.2e})"
    )
