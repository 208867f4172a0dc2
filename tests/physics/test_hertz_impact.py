"""Elastic Hertz normal impact (CASES.md A1, Chung & Ooi Tests 1 and 2 = B1, B2).

e = 1 (no damping), friction 0, no gravity, bodies exactly touching at t = 0.
B1: two identical spheres R = 10 mm, v = +-10 m/s (v0 = 20 m/s).
B2: sphere R = 0.1 m on a rigid plane (Plane(material=None)), v0 = 0.2 m/s.
The reference is the A1 closed form evaluated here; the B1/B2 table values are only used to
check that closed form. Gates (A1): F_max, delta_max within 0.5 %, t_c within
max(0.5 %, 2 dt), |v_out/v_in - 1| <= 1e-4, |F - (4/3) E* sqrt(R*) delta^1.5| <= 0.5 % F_max on
loading and unloading; rerun at dt/2 and require every gated quantity to move by less than a
quarter of its tolerance (CASES.md section 0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs

STEPS_PER_CONTACT = 500  # dt = t_c / 500 (CASES.md section 0 asks for dt <= t_c / 200)

TOL_PEAK = 5e-3
TOL_TC_REL = 5e-3
TOL_EXIT = 1e-4
TOL_BRANCH = 5e-3

# name: (material, radius m, v0 m/s, two spheres?, table: m kg, E* Pa, delta_max m, F_max N, t_c s)
CASES = {
    "B1-glass": (
        "glass",
        0.010,
        20.0,
        True,
        (1.172861e-2, 2.500000e10, 274.11e-6, 10.697e3, 40.34e-6),
    ),
    "B1-limestone": (
        "limestone",
        0.010,
        20.0,
        True,
        (1.047198e-2, 1.066667e10, 368.30e-6, 7.108e3, 54.20e-6),
    ),
    "B2-al_alloy": (
        "al_alloy_t2",
        0.10,
        0.2,
        False,
        (11.30554, 7.692308e10, 49.72e-6, 11.370e3, 731.7e-6),
    ),
    "B2-mg_alloy": (
        "mg_alloy",
        0.10,
        0.2,
        False,
        (7.539822, 4.558405e10, 52.12e-6, 7.233e3, 767.1e-6),
    ),
}


def _pair(case, materials, hertz_pair):
    mat_name, radius, _v0, two, _table = CASES[case]
    mat = materials[mat_name]
    return hertz_pair(mat, radius, (mat, radius) if two else None)


@pytest.fixture(scope="module")
def impact(materials, hertz_pair, run_impact):
    """impact(case, refine) -> (result, reference pair); refine = 1 (dt) or 2 (dt/2). Cached."""
    cache = {}

    def get(case: str, refine: int = 1):
        if (case, refine) not in cache:
            mat_name, radius, v0, two, _table = CASES[case]
            mat = materials[mat_name]
            pair = _pair(case, materials, hertz_pair)
            tc = pair.contact_time(v0)
            dt = tc / STEPS_PER_CONTACT / refine
            law = gs.contact.HertzMindlin(restitution=1.0, friction=0.0)
            res = run_impact(
                law,
                mat,
                radius,
                v0,
                time_step=dt,
                duration=3.2 * tc,  # >= 2 t_c after separation (CASES.md B0)
                other=(mat, radius) if two else None,
                record_windows=[(0.0, 1.3 * tc)],
                record_contacts=True,
            )
            cache[(case, refine)] = (res, pair)
        return cache[(case, refine)]

    return get


def _measure(res, pair):
    """Gated quantities of one run, relative to the A1 closed form."""
    v0 = res.v_in
    loading = (res.overlap > 0) & (res.approach_speed > 0)
    unloading = (res.overlap > 0) & (res.approach_speed <= 0)
    fmax_ref = pair.max_force(v0)
    dev = np.abs(res.force_n - pair.force(res.overlap)) / fmax_ref
    return {
        "delta_max": float(res.overlap.max()) / pair.max_overlap(v0) - 1.0,
        "f_max": float(res.force_n.max()) / fmax_ref - 1.0,
        "t_c": res.contact_end_time() / pair.contact_time(v0) - 1.0,
        "exit": res.v_out / v0 - 1.0,
        "branch_loading": float(dev[loading].max()) if loading.any() else math.nan,
        "branch_unloading": float(dev[unloading].max()) if unloading.any() else math.nan,
        "branch_all": float(dev.max()),
    }


@pytest.mark.parametrize("case", list(CASES))
def test_closed_form_matches_table(case, materials, hertz_pair):
    """Self-check of the A1 closed form (and of gs.timestep.hertz_contact_time) vs B1/B2."""
    mat_name, radius, v0, two, (m, estar, dmax, fmax, tc) = CASES[case]
    mat = materials[mat_name]
    pair = _pair(case, materials, hertz_pair)
    mass = mat.density * 4.0 / 3.0 * math.pi * radius**3
    got = {
        "m": (mass, m),
        "E*": (pair.youngs, estar),
        "delta_max": (pair.max_overlap(v0), dmax),
        "F_max": (pair.max_force(v0), fmax),
        "F_max (1.25 m* v0^2 / delta_max)": (1.25 * pair.mass * v0**2 / pair.max_overlap(v0), fmax),
        "t_c": (pair.contact_time(v0), tc),
        "t_c (2.868266 form)": (
            2.868266 * (pair.mass**2 / (pair.radius * pair.youngs**2 * v0)) ** 0.2,
            tc,
        ),
    }
    for name, (value, table) in got.items():
        assert abs(value / table - 1.0) <= 1e-3, (
            f"{case} {name}: closed form {value:.6g}, table {table:.6g}"
        )

    api = gs.timestep.hertz_contact_time(mat, radius, v0, other=(mat, radius) if two else None)
    assert abs(api / pair.contact_time(v0) - 1.0) <= 1e-5, (
        f"{case}: gs.timestep.hertz_contact_time = {api:.8g} s, A1 closed form "
        f"{pair.contact_time(v0):.8g} s"
    )


@pytest.mark.parametrize("case", list(CASES))
def test_peak_overlap_and_force(case, impact):
    res, pair = impact(case)
    q = _measure(res, pair)
    v0 = res.v_in
    assert abs(q["delta_max"]) <= TOL_PEAK, (
        f"{case}: delta_max = {res.overlap.max():.6e} m, A1 {pair.max_overlap(v0):.6e} m "
        f"(rel. error {q['delta_max']:+.3e}, gate {TOL_PEAK})"
    )
    assert abs(q["f_max"]) <= TOL_PEAK, (
        f"{case}: F_max = {res.force_n.max():.6e} N, A1 {pair.max_force(v0):.6e} N "
        f"(rel. error {q['f_max']:+.3e}, gate {TOL_PEAK})"
    )


@pytest.mark.parametrize("case", list(CASES))
def test_contact_time(case, impact):
    res, pair = impact(case)
    tc_ref = pair.contact_time(res.v_in)
    tc = res.contact_end_time()
    tol = max(TOL_TC_REL * tc_ref, 2.0 * res.time_step)
    assert math.isfinite(tc), f"{case}: contact end not found ({res.notes})"
    assert abs(tc - tc_ref) <= tol, (
        f"{case}: t_c = {tc:.6e} s, A1 {tc_ref:.6e} s (diff {tc - tc_ref:+.3e} s, "
        f"gate {tol:.3e} s, dt = {res.time_step:.3e} s)"
    )


@pytest.mark.parametrize("case", list(CASES))
def test_exit_speed(case, impact):
    res, _pair = impact(case)
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, (
        f"{case}: still in contact at the end (overlap {res.overlap[-1]:.3e} m, "
        f"{res.num_contacts[-1]} contacts)"
    )
    ratio = res.v_out / res.v_in
    assert abs(ratio - 1.0) <= TOL_EXIT, (
        f"{case}: v_out/v_in = {ratio:.10f} (v_out {res.v_out:.10g} m/s, v_in {res.v_in} m/s, "
        f"gate |ratio - 1| <= {TOL_EXIT})"
    )


@pytest.mark.parametrize("case", list(CASES))
def test_force_on_hertz_curve(case, impact):
    """F(delta) lies on (4/3) E* sqrt(R*) delta^1.5 while loading and while unloading."""
    res, pair = impact(case)
    q = _measure(res, pair)
    for branch in ("branch_loading", "branch_unloading"):
        assert q[branch] <= TOL_BRANCH, (
            f"{case}: {branch} max |F - K delta^1.5| = {q[branch]:.3e} F_max (gate {TOL_BRANCH})"
        )
    assert q["branch_all"] <= TOL_BRANCH, (
        f"{case}: force off the Hertz curve (incl. zero force when apart) by "
        f"{q['branch_all']:.3e} F_max"
    )


@pytest.mark.parametrize("case", list(CASES))
def test_contacts_report_matches_state(case, impact):
    """sim.contacts() overlap/force agree with the particle state (no gravity, one contact)."""
    res, pair = impact(case)
    dmax = pair.max_overlap(res.v_in)
    fmax = pair.max_force(res.v_in)
    in_contact = res.overlap > 1e-9 * dmax
    apart = res.overlap < -1e-9 * dmax
    assert np.all(res.num_contacts[in_contact] == 1), (
        f"{case}: num_contacts during contact = {np.unique(res.num_contacts[in_contact])}"
    )
    assert np.all(res.num_contacts[apart] == 0), (
        f"{case}: num_contacts while apart = {np.unique(res.num_contacts[apart])}"
    )
    err_overlap = np.max(
        np.abs(res.contact_overlap - np.clip(res.overlap, 0, None))[in_contact | apart]
    )
    assert err_overlap <= 1e-6 * dmax, (
        f"{case}: contacts()['overlap'] differs from r1 + r2 - |x1 - x2| by {err_overlap:.3e} m"
    )
    err_force = np.max(np.linalg.norm(res.contact_force - res.force[:, 0], axis=1))
    assert err_force <= 1e-9 * fmax, (
        f"{case}: contacts()['force'] differs from the particle force by {err_force:.3e} N"
    )
    n_expected = np.array([0.0, 0.0, 1.0]) if case.startswith("B2") else np.array([-1.0, 0.0, 0.0])
    err_n = np.max(np.abs(res.contact_normal[in_contact] - n_expected))
    assert err_n <= 1e-9, f"{case}: contact normal (from body 2 to body 1) off by {err_n:.3e}"


@pytest.mark.parametrize("case", list(CASES))
def test_time_step_convergence(case, impact):
    """CASES.md section 0: halving dt moves every gated quantity by < 1/4 of its tolerance."""
    res1, pair = impact(case, 1)
    res2, _ = impact(case, 2)
    q1, q2 = _measure(res1, pair), _measure(res2, pair)
    tc_ref = pair.contact_time(res1.v_in)
    tol = {
        "delta_max": TOL_PEAK,
        "f_max": TOL_PEAK,
        "t_c": max(TOL_TC_REL, 2.0 * res1.time_step / tc_ref),
        "exit": TOL_EXIT,
        "branch_loading": TOL_BRANCH,
        "branch_unloading": TOL_BRANCH,
    }
    for name, t in tol.items():
        change = abs(q1[name] - q2[name])
        assert change < 0.25 * t, (
            f"{case}: {name} changes by {change:.3e} from dt = {res1.time_step:.3e} s to dt/2 "
            f"({q1[name]:+.3e} -> {q2[name]:+.3e}); allowed {0.25 * t:.3e}"
        )
