"""Flat-bottomed silo discharge (validation/CASES.md D1, reduced to run in about half a minute).

One constant-head silo, 60 mm across with a bed 50 mm deep (about 2400 spheres d = 4 mm +/- 5 %;
what the outlet removes is re-poured on top), two orifices D0 = 24 and 28 mm (D0/d = 6 and 7),
run side by side in two processes with ``studies.silo_discharge.silo_discharge``. Reduced against
the D1 set-up in size and in Young's modulus (1e7 Pa instead of 1e8 Pa, for a 3.2 x larger time
step: D0 = 24 mm in a 60 mm silo filled 125 mm high discharged at 0.0929 kg/s with 1e7 Pa and at
0.0924 kg/s with 1e8 Pa).

Checks: the discharge is steady over the window (linear mass-time history, equal rates in the
two halves), the rate grows with the orifice, every removed particle is re-poured and none is
lost or created (exact in number, to round-off in mass), and W lies inside the envelope of
Beverloo's W = C rho_b sqrt(g) (D0 - k d)^2.5 over the CASES D1 acceptance ranges C in
[0.5, 0.7], k in [1, 2] with the measured bulk density. Plus the helpers on synthetic data.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from studies.silo_discharge import silo_beverloo, silo_case, silo_run
from studies.silo_discharge import silo_discharge as sd

CASE = silo_case.SiloCase(**silo_case.QUICK_CASE)
ORIFICES = tuple(1e-3 * v for v in silo_case.QUICK_ORIFICES_MM)  # m


@pytest.fixture(scope="module")
def runs() -> list[silo_run.DischargeResult]:
    return silo_run.run_many([(CASE, d0, 1, None) for d0 in ORIFICES], jobs=2)


def test_discharge_is_steady(runs: list[silo_run.DischargeResult]) -> None:
    for r in runs:
        assert not r.clogged, r.notes
        assert r.discharge_time >= CASE.measure_window(r.orifice)[1]
        assert r.r_squared > 0.99, (r.orifice, r.r_squared)
        # the rates over the two halves of the window agree
        assert r.rate_second_half / r.rate_first_half == pytest.approx(1.0, abs=0.2)


def test_rate_increases_with_orifice(runs: list[silo_run.DischargeResult]) -> None:
    small, large = runs
    assert small.orifice < large.orifice
    # Beverloo: ((28 - 6) / (24 - 6))^2.5 = 1.65
    assert large.rate > 1.3 * small.rate


def test_mass_accounting_is_exact(runs: list[silo_run.DischargeResult]) -> None:
    for r in runs:
        assert r.lost == 0
        assert r.refill_count == r.discharged_count  # the head is topped up after each chunk
        assert r.remaining_count == r.particles  # so the number in the silo is back to the fill
        assert r.inserted_count == r.remaining_count + r.discharged_count
        assert r.count[-1] == r.discharged_count
        assert r.inserted_mass == pytest.approx(r.remaining_mass + r.discharged_mass, rel=1e-12)


def test_bulk_density_and_beverloo(runs: list[silo_run.DischargeResult]) -> None:
    for r in runs:
        assert 0.55 < r.core_bulk_density / CASE.density < 0.65
        # Beverloo over the CASES acceptance ranges: the highest with C = 0.7, k = 1, the
        # lowest with C = 0.5, k = 2 (0.64-1.57 x the C = 0.58, k = 1.5 value at D0/d = 6-7)
        d, rho = CASE.diameter, r.core_bulk_density
        low = silo_beverloo.beverloo_rate(r.orifice, d, rho, c=0.5, k=2.0)
        high = silo_beverloo.beverloo_rate(r.orifice, d, rho, c=0.7, k=1.0)
        assert low < r.rate < high, (r.orifice, low, r.rate, high)


def test_seed_scatter_of_repeated_runs(runs: list[silo_run.DischargeResult]) -> None:
    again = dataclasses.replace(runs[0], seed=2, rate=1.1 * runs[0].rate)
    expected = math.log(1.1) / math.sqrt(2)  # sample sd of two logs
    assert sd.seed_scatter(ORIFICES, [*runs, again]) == pytest.approx(expected, rel=1e-12)
    assert math.isnan(sd.seed_scatter(ORIFICES, runs))


# ------------------------------------------------------------------------------ helpers


def test_exponent_interval_brackets_the_true_exponent() -> None:
    d = 4e-3
    d0 = np.array([24e-3, 32e-3, 40e-3, 52e-3, 64e-3])
    w = silo_beverloo.beverloo_rate(d0, d, 1500.0, c=0.58, k=1.5, exponent=2.5)
    w = w * np.exp(0.01 * np.array([1.0, -1.0, 0.5, -0.5, 0.0]))  # 1 % scatter
    lo, hi = silo_beverloo.exponent_interval(d0, w, d, 1500.0, sigma_log=0.01)
    assert lo < 2.5 < hi
    wide = silo_beverloo.exponent_interval(d0, w, d, 1500.0, sigma_log=0.05)
    assert wide[0] < lo and wide[1] > hi
    with pytest.raises(ValueError, match="sigma_log must be positive"):
        silo_beverloo.exponent_interval(d0, w, d, 1500.0, sigma_log=0.0)


def test_measure_rate_of_a_linear_history() -> None:
    t = np.linspace(0.0, 2.0, 401)
    mass = np.clip(0.3 * (t - 0.1), 0.0, None)
    w, w1, w2, r2 = silo_run.measure_rate(t, mass, inventory=0.5)
    assert (w, w1, w2) == pytest.approx((0.3, 0.3, 0.3), rel=1e-9)
    assert r2 == pytest.approx(1.0)
    assert math.isnan(silo_run.measure_rate(t[:2], mass[:2], inventory=0.5)[0])


@pytest.mark.parametrize("exponent", [2.5, None])
def test_fit_beverloo_recovers_synthetic_parameters(exponent: float | None) -> None:
    d = 4e-3
    d0 = np.array([24e-3, 28e-3, 32e-3, 36e-3, 44e-3])
    rho = np.array([1400.0, 1410.0, 1420.0, 1430.0, 1440.0])
    n = 2.5 if exponent is not None else 2.7
    w = silo_beverloo.beverloo_rate(d0, d, rho, c=0.6, k=1.3, exponent=n)
    fit = silo_beverloo.fit_beverloo(d0, w, d, rho, exponent=exponent)
    assert fit.exponent == pytest.approx(n, abs=2e-3)
    assert fit.k == pytest.approx(1.3, abs=2e-3)
    assert fit.c == pytest.approx(0.6, rel=2e-2)
    assert fit.rms_log_residual < 2e-3
    assert not fit.at_bound


def test_measure_rate_between_times() -> None:
    t = np.linspace(0.0, 1.0, 201)
    mass = 0.5 * t + 0.2 * np.where(t < 0.3, t, 0.3)  # faster before 0.3 s, then 0.5 kg/s
    w, w1, w2, r2 = silo_run.measure_rate_between(t, mass, 0.3, 1.0)
    assert (w, w1, w2) == pytest.approx((0.5, 0.5, 0.5), rel=1e-9)
    assert r2 == pytest.approx(1.0)


def test_silo_diameter_follows_beverloo_and_the_wall_gap() -> None:
    case = silo_case.SiloCase(silo_ratio=2.5, wall_gap=30.0, diameter=4e-3)
    assert case.silo_for(0.024) == pytest.approx(0.024 + 0.12)  # D0 + 30 d > 2.5 D0
    assert case.silo_for(0.1) == pytest.approx(0.25)  # 2.5 D0 > D0 + 30 d
    with pytest.raises(ValueError, match=r"SiloCase.wall_gap must be >= 0, got -1"):
        silo_case.SiloCase(wall_gap=-1.0)


def test_annulus_floor_has_the_orifice_area() -> None:
    r_in, r_out = 12e-3, 33e-3
    mesh = silo_case.annulus_mesh(r_in, r_out, segments=72)
    v, t = mesh.vertices, mesh.triangles
    assert np.all(v[:, 2] == 0.0)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    outer = 0.5 * 72 * r_out**2 * math.sin(2 * math.pi / 72)  # the outer polygon
    # the hole (a 72-gon) has the area of the circle of radius r_in
    assert outer - area == pytest.approx(math.pi * r_in**2, rel=1e-9)
    assert np.hypot(v[:, 0], v[:, 1]).max() == pytest.approx(r_out)


def test_material_options_reach_the_case() -> None:
    args = sd.build_parser().parse_args(
        ["--youngs-modulus", "3e6", "--friction", "0.3", "--rolling-friction", "0"]
    )
    case, orifices = sd.case_from_args(args)
    assert (case.youngs_modulus, case.friction, case.rolling_friction) == (3e6, 0.3, 0.0)
    assert case.time_step is None and len(orifices) == len(silo_case.DEFAULT_ORIFICES_MM)
    law = case.contact_law()
    assert law.friction == 0.3 and law.rolling is not None and law.rolling.rolling_friction == 0.0
    default, _ = sd.case_from_args(sd.build_parser().parse_args([]))
    assert default == silo_case.SiloCase()
