"""Rolling resistance of a single sphere on a plane: EPSD, CDT, EPSD2 (CASES.md A6).

Set-up (Ai et al. 2011; parameters of LIGGGHTS-PFM ``epsd_rollFric/tc1``, ``tc2``): sphere
R = 5 mm, rho = 1056 kg/m^3, E = 40 MPa, nu = 0.49, e = 0.9, mu = 0.8, mu_r = 0.2, eta_r = 0.3,
dt = 1e-5 s, g = 9.81 m/s^2, on a plane wall of the *same* material (not rigid:
E* = E/(2(1 - nu^2))). The sphere is dropped from 1 um above the plane and settles for 0.1 s (the
settled overlap is checked against the static Hertz overlap with that E*); then it gets
v0 = 1 m/s along +x and omega0 = 0.
An incline of angle alpha is modelled by tilting gravity, g (-sin alpha, 0, -cos alpha) with the
plane normal +z, so "uphill" is +x.

Closed form (A6; static F_n = m g cos alpha): slip phase until v = R omega, then pure rolling with
deceleration (5/7) g (sin alpha + mu_r cos alpha). It is recomputed below and checked against the
tabulated numbers.

"Stop": the first time the forward velocity v_x drops to V_STOP = 1e-4 m/s (interpolated between
records 0.5 ms apart); the stop position is x there. With EPSD the stretched rolling spring makes
the sphere rock back by ~4 um (|v| up to ~2 mm/s, damped by eta_r in a few ms), so "|v| below
1e-4 and staying below" is only reached ~15 ms (3 % of t_stop) later and is used for the at-rest
checks, not for the stop time. The rocking decays at rate eta_r sqrt(k_r / I_r) ~ mu_r, so with
mu_r = 0.1 |omega| < 1e-3 rad/s takes ~70 ms. At rest therefore means, over the window
[t_stop + 0.1 s, t_stop + 0.3 s]:
|v| < 1e-4 m/s, |omega| < 1e-3 rad/s, no drift of the mean position, and any residual rocking
dies out (no sign-alternating creep).

CDT (constant torque -mu_r R F_n w/|w|) cannot hold a sphere at rest: with velocity Verlet a
residual |omega| < dt M/(2 I) is trapped for ever while the torque flips sign every step (the
half-step omega alternates in sign) and the sphere creeps. The CDT test asserts this defect
quantitatively against the EPSD run; that is why EPSD exists.

Gates (A6): stop position within 1 % (or 0.5 R), stop time within 2 %; every gated quantity moves by
less than a quarter of its tolerance when dt is halved (CASES.md section 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache

import numpy as np
import pytest

import grainscale as gs

RADIUS = 5e-3
DENSITY = 1056.0
YOUNGS = 40e6
POISSON = 0.49
RESTITUTION = 0.9
FRICTION = 0.8
ROLLING_DAMPING = 0.3
DT = 1e-5
G = 9.81
V0 = 1.0
INCLINE = 10.0  # degrees

DROP_GAP = 1e-6  # sphere released this far above the plane (m)
SETTLE_STEPS = 10_000  # 0.1 s
RECORD_EVERY = 50  # steps between records at DT (0.5 ms); scaled when dt is refined
V_STOP = 1e-4  # m/s
REST_DELAY = 0.1  # s after the stop before the at-rest window (EPSD rocking decays)
REST_WINDOW = 0.2  # s

TOL_X = 0.01  # stop position, relative (or 0.5 R)
TOL_T = 0.02  # stop time, relative
TOL_ACCEL = 0.02
W_REST = 1e-3  # rad/s
DRIFT_REST = 1e-8  # m: change of the mean position across the at-rest window
DECAY_REST = 1e-3  # max|omega| late / early in the at-rest window

MASS = DENSITY * 4.0 / 3.0 * math.pi * RADIUS**3
E_STAR = YOUNGS / (2.0 * (1.0 - POISSON**2))  # sphere on a plane of the same material

# CASES.md A6 tables: mu_r -> (t_stop, x_stop) on the flat plane; incline 10 deg, mu_r = 0.2.
TABLE_FLAT = {0.2: (0.5097, 0.1884), 0.1: (1.0194, 0.3698), 0.05: (2.0387, 0.7336)}
TABLE_FLAT_SLIP = (0.04432, 0.65217, 0.03661)  # mu_r = 0.2: t1, v1, x1
TABLE_INCLINE = (0.04180, 0.60574, 2.5969, 0.2750, 0.1042)  # t1, v1, a_roll, t_stop, x_stop
TABLE_INCLINE_ACCEL = {0.1: 0.52671, 0.15: 0.18167}  # rolling down from rest


# ----------------------------------------------------------------------------- closed form


@dataclass(frozen=True)
class ClosedForm:
    t1: float  # end of the slip phase (s)
    v1: float  # velocity then (m/s)
    x1: float  # distance then (m)
    a_roll: float  # rolling deceleration (m/s^2, positive)
    t_stop: float
    x_stop: float


def closed_form(mu_r: float, incline_deg: float = 0.0, v0: float = V0) -> ClosedForm:
    """Launch along +x (uphill) with omega0 = 0, CASES.md A6 (F_n = m g cos alpha, I = 2/5 m R^2).

    Slip: dv/dt = -(mu g_n + g_s), R domega/dt = 2.5 (mu - mu_r) g_n until v = R omega;
    rolling: dv/dt = -(5/7)(g_s + mu_r g_n).
    """
    a = math.radians(incline_deg)
    gn, gs_ = G * math.cos(a), G * math.sin(a)
    decel_slip = FRICTION * gn + gs_
    t1 = v0 / (gs_ + 3.5 * FRICTION * gn - 2.5 * mu_r * gn)
    v1 = v0 - decel_slip * t1
    x1 = v0 * t1 - 0.5 * decel_slip * t1**2
    a_roll = 5.0 / 7.0 * (gs_ + mu_r * gn)
    return ClosedForm(t1, v1, x1, a_roll, t1 + v1 / a_roll, x1 + v1**2 / (2.0 * a_roll))


def rolling_down_acceleration(mu_r: float, incline_deg: float = INCLINE) -> float:
    """(5/7) g (sin alpha - mu_r cos alpha), the pure-rolling acceleration down the slope."""
    a = math.radians(incline_deg)
    return 5.0 / 7.0 * G * (math.sin(a) - mu_r * math.cos(a))


def static_overlap(incline_deg: float = 0.0) -> float:
    """Hertz overlap under m g cos alpha with E* = E / (2 (1 - nu^2)), R* = R."""
    fn = MASS * G * math.cos(math.radians(incline_deg))
    return (fn / (4.0 / 3.0 * E_STAR * math.sqrt(RADIUS))) ** (2.0 / 3.0)


# ----------------------------------------------------------------------------- simulation


@dataclass(frozen=True)
class Run:
    """A sphere settled on the plane, then (optionally) launched; records since the launch.

    x is the displacement along +x from the launch point, v = v_x, w = omega_y (positive for
    rolling along +x), torque = torque_y of the last force evaluation (total, N m). The fine_*
    arrays hold every step of the last ``fine_steps`` steps.
    """

    model: str
    mu_r: float
    incline_deg: float
    time_step: float
    settled_overlap: float
    settled_vz: float
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    fine_t: np.ndarray
    fine_w: np.ndarray
    fine_torque: np.ndarray

    @property
    def label(self) -> str:
        return f"{self.model} mu_r={self.mu_r} incline={self.incline_deg} deg dt={self.time_step}"


def _rolling_model(model: str, mu_r: float):
    if model == "epsd":
        return gs.contact.EPSD(mu_r, ROLLING_DAMPING)
    if model == "epsd2":
        return gs.contact.EPSD2(mu_r)
    if model == "cdt":
        return gs.contact.CDT(mu_r)
    raise ValueError(model)


@cache
def simulate(
    model: str,
    mu_r: float,
    incline_deg: float = 0.0,
    launch: bool = True,
    duration: float = 0.85,
    refine: int = 1,
    fine_steps: int = 0,
) -> Run:
    """Settle, launch with v0 = +x V0 (if ``launch``), run ``duration`` s; dt = DT / refine."""
    dt = DT / refine
    a = math.radians(incline_deg)
    material = gs.Material(density=DENSITY, youngs_modulus=YOUNGS, poisson_ratio=POISSON)
    law = gs.contact.HertzMindlin(
        restitution=RESTITUTION, friction=FRICTION, rolling=_rolling_model(model, mu_r)
    )
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.5, -0.05, -0.05), hi=(1.0, 0.05, 0.05)),
        contact=law,
        gravity=(-G * math.sin(a), 0.0, -G * math.cos(a)),
        time_step=dt,
        quiet=True,
    )
    pid = int(
        sim.add_particles(
            position=[[0.0, 0.0, RADIUS + DROP_GAP]], radius=RADIUS, material=material
        )[0]
    )
    sim.add_wall(gs.geometry.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=material))

    def state() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        with sim.particles(writable=False) as p:
            k = int(np.nonzero(p.id == pid)[0][0])
            return (
                np.array(p.position[k]),
                np.array(p.velocity[k]),
                np.array(p.angular_velocity[k]),
                np.array(p.torque[k]),
            )

    sim.run(steps=SETTLE_STEPS * refine)
    pos, vel, _, _ = state()
    settled_overlap = RADIUS - float(pos[2])
    settled_vz = float(vel[2])
    if launch:
        with sim.particles() as p:
            k = int(np.nonzero(p.id == pid)[0][0])
            p.velocity[k] = (V0, 0.0, 0.0)
            p.angular_velocity[k] = (0.0, 0.0, 0.0)
    t0, x0 = sim.time, float(pos[0])

    every = RECORD_EVERY * refine
    total = int(round(duration / dt))
    coarse = total - fine_steps
    rec: list[tuple[float, float, float, float]] = [(0.0, 0.0, float(vel[0]), 0.0)]
    if launch:
        rec[0] = (0.0, 0.0, V0, 0.0)
    done = 0
    while done < coarse:
        n = min(every, coarse - done)
        sim.run(steps=n)
        done += n
        pos, vel, w, _ = state()
        rec.append((sim.time - t0, float(pos[0]) - x0, float(vel[0]), float(w[1])))
    fine: list[tuple[float, float, float]] = []
    for _ in range(fine_steps):
        sim.run(steps=1)
        _, _, w, tq = state()
        fine.append((sim.time - t0, float(w[1]), float(tq[1])))
    r = np.array(rec)
    f = np.array(fine).reshape(-1, 3)
    return Run(
        model=model,
        mu_r=mu_r,
        incline_deg=incline_deg,
        time_step=dt,
        settled_overlap=settled_overlap,
        settled_vz=settled_vz,
        t=r[:, 0],
        x=r[:, 1],
        v=r[:, 2],
        w=r[:, 3],
        fine_t=f[:, 0],
        fine_w=f[:, 1],
        fine_torque=f[:, 2],
    )


def stop_point(run: Run) -> tuple[float, float]:
    """(t, x) where the forward velocity first drops to V_STOP, interpolated between records."""
    below = np.nonzero(run.v <= V_STOP)[0]
    if below.size == 0 or below[0] == 0:
        raise AssertionError(
            f"{run.label}: no forward stop (v_x = {run.v[0]:.4g} m/s at t = 0, "
            f"{run.v[-1]:.4g} m/s at t = {run.t[-1]:.4g} s, threshold {V_STOP} m/s)"
        )
    k = int(below[0])
    f = (run.v[k - 1] - V_STOP) / (run.v[k - 1] - run.v[k])
    t = run.t[k - 1] + f * (run.t[k] - run.t[k - 1])
    x = run.x[k - 1] + f * (run.x[k] - run.x[k - 1])
    return float(t), float(x)


@dataclass(frozen=True)
class Rest:
    """At-rest metrics over [t_from, t_to]; the quarters are the first and last 25 %."""

    t_from: float
    t_to: float
    v_max: float
    w_max: float
    band: float  # max x - min x
    drift: float  # mean x (last quarter) - mean x (first quarter)
    w_early: float  # max |omega| in the first quarter
    w_late: float  # max |omega| in the last quarter
    w_rms_late: float

    @property
    def decay(self) -> float:
        return self.w_late / self.w_early if self.w_early > 0 else 0.0

    def __str__(self) -> str:
        return (
            f"window [{self.t_from:.4f}, {self.t_to:.4f}] s: max|v| = {self.v_max:.3e} m/s, "
            f"max|omega| = {self.w_max:.3e} rad/s, x band = {self.band:.3e} m, "
            f"drift = {self.drift:.3e} m, max|omega| first/last quarter = {self.w_early:.3e} / "
            f"{self.w_late:.3e} rad/s"
        )


def rest_metrics(run: Run, t_from: float, t_to: float) -> Rest:
    sel = (run.t >= t_from) & (run.t <= t_to)
    if sel.sum() < 40 or run.t[-1] < t_to - 1e-9:
        raise AssertionError(
            f"{run.label}: run ends at {run.t[-1]:.4f} s, at-rest window [{t_from:.4f}, "
            f"{t_to:.4f}] s not covered"
        )
    t, x, v, w = run.t[sel], run.x[sel], run.v[sel], run.w[sel]
    q = max(1, t.size // 4)
    return Rest(
        t_from=t_from,
        t_to=t_to,
        v_max=float(np.max(np.abs(v))),
        w_max=float(np.max(np.abs(w))),
        band=float(np.ptp(x)),
        drift=float(np.mean(x[-q:]) - np.mean(x[:q])),
        w_early=float(np.max(np.abs(w[:q]))),
        w_late=float(np.max(np.abs(w[-q:]))),
        w_rms_late=float(np.sqrt(np.mean(w[-q:] ** 2))),
    )


def rest_after_stop(run: Run) -> Rest:
    t_stop, _ = stop_point(run)
    return rest_metrics(run, t_stop + REST_DELAY, t_stop + REST_DELAY + REST_WINDOW)


def check_stop(run: Run, ref: ClosedForm) -> str:
    """Assert the A6 stop gates; returns a summary line."""
    t_stop, x_stop = stop_point(run)
    dx, dt_rel = x_stop - ref.x_stop, t_stop / ref.t_stop - 1.0
    summary = (
        f"{run.label}: stop t = {t_stop:.5f} s (ref {ref.t_stop:.5f}, {100 * dt_rel:+.3f} %), "
        f"x = {x_stop:.5f} m (ref {ref.x_stop:.5f}, {100 * dx / ref.x_stop:+.3f} %)"
    )
    assert abs(dx) <= max(TOL_X * ref.x_stop, 0.5 * RADIUS), summary + " -- position gate 1 %"
    assert abs(dt_rel) <= TOL_T, summary + " -- time gate 2 %"
    return summary


def check_at_rest(run: Run) -> Rest:
    """A6 after-stop gates: |v| < V_STOP, |omega| < W_REST, no drift, residual rocking dies out."""
    t_stop, x_stop = stop_point(run)
    after = run.t >= t_stop
    excursion = float(np.max(np.abs(run.x[after] - x_stop)))
    assert excursion < 0.01 * RADIUS, (
        f"{run.label}: moved up to {excursion:.3e} m from the stop point after stopping "
        f"(gate 0.01 R = {0.01 * RADIUS:.1e} m)"
    )
    rest = rest_after_stop(run)
    msg = f"{run.label} after the stop (excursion from x_stop {excursion:.2e} m), {rest}"
    assert rest.v_max < V_STOP, msg + f" -- |v| must stay below {V_STOP} m/s"
    assert rest.w_max < W_REST, msg + f" -- |omega| must stay below {W_REST} rad/s"
    assert abs(rest.drift) < DRIFT_REST, msg + f" -- creep: |drift| must be < {DRIFT_REST} m"
    assert rest.w_late <= max(DECAY_REST * rest.w_early, 1e-12), (
        msg + f" -- residual rocking must decay by {DECAY_REST} across the window"
    )
    return rest


# ----------------------------------------------------------------------------- closed form vs table


@pytest.mark.parametrize("mu_r", sorted(TABLE_FLAT))
def test_closed_form_matches_table_flat(mu_r):
    ref = closed_form(mu_r)
    t_tab, x_tab = TABLE_FLAT[mu_r]
    assert abs(ref.t_stop - t_tab) <= 6e-5, f"mu_r={mu_r}: t_stop {ref.t_stop:.6f} vs {t_tab}"
    assert abs(ref.x_stop - x_tab) <= 6e-5, f"mu_r={mu_r}: x_stop {ref.x_stop:.6f} vs {x_tab}"
    if mu_r == 0.2:
        got = (ref.t1, ref.v1, ref.x1)
        for g, tab, name in zip(got, TABLE_FLAT_SLIP, ("t1", "v1", "x1"), strict=True):
            assert abs(g - tab) <= 6e-6, f"mu_r=0.2 flat: {name} {g:.6f} vs table {tab}"


def test_closed_form_matches_table_incline():
    ref = closed_form(0.2, INCLINE)
    got = (ref.t1, ref.v1, ref.a_roll, ref.t_stop, ref.x_stop)
    for g, tab, name in zip(
        got, TABLE_INCLINE, ("t1", "v1", "a_roll", "t_stop", "x_stop"), strict=True
    ):
        assert abs(g - tab) <= 0.6 * 10.0 ** (-len(repr(tab).split(".")[1])), (
            f"incline 10 deg, mu_r=0.2: {name} = {g:.6f}, table {tab}"
        )
    for mu_r, tab in TABLE_INCLINE_ACCEL.items():
        a = rolling_down_acceleration(mu_r)
        assert abs(a - tab) <= 6e-6, f"mu_r={mu_r}: rolling-down acceleration {a:.6f} vs {tab}"
    assert math.tan(math.radians(INCLINE)) < 0.2, "tan 10 deg must be below mu_r = 0.2"
    assert math.tan(math.radians(INCLINE)) > 0.1, "tan 10 deg must exceed mu_r = 0.1"


# ----------------------------------------------------------------------------- settling


def test_settled_overlap_is_static_hertz_with_wall_material():
    """Wall of the sphere's material: E* = E / (2 (1 - nu^2)) (a rigid wall would give 0.63x)."""
    run = simulate("epsd", 0.2, duration=0.85)
    ref = static_overlap()
    assert abs(run.settled_overlap / ref - 1.0) <= 0.01, (
        f"settled overlap {run.settled_overlap:.6e} m, static Hertz {ref:.6e} m "
        f"(rigid wall would give {ref * 2 ** (-2 / 3):.6e} m)"
    )
    assert abs(run.settled_vz) < 1e-4, f"sphere not settled: v_z = {run.settled_vz:.3e} m/s"


# ----------------------------------------------------------------------------- flat plane (tc1)


@pytest.mark.parametrize(("mu_r", "duration"), [(0.2, 0.85), (0.1, 1.35)])
def test_epsd_flat_stop(mu_r, duration):
    run = simulate("epsd", mu_r, duration=duration)
    print(check_stop(run, closed_form(mu_r)))
    print(check_at_rest(run))


def test_epsd_flat_slip_phase_end():
    """The slip phase ends (v = R omega) at t1 within 2 % (resolution: one record, 0.5 ms)."""
    run = simulate("epsd", 0.2, duration=0.85)
    ref = closed_form(0.2)
    k = int(np.nonzero(run.v - RADIUS * run.w <= 1e-3 * V0)[0][0])
    assert abs(run.t[k] / ref.t1 - 1.0) <= 0.02 + 0.5 * RECORD_EVERY * DT / ref.t1, (
        f"slip ends at t = {run.t[k]:.5f} s (v = {run.v[k]:.5f} m/s), closed form "
        f"t1 = {ref.t1:.5f} s (v1 = {ref.v1:.5f} m/s)"
    )
    assert abs(run.v[k] / ref.v1 - 1.0) <= 0.01, (
        f"velocity at the end of slip {run.v[k]:.5f} m/s, closed form v1 = {ref.v1:.5f} m/s"
    )


@pytest.mark.parametrize("incline_deg", [0.0, INCLINE])
def test_epsd_time_step_convergence(incline_deg):
    duration = 0.85 if incline_deg == 0 else 0.6
    r1 = simulate("epsd", 0.2, incline_deg, duration=duration)
    r2 = simulate("epsd", 0.2, incline_deg, duration=duration, refine=2)
    (t1, x1), (t2, x2) = stop_point(r1), stop_point(r2)
    print(
        f"incline {incline_deg} deg: stop (t, x) = ({t1:.6f}, {x1:.6f}) at dt, "
        f"({t2:.6f}, {x2:.6f}) at dt/2"
    )
    assert abs(x2 / x1 - 1.0) < 0.25 * TOL_X, (
        f"stop position {x1:.6f} m (dt) -> {x2:.6f} m (dt/2): change above {0.25 * TOL_X}"
    )
    assert abs(t2 / t1 - 1.0) < 0.25 * TOL_T, (
        f"stop time {t1:.6f} s (dt) -> {t2:.6f} s (dt/2): change above {0.25 * TOL_T}"
    )


# ----------------------------------------------------------------------------- CDT defect

CDT_FINE_STEPS = 2000


def test_cdt_kinematics_but_no_rest():
    """CDT gets the rolling kinematics right but chatters and creeps at rest; EPSD does not."""
    mu_r = 0.2
    cdt = simulate("cdt", mu_r, duration=0.85, fine_steps=CDT_FINE_STEPS)
    epsd = simulate("epsd", mu_r, duration=0.85, fine_steps=CDT_FINE_STEPS)
    print(check_stop(cdt, closed_form(mu_r)))
    rest_cdt, rest_epsd = rest_after_stop(cdt), rest_after_stop(epsd)
    print(f"CDT  {rest_cdt}\nEPSD {rest_epsd}")

    # 1. The rolling torque of CDT flips sign every step at full magnitude mu_r R F_n (the
    #    half-step omega that it sees alternates in sign): it never comes to rest.
    m_r = mu_r * RADIUS * MASS * G
    for name, run in (("CDT", cdt), ("EPSD", epsd)):
        assert run.fine_t[0] > stop_point(run)[0] + REST_DELAY + REST_WINDOW - 1e-9, (
            f"{name}: per-step window starts at {run.fine_t[0]:.4f} s, before the at-rest window"
        )
    tq_c, tq_e = cdt.fine_torque / m_r, epsd.fine_torque / m_r
    flips = float(np.mean(np.sign(tq_c[1:]) != np.sign(tq_c[:-1])))
    mean_c = float(np.mean(np.abs(tq_c)))
    max_e = float(np.max(np.abs(tq_e)))
    detail = (
        f"per-step torque_y / (mu_r R m g) over the last {CDT_FINE_STEPS} steps: CDT mean |.| = "
        f"{mean_c:.4f}, sign flips on {100 * flips:.1f} % of steps; EPSD max |.| = {max_e:.3e}"
    )
    print(detail)
    assert flips > 0.9 and abs(mean_c - 1.0) < 0.1, "CDT torque does not chatter: " + detail
    assert max_e < 1e-6, "EPSD torque at rest is not zero: " + detail

    # 2. The residual angular velocity at rest: CDT's stays (trapped below dt M / (2 I)),
    #    EPSD's decays to nothing -- orders of magnitude apart.
    w_c = float(np.max(np.abs(cdt.fine_w)))
    w_e = float(np.max(np.abs(epsd.fine_w)))
    detail = (
        f"max |omega| over the last {CDT_FINE_STEPS} steps: CDT {w_c:.3e}, EPSD {w_e:.3e} rad/s"
    )
    print(detail)
    assert w_c > 1e3 * w_e and w_c > 1e-6, "CDT residual omega not above EPSD's: " + detail
    assert rest_cdt.w_late > 0.5 * rest_cdt.w_early, (
        f"CDT residual rotation decays ({rest_cdt}); expected it to persist"
    )


# ----------------------------------------------------------------------------- EPSD2


def test_epsd2_flat_stops_and_stays():
    """EPSD2 (k_r = k_t R^2, undamped): stops near the same place; its rocking decays, no creep."""
    run = simulate("epsd2", 0.2, duration=1.1)
    ref = closed_form(0.2)
    t_stop, x_stop = stop_point(run)
    print(
        f"{run.label}: stop t = {t_stop:.5f} s, x = {x_stop:.5f} m (CDT-type closed form "
        f"{ref.t_stop:.5f} s, {ref.x_stop:.5f} m)"
    )
    # Same plastic limit mu_r R F_n as EPSD, so the kinematics match the closed form loosely.
    assert abs(x_stop / ref.x_stop - 1.0) < 0.05, f"EPSD2 stop x {x_stop:.5f} vs {ref.x_stop:.5f}"
    rest = rest_metrics(run, t_stop + REST_DELAY, run.t[-1])
    msg = f"{run.label} after the stop, {rest}"
    print(msg)
    after = run.t >= t_stop
    excursion = float(np.max(np.abs(run.x[after] - x_stop)))
    assert excursion < 1e-3 * RADIUS, msg + f" -- |x - x_stop| up to {excursion:.3e} m"
    assert abs(rest.drift) < 1e-7, msg + " -- creep"
    assert rest.decay < 0.3, msg + " -- rocking does not decay"
    assert rest.w_late < W_REST, msg + f" -- |omega| late must be < {W_REST} rad/s"


# ----------------------------------------------------------------------------- incline (tc2)


def test_incline_uphill_stop_then_rest():
    run = simulate("epsd", 0.2, INCLINE, duration=0.6)
    print(check_stop(run, closed_form(0.2, INCLINE)))
    print(check_at_rest(run))


@pytest.mark.parametrize("mu_r", [0.1])
def test_incline_rolls_down_from_rest(mu_r):
    """mu_r < tan alpha: the settled sphere rolls down with (5/7) g (sin a - mu_r cos a)."""
    run = simulate("epsd", mu_r, INCLINE, launch=False, duration=0.3)
    ref = rolling_down_acceleration(mu_r)
    sel = run.t >= 0.05
    slope, _ = np.polyfit(run.t[sel], run.v[sel], 1)
    got = -slope
    print(f"mu_r={mu_r}: rolling-down acceleration {got:.5f} m/s^2 (closed form {ref:.5f})")
    assert abs(got / ref - 1.0) <= TOL_ACCEL, (
        f"mu_r={mu_r}: rolling-down acceleration {got:.5f} m/s^2, closed form {ref:.5f} m/s^2"
    )
    slip = float(np.max(np.abs(run.v[sel] - RADIUS * run.w[sel])))
    assert slip < 1e-3 * abs(run.v[-1]), f"mu_r={mu_r}: not pure rolling (max |v - R w| = {slip})"


def test_incline_holds_at_rest():
    """mu_r = 0.2 > tan 10 deg: the settled sphere stays at rest."""
    run = simulate("epsd", 0.2, INCLINE, launch=False, duration=0.3)
    rest = rest_metrics(run, 0.0, run.t[-1])
    msg = f"mu_r=0.2 on 10 deg, at rest from settling: {rest}"
    print(msg)
    assert rest.v_max < V_STOP, msg
    assert rest.w_max < W_REST, msg
    assert rest.band < 1e-3 * RADIUS, msg
    assert abs(rest.drift) < DRIFT_REST, msg
