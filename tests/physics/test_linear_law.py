"""Linear spring-dashpot law: exact restitution and contact duration (CASES.md A2, A1, B3).

A2: sphere R = 2.5 mm, rho = 4000 kg/m^3 (the Al oxide material of B0; its E and nu do not enter
with a given k_n) on a rigid plane (Plane(material=None): m* = m), Linear(normal_stiffness=1e6,
friction=0, restitution=e), v0 = 1 m/s, g = 0, dt = t_c / 500 with t_c = pi / omega_d.
Model-exact expectations, m* d'' + c d' + k d = 0, zeta = |ln e| / sqrt(ln^2 e + pi^2):
* tension allowed (limit_force=False), contact ends at d = 0: e_out = e_in, t_c = pi / omega_d;
* no tension (limit_force=True), contact ends when F = k d + c d' first reaches 0:
  e_out = e_F = exp(-zeta phi / sqrt(1 - zeta^2)), t_c = phi / omega_d.
Gates: |e_out - e_ref| <= 1e-3, |t_c - t_ref| <= 2 dt, e_out independent of v0 in {0.1, 1, 10}
to 1e-4; the closed forms reproduce the CASES.md A2 table to 1e-4.
B3 with the linear law: Al oxide and cast iron spheres (R = 2.5 mm) on a rigid plane, v_n = 3.9 m/s,
k_n derived from E*, R*, m* and characteristic_velocity = 3.9 (LIGGGHTS hooke):
|e_out - e_in| <= 2e-3; for e = 1, F_max = 0.8 F_max,Hertz and t_c = 1.067380 t_c,Hertz (A1
"Linear" line) within 0.5 %.
Section 0: every gated quantity is rerun at dt/2 and must move by less than a quarter of its
tolerance (for t_c: a quarter of 2 dt of the coarse run).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from cases_tables import TABLE_E, TABLE_E_F, TABLE_W0TC_NO_TENSION, TABLE_W0TC_TENSION, TABLE_ZETA

import grainscale as gs

RADIUS = 2.5e-3
STIFFNESS = 1e6  # N/m
V0 = 1.0
STEPS_PER_CONTACT = 1000  # dt = t_c / 1000 (<= t_c/200, CASES.md section 0): the dashpot sees
# the half-step velocity, so e converges at first order in dt

TOL_E = 1e-3
TOL_TC_STEPS = 2.0  # |t_c - t_ref| <= 2 dt
TOL_V_INDEPENDENCE = 1e-4
TOL_TABLE = 1e-4


CONVERGENCE_E = (0.1, 0.5, 0.9)  # representative subset rerun at dt/2
VELOCITY_E = (0.2, 0.5, 0.8)
VELOCITIES = (0.1, 1.0, 10.0)

# B3 with the linear law.
B3_V0 = 3.9
B3_MATERIALS = ("al_oxide", "cast_iron")
B3_E = (0.2, 0.4, 0.6, 0.8, 1.0)
TOL_B3_E = 2e-3
TOL_B3_ELASTIC = 5e-3
LINEAR_TO_HERTZ_FORCE = 0.8  # CASES.md A1
LINEAR_TO_HERTZ_DURATION = 1.067380  # CASES.md A1

LIMIT_FORCE = pytest.mark.parametrize("limit_force", [False, True], ids=["tension", "no_tension"])


# --------------------------------------------------------------------------- closed forms (A2)


def damping_ratio(e: float) -> float:
    """zeta = |ln e| / sqrt(ln^2 e + pi^2) (0 for e = 1)."""
    if e >= 1.0:
        return 0.0
    log_e = abs(math.log(e))
    return log_e / math.sqrt(log_e**2 + math.pi**2)


def end_phase(e: float, limit_force: bool) -> float:
    """omega_d t_c: pi (contact ends at d = 0) or phi (contact ends at F = 0), CASES.md A2."""
    z = damping_ratio(e)
    if not limit_force or z == 0.0:
        return math.pi
    s = math.sqrt(1.0 - z * z)
    if z < 1.0 / math.sqrt(2.0):
        return math.pi - math.atan(2.0 * z * s / (1.0 - 2.0 * z * z))
    if z > 1.0 / math.sqrt(2.0):
        return math.atan(2.0 * z * s / (2.0 * z * z - 1.0))
    return math.pi / 2.0


def expected_restitution(e: float, limit_force: bool) -> float:
    """e (tension allowed) or e_F = exp(-zeta phi / sqrt(1 - zeta^2)) (no tension)."""
    if not limit_force:
        return e
    z = damping_ratio(e)
    return math.exp(-z * end_phase(e, True) / math.sqrt(1.0 - z * z))


def omega0_duration(e: float, limit_force: bool) -> float:
    """omega_0 t_c = (omega_d t_c) / sqrt(1 - zeta^2)."""
    return end_phase(e, limit_force) / math.sqrt(1.0 - damping_ratio(e) ** 2)


def hooke_stiffness(youngs: float, radius: float, mass: float, v_c: float) -> float:
    """LIGGGHTS hooke k_n = 16/15 sqrt(R*) E* (15 m* v_c^2 / (16 sqrt(R*) E*))^(1/5)."""
    a = math.sqrt(radius) * youngs
    return 16.0 / 15.0 * a * (15.0 * mass * v_c**2 / (16.0 * a)) ** 0.2


# --------------------------------------------------------------------------- runs


def _sphere_mass(material: gs.Material, radius: float) -> float:
    return material.density * 4.0 / 3.0 * math.pi * radius**3


@pytest.fixture(scope="module")
def a2_bounce(materials, run_impact):
    """a2_bounce(e, limit_force, v0, refine) -> (ImpactResult, omega_0, t_ref). Cached.

    dt = (pi / omega_d) / (500 refine) for both variants; t_ref is the expected duration.
    """
    store = {}
    mat = materials["al_oxide"]  # rho = 4000 kg/m^3
    mass = _sphere_mass(mat, RADIUS)
    omega0 = math.sqrt(STIFFNESS / mass)

    def get(e: float, limit_force: bool, v0: float = V0, refine: int = 1):
        key = (e, limit_force, v0, refine)
        if key not in store:
            omega_d = omega0 * math.sqrt(1.0 - damping_ratio(e) ** 2)
            dt = math.pi / omega_d / STEPS_PER_CONTACT / refine
            t_ref = omega0_duration(e, limit_force) / omega0
            law = gs.contact.Linear(
                normal_stiffness=STIFFNESS, friction=0.0, restitution=e, limit_force=limit_force
            )
            window = [(0.8 * t_ref, 1.2 * t_ref)]
            duration = 2.0 * math.pi / omega_d
            res = run_impact(
                law, mat, RADIUS, v0, time_step=dt, duration=duration, record_windows=window
            )
            store[key] = (res, omega0, t_ref)
        return store[key]

    return get


def _duration(res, limit_force: bool) -> float:
    return res.force_end_time() if limit_force else res.contact_end_time()


def _check_separated(res, what: str) -> None:
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, (
        f"{what}: bodies not separated at the end (overlap {res.overlap[-1]:.3e} m, "
        f"{res.num_contacts[-1]} contacts)"
    )


# --------------------------------------------------------------------------- A2


def test_closed_forms_match_cases_table():
    """zeta, omega_0 t_c and e_F computed from the A2 formulas reproduce the CASES.md table."""
    for k, e in enumerate(TABLE_E):
        z = damping_ratio(e)
        assert abs(z - TABLE_ZETA[k]) <= 1e-5, f"zeta({e}) = {z:.6f}, table {TABLE_ZETA[k]}"
        checks = (
            ("omega0 t_c (tension)", omega0_duration(e, False), TABLE_W0TC_TENSION[k]),
            ("e_F (no tension)", expected_restitution(e, True), TABLE_E_F[k]),
            ("omega0 t_c (no tension)", omega0_duration(e, True), TABLE_W0TC_NO_TENSION[k]),
        )
        for label, got, ref in checks:
            assert abs(got - ref) <= TOL_TABLE, (
                f"e_in={e}: {label} = {got:.6f}, table {ref} (diff {got - ref:+.1e}, "
                f"gate {TOL_TABLE})"
            )
    # Limits: e = 1 is undamped (no-tension and tension coincide), e_F > e for e < 1.
    assert expected_restitution(1.0, True) == 1.0
    assert all(expected_restitution(e, True) > e for e in TABLE_E)


@pytest.mark.parametrize("e_in", TABLE_E)
@LIMIT_FORCE
def test_restitution(e_in, limit_force, a2_bounce):
    res, _, _ = a2_bounce(e_in, limit_force)
    _check_separated(res, f"e_in={e_in} limit_force={limit_force}")
    e_ref = expected_restitution(e_in, limit_force)
    e_out = res.restitution
    assert abs(e_out - e_ref) <= TOL_E, (
        f"linear k={STIFFNESS:g} limit_force={limit_force} e_in={e_in}: e_out = {e_out:.6f}, "
        f"expected {e_ref:.6f} (diff {e_out - e_ref:+.2e}, gate {TOL_E})"
    )


@pytest.mark.parametrize("e_in", TABLE_E)
@LIMIT_FORCE
def test_contact_duration(e_in, limit_force, a2_bounce):
    res, omega0, t_ref = a2_bounce(e_in, limit_force)
    t_c = _duration(res, limit_force)
    assert math.isfinite(t_c), (
        f"limit_force={limit_force} e_in={e_in}: end of contact not found near "
        f"t_ref = {t_ref:.6e} s: {res.notes}"
    )
    dt = res.time_step
    assert abs(t_c - t_ref) <= TOL_TC_STEPS * dt, (
        f"limit_force={limit_force} e_in={e_in}: t_c = {t_c:.6e} s (omega0 t_c = "
        f"{omega0 * t_c:.5f}), expected {t_ref:.6e} s ({omega0 * t_ref:.5f}); "
        f"diff {(t_c - t_ref) / dt:+.2f} dt, gate {TOL_TC_STEPS} dt"
    )


@pytest.mark.parametrize("e_in", CONVERGENCE_E)
@LIMIT_FORCE
def test_time_step_convergence(e_in, limit_force, a2_bounce):
    """Section 0: halving dt moves e_out by < TOL_E / 4 and t_c by < (2 dt) / 4."""
    res1, _, _ = a2_bounce(e_in, limit_force, refine=1)
    res2, _, _ = a2_bounce(e_in, limit_force, refine=2)
    e_ref = expected_restitution(e_in, limit_force)
    de = abs(res1.restitution - res2.restitution)
    assert de < 0.25 * TOL_E, (
        f"limit_force={limit_force} e_in={e_in}: e_out - e_ref = "
        f"{res1.restitution - e_ref:+.2e} at dt = t_c/{STEPS_PER_CONTACT}, "
        f"{res2.restitution - e_ref:+.2e} at dt/2; change {de:.2e} >= {0.25 * TOL_E:.1e} "
        "(quarter of the gate)"
    )
    dt = res1.time_step
    dtc = abs(_duration(res1, limit_force) - _duration(res2, limit_force))
    assert dtc < 0.25 * TOL_TC_STEPS * dt, (
        f"limit_force={limit_force} e_in={e_in}: t_c changes by {dtc / dt:.3f} dt when dt is "
        f"halved (allowed {0.25 * TOL_TC_STEPS} dt)"
    )


@pytest.mark.parametrize("e_in", VELOCITY_E)
@LIMIT_FORCE
def test_velocity_independence(e_in, limit_force, a2_bounce):
    got = {v0: a2_bounce(e_in, limit_force, v0=v0)[0].restitution for v0 in VELOCITIES}
    spread = max(got.values()) - min(got.values())
    text = ", ".join(f"v0={v0}: {e:.8f}" for v0, e in got.items())
    assert spread <= TOL_V_INDEPENDENCE, (
        f"limit_force={limit_force} e_in={e_in}: e_out depends on v0 ({text}); "
        f"spread {spread:.2e} > {TOL_V_INDEPENDENCE}"
    )
    e_ref = expected_restitution(e_in, limit_force)
    worst = max(abs(e - e_ref) for e in got.values())
    assert worst <= TOL_E, f"limit_force={limit_force} e_in={e_in}: expected {e_ref:.6f}, {text}"


def test_tension_variants_differ(a2_bounce):
    """Negative control: damping dissipates, and the two variants are distinguishable."""
    tension, _, _ = a2_bounce(0.5, False)
    clamped, _, _ = a2_bounce(0.5, True)
    assert tension.restitution < 0.52, f"e_in=0.5 gave e_out = {tension.restitution:.4f}"
    assert np.min(tension.force_n) < 0.0, "tension-allowed damped contact never shows F_n < 0"
    assert np.min(clamped.force_n) >= 0.0, (
        f"limit_force=True shows a tensile force {np.min(clamped.force_n):.3e} N"
    )
    assert clamped.restitution - tension.restitution > 0.04, (
        f"e_out(no tension) = {clamped.restitution:.4f} vs e_out(tension) = "
        f"{tension.restitution:.4f}: expected 0.5503 vs 0.5"
    )


# --------------------------------------------------------------------------- B3, linear law


@pytest.fixture(scope="module")
def b3_bounce(materials, hertz_pair, run_impact):
    """b3_bounce(material, e, refine) -> (ImpactResult, HertzPair, k_n). Cached."""
    store = {}

    def get(mat_name: str, e: float, refine: int = 1):
        key = (mat_name, e, refine)
        if key not in store:
            mat = materials[mat_name]
            pair = hertz_pair(mat, RADIUS)
            k_n = hooke_stiffness(pair.youngs, pair.radius, pair.mass, B3_V0)
            omega_d = math.sqrt(k_n / pair.mass) * math.sqrt(1.0 - damping_ratio(e) ** 2)
            t_c = math.pi / omega_d
            law = gs.contact.Linear(
                normal_stiffness=None,
                characteristic_velocity=B3_V0,
                friction=0.0,
                restitution=e,
            )
            res = run_impact(
                law,
                mat,
                RADIUS,
                B3_V0,
                time_step=t_c / STEPS_PER_CONTACT / refine,
                duration=2.0 * t_c,
            )
            store[key] = (res, pair, k_n)
        return store[key]

    return get


def test_hooke_stiffness_reproduces_hertz_overlap(materials, hertz_pair):
    """The derived k_n gives the Hertz delta_max at v = v_c: k_n delta_max^2 = m* v_c^2."""
    for name in B3_MATERIALS:
        pair = hertz_pair(materials[name], RADIUS)
        k_n = hooke_stiffness(pair.youngs, pair.radius, pair.mass, B3_V0)
        d_lin = B3_V0 * math.sqrt(pair.mass / k_n)
        d_hertz = pair.max_overlap(B3_V0)
        assert abs(d_lin / d_hertz - 1.0) <= 1e-12, f"{name}: {d_lin:.6e} vs {d_hertz:.6e}"


@pytest.mark.parametrize("e_in", B3_E)
@pytest.mark.parametrize("mat_name", B3_MATERIALS)
def test_b3_restitution(mat_name, e_in, b3_bounce):
    res, _, _ = b3_bounce(mat_name, e_in)
    _check_separated(res, f"B3 linear {mat_name} e_in={e_in}")
    assert abs(res.restitution - e_in) <= TOL_B3_E, (
        f"B3 linear {mat_name} e_in={e_in}: e_out = {res.restitution:.6f} "
        f"(diff {res.restitution - e_in:+.2e}, gate {TOL_B3_E})"
    )
    res2, _, _ = b3_bounce(mat_name, e_in, refine=2)
    de = abs(res.restitution - res2.restitution)
    assert de < 0.25 * TOL_B3_E, (
        f"B3 linear {mat_name} e_in={e_in}: e_out {res.restitution:.6f} -> "
        f"{res2.restitution:.6f} at dt/2 (change {de:.2e} >= {0.25 * TOL_B3_E:.1e})"
    )


@pytest.mark.parametrize("mat_name", B3_MATERIALS)
def test_b3_elastic_peak_force_and_duration(mat_name, b3_bounce):
    """e = 1: F_max = 0.8 F_max,Hertz, t_c = 1.067380 t_c,Hertz, delta_max = delta_max,Hertz."""
    values = {}
    for refine in (1, 2):
        res, pair, _ = b3_bounce(mat_name, 1.0, refine)
        t_c = res.contact_end_time()
        assert math.isfinite(t_c), f"B3 linear {mat_name}: no end of contact found: {res.notes}"
        values[refine] = {
            "F_max / F_max,Hertz": (
                float(np.max(res.force_n)) / pair.max_force(B3_V0),
                LINEAR_TO_HERTZ_FORCE,
            ),
            "t_c / t_c,Hertz": (t_c / pair.contact_time(B3_V0), LINEAR_TO_HERTZ_DURATION),
            "delta_max / delta_max,Hertz": (
                float(np.max(res.overlap)) / pair.max_overlap(B3_V0),
                1.0,
            ),
        }
    for label, (got, ref) in values[1].items():
        assert abs(got / ref - 1.0) <= TOL_B3_ELASTIC, (
            f"B3 linear {mat_name} e=1: {label} = {got:.6f}, expected {ref:.6f} "
            f"(rel. diff {got / ref - 1.0:+.2e}, gate {TOL_B3_ELASTIC})"
        )
        fine = values[2][label][0]
        assert abs(fine - got) < 0.25 * TOL_B3_ELASTIC * ref, (
            f"B3 linear {mat_name} e=1: {label} {got:.6f} -> {fine:.6f} at dt/2"
        )
