"""Spin at impact: no slip for opposite spins (CASES.md B7) and the Coulomb bound (Test 6 like).

B7: two identical Al-alloy spheres R = 0.1 m, v = +-0.2 m/s (v0 = 0.4 m/s), omega1 = +w a,
omega2 = -w a about an axis a perpendicular to the line of centres, w = (0.2 / R) tan(5 deg i);
mu = 0.4, e = 0.5. The contact-point surface velocities are identical, so after separation
omega' = omega0 and v_t' = 0 exactly (gates 1e-6), while the normal restitution is still 0.5
(gate 2e-3). A sign error in the relative tangential velocity gives slip 2 R w and fails grossly;
co-rotating spins (which do slip) serve as the negative control.

Sphere on a rigid plane with spin (Test 6 like): the tangential force is non-zero and never exceeds
mu F_n+ at any step, and the tangential impulse of a sliding contact never exceeds mu times the
normal impulse (DESIGN.md 2.4).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs

RADIUS = 0.1
V_N = 0.2  # speed of each sphere / of the sphere onto the plane, m/s
MU = 0.4
E = 0.5
STEPS_PER_CONTACT = 1000
# Damped (e = 0.5, tension allowed) contact duration / elastic t_c, CASES.md A3 table.
TC_RATIO_E05 = 1.0934


def spin_of_test6(i: int) -> float:
    """omega0 = (v_n / R) tan(5 deg i), CASES.md B0 Test 6 list (rad/s)."""
    return V_N / RADIUS * math.tan(math.radians(5.0 * i))


def _law():
    return gs.contact.HertzMindlin(restitution=E, friction=MU)


@pytest.fixture(scope="module")
def spin_pair(materials, hertz_pair, run_impact):
    """spin_pair(i, axis, sign2, refine) -> result; omega2 = sign2 * omega1. Cached."""
    store = {}

    def get(i: int, axis=(0.0, 0.0, 1.0), sign2: float = -1.0, refine: int = 1):
        key = (i, tuple(axis), sign2, refine)
        if key not in store:
            mat = materials["al_alloy"]
            v0 = 2.0 * V_N
            tc = hertz_pair(mat, RADIUS, (mat, RADIUS)).contact_time(v0)
            a = np.asarray(axis, float) / np.linalg.norm(axis)
            w = spin_of_test6(i) * a
            store[key] = run_impact(
                _law(),
                mat,
                RADIUS,
                v0,
                time_step=tc / STEPS_PER_CONTACT / refine,
                duration=(TC_RATIO_E05 + 2.0) * tc,
                other=(mat, RADIUS),
                angular_velocity=[w, sign2 * w],
                record_windows=[],
            )
        return store[key]

    return get


AXES = {"z": (0.0, 0.0, 1.0), "oblique_yz": (0.0, 1.0, 1.0)}


@pytest.mark.parametrize("axis", list(AXES))
@pytest.mark.parametrize("i", [1, 5, 9, 13, 17])
def test_opposite_spins_do_not_slip(i, axis, spin_pair):
    res = spin_pair(i, AXES[axis])
    w0 = spin_of_test6(i)
    omega0 = res.angular_velocity[0]
    omega1 = res.angular_velocity[-1]
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, "spheres still in contact at the end"
    for body in (0, 1):
        change = np.linalg.norm(omega1[body] - omega0[body]) / w0
        assert change <= 1e-6, (
            f"i={i} axis={axis} sphere {body + 1}: omega {omega0[body]} -> {omega1[body]} rad/s, "
            f"|omega' - omega0| / omega0 = {change:.3e} > 1e-6"
        )
        vt = res.velocity[-1, body, 1:]  # line of centres is x
        assert np.linalg.norm(vt) <= 1e-6 * RADIUS * w0, (
            f"i={i} axis={axis} sphere {body + 1}: tangential velocity {vt} m/s after "
            f"separation, gate {1e-6 * RADIUS * w0:.3e} m/s"
        )
    assert abs(res.restitution - E) <= 2e-3, (
        f"i={i} axis={axis}: normal restitution {res.restitution:.6f}, expected {E} (gate 2e-3)"
    )


@pytest.mark.parametrize("i", [1, 17])
def test_no_slip_time_step_convergence(i, spin_pair):
    r1, r2 = spin_pair(i, refine=1), spin_pair(i, refine=2)
    de = abs(r1.restitution - r2.restitution)
    assert de < 0.25 * 2e-3, (
        f"i={i}: e_n {r1.restitution:.6f} -> {r2.restitution:.6f} when dt is halved "
        f"(change {de:.2e}, allowed 5e-4)"
    )
    w0 = spin_of_test6(i)
    dw = np.max(np.abs(r1.angular_velocity[-1] - r2.angular_velocity[-1])) / w0
    assert dw < 0.25e-6, f"i={i}: omega' changes by {dw:.2e} omega0 when dt is halved"


def test_co_rotating_spins_slip(spin_pair):
    """Negative control: equal spins (slip 2 R w at the contact) must be changed by friction."""
    i = 9
    res = spin_pair(i, sign2=+1.0)
    w0 = spin_of_test6(i)
    change = np.abs(res.angular_velocity[-1, :, 2] / w0 - 1.0)
    assert np.all(change > 1e-2), (
        f"co-rotating spins w0 = {w0:.4f} rad/s came out as {res.angular_velocity[-1, :, 2]} "
        f"(relative change {change}); friction did not act"
    )
    # Equal and opposite tangential impulses: total tangential momentum stays zero.
    p_t = res.velocity[-1, 0, 1] + res.velocity[-1, 1, 1]
    assert abs(p_t) <= 1e-9 * RADIUS * w0, f"tangential momentum not conserved: {p_t:.3e}"
    assert abs(res.velocity[-1, 0, 1]) > 1e-3 * RADIUS * w0, "no tangential velocity acquired"


@pytest.fixture(scope="module")
def spin_on_plane(materials, hertz_pair, run_impact):
    store = {}

    def get(i: int):
        if i not in store:
            mat = materials["al_alloy"]
            tc = hertz_pair(mat, RADIUS).contact_time(V_N)
            store[i] = run_impact(
                _law(),
                mat,
                RADIUS,
                V_N,
                time_step=tc / STEPS_PER_CONTACT,
                duration=(TC_RATIO_E05 + 1.0) * tc,
                angular_velocity=[(0.0, spin_of_test6(i), 0.0)],
                record_windows=[(0.0, 1.3 * tc)],
                record_contacts=True,
            )
        return store[i], mat

    return get


@pytest.mark.parametrize("i", [1, 9, 17])
def test_tangential_force_bounded_by_coulomb(i, spin_on_plane):
    res, mat = spin_on_plane(i)
    dt = res.time_step
    n = res.contact_normal
    f = res.contact_force
    fn = np.einsum("ij,ij->i", f, n)
    ft = f - fn[:, None] * n
    ft_mag = np.linalg.norm(ft, axis=1)
    fn_plus = np.clip(fn, 0.0, None)
    scale = float(fn.max())
    in_contact = res.num_contacts > 0
    assert in_contact.sum() > 100, f"only {in_contact.sum()} contact steps recorded"
    excess = ft_mag - MU * fn_plus
    k = int(np.argmax(excess))
    assert excess[k] <= 1e-9 * scale, (
        f"i={i}: |F_t| = {ft_mag[k]:.6e} N > mu F_n+ = {MU * fn_plus[k]:.6e} N at t = "
        f"{res.t[k]:.4e} s (F_n = {fn[k]:.6e} N)"
    )
    assert ft_mag.max() >= 0.05 * MU * scale, (
        f"i={i}: tangential force stays tiny (max |F_t| = {ft_mag.max():.3e} N, "
        f"mu max F_n = {MU * scale:.3e} N): spin does not produce friction"
    )

    # Impulses (velocity Verlet applies each evaluated force for one full dt).
    j_t = np.linalg.norm(ft.sum(axis=0) * dt)
    j_n_plus = fn_plus.sum() * dt
    assert j_t <= MU * j_n_plus * (1.0 + 1e-9), (
        f"i={i}: tangential impulse {j_t:.6e} N s > mu * normal impulse {MU * j_n_plus:.6e} N s"
    )
    # Reported contact forces are the applied forces: they integrate to the momentum change.
    m = mat.density * 4.0 / 3.0 * math.pi * RADIUS**3
    dp = m * (res.velocity[-1, 0] - res.velocity[0, 0])
    j = f.sum(axis=0) * dt
    assert np.linalg.norm(dp - j) <= 1e-6 * np.linalg.norm(dp), (
        f"i={i}: m dv = {dp} N s but the recorded contact forces integrate to {j} N s"
    )
    if i == 17:
        # v_t/v_n = tan(85 deg) = 11.4: gross sliding throughout, |F_t| = mu F_n+ at every step.
        assert j_t >= 0.99 * MU * j_n_plus, (
            f"i={i}: sliding contact transmits only {j_t / j_n_plus:.4f} of the normal impulse "
            f"(expected mu = {MU})"
        )
        # Test 6 gross sliding: spin loss = mu J_n+ R / I (lever arm R - delta/2 ~ R, 1e-3).
        inertia = 0.4 * m * RADIUS**2
        dw = res.angular_velocity[0, 0, 1] - res.angular_velocity[-1, 0, 1]
        dw_ref = j_t * RADIUS / inertia
        assert abs(dw / dw_ref - 1.0) <= 1e-3, (
            f"i={i}: spin drop {dw:.6e} rad/s, expected mu J_n+ R / I = {dw_ref:.6e} rad/s"
        )
        # Friction acts against the slip of the contact point (-R w ex): +ex on the sphere.
        assert res.velocity[-1, 0, 0] > 0, (
            f"i={i}: sphere pushed the wrong way {res.velocity[-1, 0]}"
        )
