"""EEPA (bilinear elasto-plastic adhesive) single contact (CASES.md A7).

Two spheres R = 1 mm, E = 10 MPa, nu = 0.3, rho = 1000 kg/m^3 (E* = E / (2 (1 - nu^2)),
R* = R / 2), g = 0, friction 0, restitution 1 (beta = 0: no damping). The overlap follows a
prescribed quasi-static path: every step both centres are placed on the x axis at the wanted
overlap with zero velocity, then one step is run (dt = 1e-12 s, so the drift 0.5 F/m dt^2 is far
below the round-off of the positions); the pair force and overlap are read from sim.contacts().

Model (cpp/contact/normal_models.hpp, DESIGN.md 2.4), n = 1, chi = 1:
  loading F = f0 + k1 d; unloading/reloading F = f0 + k2 (d - dp); adhesive F = f0 - k_adh d;
  dp = (1 - k1/k2) d_max, k2 = 3 k1 -> dp = (2/3) d_max; k1 = 2 E* R* when loading_stiffness=None.
Path 0 -> d_max -> d_u -> 1.5 d_max -> 0 with dp < d_u < d_max. Closed-form checks (1e-10
relative): virgin slope k1; unloading slope k2 and F = f0 at d = dp; reloading retraces the k2 line
up to d_max, then continues on k1; second unloading with dp = (2/3)(1.5 d_max); adhesive branch
F = f0 - k_adh d where k2 (d - dp) < -k_adh d. Pull-off (the definition the engine documents: the
minimum of F, where the unloading line meets the adhesive branch):
  k2 (d* - dp) = -k_adh d*  ->  d* = k2 dp / (k2 + k_adh),  F_min = f0 - k_adh d*.
Also the exponent 1.5 branch algebra (dp^1.5 = (1 - k1/k2) d_max^1.5) on a shorter path, and
dynamic impacts: damped linear-elastic EEPA (unloading_ratio = 1) gives e_out = e within 2e-3
(CASES.md A2 with k = k1), and the undamped hysteresis loop (k2 = 3 k1, no adhesion) gives
e_out = sqrt(k1/k2) (elastic energy returned on the k2 line: k1^2 d_max^2 / (2 k2)).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import grainscale as gs

RADIUS = 1e-3
MATERIAL = gs.Material(density=1000.0, youngs_modulus=10e6, poisson_ratio=0.3, name="eepa_soft")
E_STAR = MATERIAL.youngs_modulus / (2.0 * (1.0 - MATERIAL.poisson_ratio**2))  # two spheres
R_STAR = RADIUS / 2.0
K1_DERIVED = 2.0 * E_STAR * R_STAR  # n = 1
K1_DERIVED_15 = 4.0 / 3.0 * E_STAR * math.sqrt(R_STAR)  # n = 1.5
RATIO = 3.0  # k2 / k1
PULL_OFF = -1e-3  # f0 (N)
D_MAX = 1e-5  # first maximum overlap (m), 2 % of R*
D_UNLOAD = 0.8 * D_MAX  # dp = 0.667 d_max < d_u < d_max
QS_TIME_STEP = 1e-12
SEGMENT_POINTS = 41

TOL_ALGEBRA = 1e-10
TOL_E = 2e-3


# --------------------------------------------------------------------------- quasi-static driver


class QuasiStatic:
    """Two spheres on the x axis whose overlap is prescribed step by step."""

    def __init__(self, law: gs.contact.EEPA) -> None:
        half = 8.0 * RADIUS
        self.sim = gs.Simulation(
            domain=gs.Box(lo=(-half, -half, -half), hi=(half, half, half)),
            contact=law,
            gravity=(0.0, 0.0, 0.0),
            time_step=QS_TIME_STEP,
            thermo_every=10**9,
            record_contacts=True,
        )
        x = np.array([[-2.0 * RADIUS, 0.0, 0.0], [2.0 * RADIUS, 0.0, 0.0]])
        self.ids = [
            int(self.sim.add_particles(position=x[k : k + 1], radius=RADIUS, material=MATERIAL)[0])
            for k in range(2)
        ]

    def apply(self, d: float) -> tuple[float, float]:
        """Set overlap d, run one step; return (overlap, normal force on sphere 0) reported."""
        with self.sim.particles() as p:
            row = {int(k): r for r, k in enumerate(p.id)}
            p.position[row[self.ids[0]]] = (-(RADIUS - 0.5 * d), 0.0, 0.0)
            p.position[row[self.ids[1]]] = (RADIUS - 0.5 * d, 0.0, 0.0)
            p.velocity[:] = 0.0
            p.angular_velocity[:] = 0.0
        self.sim.run(steps=1)
        c = self.sim.contacts()
        assert len(c["id_i"]) == 1, f"overlap {d:.6e} m: {len(c['id_i'])} contacts, expected 1"
        sign = 1.0 if int(c["id_i"][0]) == self.ids[0] else -1.0
        force_n = float(np.dot(c["force"][0], c["normal"][0]))
        # The particle force (no gravity, one contact) must be the same pair force.
        with self.sim.particles() as p:
            row = {int(k): r for r, k in enumerate(p.id)}
            f0 = np.array(p.force[row[self.ids[0]]])
        normal0 = sign * np.asarray(c["normal"][0])
        assert abs(float(np.dot(f0, normal0)) - force_n) <= 1e-12 * max(abs(force_n), 1e-3), (
            f"particle force {f0} disagrees with the contact force {force_n:.6e} N"
        )
        return float(c["overlap"][0]), force_n

    def follow(self, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out = np.array([self.apply(float(d)) for d in path])
        for d_set, d_got in zip(path, out[:, 0], strict=True):
            assert abs(d_got - d_set) <= 1e-12 * D_MAX, (
                f"reported overlap {d_got:.15e} differs from the prescribed {d_set:.15e}"
            )
        return out[:, 0], out[:, 1]


def _assert_close(label: str, d: np.ndarray, got: np.ndarray, ref: np.ndarray, scale: float):
    """|F - F_ref| <= 1e-10 max(|F_ref|, scale) at every point."""
    err = np.abs(got - ref) / np.maximum(np.abs(ref), scale)
    k = int(np.argmax(err))
    assert err[k] <= TOL_ALGEBRA, (
        f"{label}: at d = {d[k]:.6e} m F = {got[k]:.12e} N, closed form {ref[k]:.12e} N "
        f"(rel. error {err[k]:.2e} > {TOL_ALGEBRA}; worst of {d.size} points)"
    )


def _slope(d: np.ndarray, f: np.ndarray) -> float:
    return float((f[-1] - f[0]) / (d[-1] - d[0]))


def _assert_rel(label: str, got: float, ref: float) -> None:
    assert abs(got / ref - 1.0) <= TOL_ALGEBRA, (
        f"{label}: {got:.12e}, closed form {ref:.12e} (rel. diff {got / ref - 1.0:+.2e}, "
        f"gate {TOL_ALGEBRA})"
    )


def _law(k1: float | None, k_adh: float, exponent: float = 1.0) -> gs.contact.EEPA:
    return gs.contact.EEPA(
        exponent=exponent,
        loading_stiffness=k1,
        unloading_ratio=RATIO,
        restitution=1.0,
        friction=0.0,
        adhesive_stiffness=k_adh,
        pull_off_force=PULL_OFF,
    )


# --------------------------------------------------------------------------- n = 1 full path


@pytest.mark.parametrize("k1_given", [None, 3000.0], ids=["k1_derived_2EsRs", "k1_explicit_3000"])
def test_eepa_linear_loading_path(k1_given):
    k1 = K1_DERIVED if k1_given is None else k1_given
    k2 = RATIO * k1
    k_adh = 0.5 * k1
    f0 = PULL_OFF
    scale = abs(f0)
    qs = QuasiStatic(_law(k1_given, k_adh))
    tag = f"EEPA n=1 k1={k1:.6g}"

    # 1. virgin loading 0 -> d_max: F = f0 + k1 d, slope k1.
    d1, f1 = qs.follow(np.linspace(D_MAX / (SEGMENT_POINTS - 1), D_MAX, SEGMENT_POINTS - 1))
    _assert_close(f"{tag} virgin loading", d1, f1, f0 + k1 * d1, scale)
    _assert_rel(f"{tag} virgin loading slope", _slope(d1, f1), k1)

    # 2. unloading d_max -> d_u: F = f0 + k2 (d - dp), dp = (2/3) d_max; slope k2 = 3 k1.
    dp = (1.0 - k1 / k2) * D_MAX
    _assert_rel(f"{tag} dp / d_max", dp / D_MAX, 2.0 / 3.0)
    d2, f2 = qs.follow(np.linspace(D_MAX, D_UNLOAD, SEGMENT_POINTS))
    _assert_close(f"{tag} unloading", d2, f2, f0 + k2 * (d2 - dp), scale)
    _assert_rel(f"{tag} unloading slope", _slope(d2, f2), k2)
    _assert_rel(f"{tag} unloading slope / k1", _slope(d2, f2) / k1, RATIO)
    # F = f0 at d = dp on the unloading line (zero of F - f0 of the measured line).
    d_zero = d2[-1] - (f2[-1] - f0) / _slope(d2, f2)
    _assert_rel(f"{tag} overlap where the unloading line reaches f0", d_zero, dp)

    # 3. reloading d_u -> 1.5 d_max: the k2 line up to d_max (same forces as on unloading),
    #    then the virgin line F = f0 + k1 d.
    up = np.linspace(D_UNLOAD, D_MAX, SEGMENT_POINTS)
    d3, f3 = qs.follow(up)
    _assert_close(f"{tag} reloading below d_max", d3, f3, f0 + k2 * (d3 - dp), scale)
    _assert_close(f"{tag} reloading retraces unloading", d3, f3, f2[::-1], scale)
    d_max2 = 1.5 * D_MAX
    d4, f4 = qs.follow(np.linspace(D_MAX, d_max2, SEGMENT_POINTS)[1:])
    _assert_close(f"{tag} loading beyond d_max", d4, f4, f0 + k1 * d4, scale)
    _assert_rel(f"{tag} loading slope beyond d_max", _slope(d4, f4), k1)

    # 4. second unloading 1.5 d_max -> 0: dp2 = (2/3)(1.5 d_max); the adhesive branch takes over
    #    where k2 (d - dp2) < -k_adh d; minimum (pull-off) f0 - k_adh d* at d* = k2 dp2/(k2+k_adh).
    dp2 = (1.0 - k1 / k2) * d_max2
    _assert_rel(f"{tag} dp2 / (1.5 d_max)", dp2 / d_max2, 2.0 / 3.0)
    d_star = k2 * dp2 / (k2 + k_adh)
    f_pull = f0 - k_adh * d_star
    down = np.linspace(d_max2, d_max2 / (SEGMENT_POINTS - 1), SEGMENT_POINTS - 1)
    down = np.sort(np.concatenate([down, [dp2, d_star]]))[::-1]
    d5, f5 = qs.follow(down)
    unload = f0 + k2 * (d5 - dp2)
    adhesive = f0 - k_adh * d5
    on_line = k2 * (d5 - dp2) >= -k_adh * d5
    assert 0 < np.count_nonzero(~on_line) < d5.size, "path must cross into the adhesive branch"
    _assert_close(
        f"{tag} second unloading (k2 line)", d5[on_line], f5[on_line], unload[on_line], scale
    )
    _assert_close(f"{tag} adhesive branch", d5[~on_line], f5[~on_line], adhesive[~on_line], scale)
    _assert_rel(f"{tag} second unloading slope", _slope(d5[on_line], f5[on_line]), k2)
    _assert_rel(f"{tag} adhesive slope", _slope(d5[~on_line], f5[~on_line]), -k_adh)
    k_dp = int(np.argmin(np.abs(d5 - dp2)))
    assert abs(f5[k_dp] - f0) <= TOL_ALGEBRA * abs(f0), (
        f"{tag}: F(dp2 = {dp2:.6e} m) = {f5[k_dp]:.12e} N, expected f0 = {f0:.12e} N"
    )
    k_min = int(np.argmin(f5))
    _assert_rel(f"{tag} pull-off force (minimum of F)", float(f5[k_min]), f_pull)
    _assert_rel(f"{tag} overlap at pull-off", float(d5[k_min]), d_star)

    # Whole loop: the force never leaves the envelope f0 + k1 d (no branch above loading).
    d_all = np.concatenate([d1, d2, d3, d4, d5])
    f_all = np.concatenate([f1, f2, f3, f4, f5])
    assert np.all(f_all <= f0 + k1 * d_all + TOL_ALGEBRA * np.maximum(np.abs(f_all), scale)), (
        "a force lies above the virgin loading line"
    )


def test_eepa_contact_ends_at_separation():
    """With adhesion the force is f0 - k_adh d down to d -> 0+, and zero once apart."""
    k1 = K1_DERIVED
    qs = QuasiStatic(_law(None, 0.5 * k1))
    qs.follow(np.linspace(D_MAX / 10, D_MAX, 10))
    d, f = qs.follow(np.array([1e-9]))
    _assert_close("EEPA adhesive branch near d = 0", d, f, PULL_OFF - 0.5 * k1 * d, abs(PULL_OFF))
    with qs.sim.particles() as p:
        row = {int(k): r for r, k in enumerate(p.id)}
        p.position[row[qs.ids[0]]] = (-RADIUS - 1e-7, 0.0, 0.0)
        p.position[row[qs.ids[1]]] = (RADIUS + 1e-7, 0.0, 0.0)
    qs.sim.run(steps=1)
    assert qs.sim.num_contacts() == 0
    with qs.sim.particles() as p:
        assert np.all(np.asarray(p.force) == 0.0), f"force after separation: {np.asarray(p.force)}"


# --------------------------------------------------------------------------- n = 1.5


@pytest.mark.parametrize("k1_given", [None, 2e5], ids=["k1_derived", "k1_explicit"])
def test_eepa_exponent_15_branches(k1_given):
    """n = 1.5: F = f0 + k1 d^1.5 on loading, f0 + k2 (d^1.5 - dp^1.5) on unloading/reloading,
    dp^1.5 = (1 - k1/k2) d_max^1.5; adhesive f0 - k_adh d where it is larger."""
    n = 1.5
    k1 = K1_DERIVED_15 if k1_given is None else k1_given
    k2 = RATIO * k1
    k_adh = 0.3 * k1 * math.sqrt(D_MAX)  # N/m, same order as the unloading slope near dp
    f0 = PULL_OFF
    scale = abs(f0)
    qs = QuasiStatic(_law(k1_given, k_adh, exponent=n))
    tag = f"EEPA n=1.5 k1={k1:.6g}"

    d1, f1 = qs.follow(np.linspace(D_MAX / 20, D_MAX, 20))
    _assert_close(f"{tag} loading", d1, f1, f0 + k1 * d1**n, scale)
    dpn = (1.0 - k1 / k2) * D_MAX**n
    dp = dpn ** (1.0 / n)
    _assert_rel(f"{tag} dp / d_max", dp / D_MAX, (2.0 / 3.0) ** (2.0 / 3.0))

    # unload to below dp, reload past d_max, unload to zero
    d2, f2 = qs.follow(np.concatenate([np.linspace(D_MAX, 0.5 * D_MAX, 21), [dp]]))
    ref2 = np.maximum(f0 + k2 * (d2**n - dpn), f0 - k_adh * d2)
    _assert_close(f"{tag} unloading", d2, f2, ref2, scale)
    assert abs(f2[-1] - f0) <= TOL_ALGEBRA * abs(f0), (
        f"{tag}: F(dp = {dp:.6e} m) = {f2[-1]:.12e} N, expected f0 = {f0:.12e} N"
    )
    d3, f3 = qs.follow(np.linspace(0.5 * D_MAX, 1.2 * D_MAX, 29))
    below = d3 <= D_MAX
    ref3 = np.where(below, np.maximum(f0 + k2 * (d3**n - dpn), f0 - k_adh * d3), f0 + k1 * d3**n)
    _assert_close(f"{tag} reloading", d3, f3, ref3, scale)
    dpn2 = (1.0 - k1 / k2) * (1.2 * D_MAX) ** n
    d4, f4 = qs.follow(np.linspace(1.2 * D_MAX, D_MAX / 40, 48))
    ref4 = np.maximum(f0 + k2 * (d4**n - dpn2), f0 - k_adh * d4)
    assert np.any(f0 - k_adh * d4 > f0 + k2 * (d4**n - dpn2)), "path must reach the adhesive branch"
    _assert_close(f"{tag} final unloading", d4, f4, ref4, scale)


# --------------------------------------------------------------------------- dynamic impacts


def _eepa_impact(run_impact, law, k1: float, refine: int = 1):
    """Sphere on a rigid plane (E* = E/(1 - nu^2), R* = R, m* = m), v0 = 0.5 m/s."""
    mass = MATERIAL.density * 4.0 / 3.0 * math.pi * RADIUS**3
    t_c = math.pi * math.sqrt(mass / k1)
    dt = t_c / 500 / refine
    return run_impact(law, MATERIAL, RADIUS, 0.5, time_step=dt, duration=3.0 * t_c), t_c


def test_eepa_damped_linear_elastic_impact(run_impact):
    """unloading_ratio = 1, no adhesion, restitution 0.5: a linear spring-dashpot with k = k1."""
    e = 0.5
    k1 = 2.0 * MATERIAL.youngs_modulus / (1.0 - MATERIAL.poisson_ratio**2) * RADIUS  # wall
    law = gs.contact.EEPA(restitution=e, friction=0.0, unloading_ratio=1.0)
    results = [_eepa_impact(run_impact, law, k1, refine)[0] for refine in (1, 2)]
    res = results[0]
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, "sphere did not leave the wall"
    assert abs(res.restitution - e) <= TOL_E, (
        f"EEPA(unloading_ratio=1, restitution={e}): e_out = {res.restitution:.6f} "
        f"(diff {res.restitution - e:+.2e}, gate {TOL_E})"
    )
    de = abs(results[1].restitution - res.restitution)
    assert de < 0.25 * TOL_E, f"e_out {res.restitution:.6f} -> {results[1].restitution:.6f} at dt/2"
    # Linear elastic with k1: duration pi / omega_d.
    zeta = abs(math.log(e)) / math.sqrt(math.log(e) ** 2 + math.pi**2)
    mass = MATERIAL.density * 4.0 / 3.0 * math.pi * RADIUS**3
    t_ref = math.pi / (math.sqrt(k1 / mass) * math.sqrt(1.0 - zeta**2))
    t_c = res.contact_end_time()
    assert abs(t_c - t_ref) <= 2.0 * res.time_step, (
        f"EEPA damped impact: t_c = {t_c:.6e} s, expected pi/omega_d = {t_ref:.6e} s "
        f"({(t_c - t_ref) / res.time_step:+.2f} dt)"
    )


def test_eepa_hysteresis_restitution(run_impact):
    """Undamped, no adhesion, k2 = 3 k1: e_out = sqrt(k1/k2) = 0.57735 (plastic dissipation)."""
    k1 = 2.0 * MATERIAL.youngs_modulus / (1.0 - MATERIAL.poisson_ratio**2) * RADIUS
    law = gs.contact.EEPA(restitution=1.0, friction=0.0, unloading_ratio=RATIO)
    results = [_eepa_impact(run_impact, law, k1, refine)[0] for refine in (1, 2)]
    e_ref = math.sqrt(1.0 / RATIO)
    res = results[0]
    assert res.overlap[-1] < 0 and res.num_contacts[-1] == 0, "sphere did not leave the wall"
    assert abs(res.restitution - e_ref) <= TOL_E, (
        f"EEPA(unloading_ratio={RATIO}, e=1): e_out = {res.restitution:.6f}, expected "
        f"sqrt(k1/k2) = {e_ref:.6f} (diff {res.restitution - e_ref:+.2e}, gate {TOL_E})"
    )
    de = abs(results[1].restitution - res.restitution)
    assert de < 0.25 * TOL_E, f"e_out {res.restitution:.6f} -> {results[1].restitution:.6f} at dt/2"
    # Permanent deformation: after the maximum the force vanishes once d < dp = (2/3) d_max
    # (k_adh = 0, f0 = 0), while the spheres still overlap.
    k_max = int(np.argmax(res.overlap))
    dp = (1.0 - 1.0 / RATIO) * float(res.overlap[k_max])
    after = np.arange(res.overlap.size) > k_max
    free = after & (res.overlap > 0) & (res.overlap < dp * (1.0 - 1e-3))
    assert np.count_nonzero(free) > 10, "no records between dp and separation"
    assert np.all(res.force_n[free] == 0.0), (
        f"force below dp after unloading: max |F| = {np.max(np.abs(res.force_n[free])):.3e} N"
    )
