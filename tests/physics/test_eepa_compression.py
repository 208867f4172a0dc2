"""EEPA coarse graining in uniaxial compression (validation/CASES.md E3), reduced.

The full study is ``python -m grainscale.examples.eepa_compression`` (40 mm die, h = 1, 1.5, 2,
report in docs/studies/eepa_compression/). Here: a 24 mm die filled about 24 mm high, the
reference powder (d = 2 mm, about 1300 particles) against the cg-scaled powder at h = 2 (about
170 particles, D/d = 6) and the negative control at h = 2 with f0 left at its reference value;
unconfined compression up to 8 % strain. Run side by side in two processes.

Honest scope: this reduced set-up does not reach the 5 % agreement of Thakur et al. When the test
was written the coarse powder differed from the reference by 9 % (L1) on the confined loading
curve, -41 % on the unloading stiffness and -31 % on the unconfined strength; the control with f0
left unscaled by -70 % on the strength. (The full study, D/d >= 10, is closer on the strength,
-4.5 % at h = 1.5 and -11 % at h = 2, but its loading curves differ by 44-53 % L1, mostly a strain
offset gathered at low stress: see docs/studies/eepa_compression/report.md.) The gates on the
scaled powder are therefore set about 1.3 x above the numbers measured, to catch a regression,
and the decisive check is the negative control: with f0 unscaled the strength must be at least
twice as far from the reference as with f0 ~ h^2 (the loading curve barely depends on f0 in the
full study, so the control is judged on the strength only). The unloading stiffness is reported,
not gated. Also: quasi-static loading (inertial number below 1e-3 at sigma_pre), the broken
similarity numbers, and the measuring helpers on synthetic curves.
"""

from __future__ import annotations

import numpy as np
import pytest

from grainscale.examples import eepa_analysis as ea
from grainscale.examples import eepa_compression as ec
from grainscale.examples import eepa_uniaxial as eu

CASE = eu.Case(die_diameter=0.024, fill_height=0.036)
UNCONFINED_STRAIN = 0.08
CURVE_GATE = 0.12  # L1-relative difference of sigma(eps), scaled powder
STRENGTH_GATE = 0.4  # relative difference of sigma_c, scaled powder
CONTROL_FACTOR = 2.0  # the control is at least this many times further off


@pytest.fixture(scope="module")
def rows() -> list[dict]:
    jobs = [ec.Job(1.0), ec.Job(2.0), ec.Job(2.0, control=True)]
    runs = ec.run_jobs(CASE, jobs, workers=2, max_unconfined_strain=UNCONFINED_STRAIN)
    metrics = [ec.metrics_of(CASE, r) for r in runs]
    return ec.compare(CASE, runs, metrics)


def test_scaled_confined_loading_agrees(rows: list[dict]) -> None:
    ref, coarse, _ = rows
    assert coarse["particles"] < ref["particles"] / 5
    assert coarse["loading_l1"] <= CURVE_GATE, coarse["loading_l1"]


def test_scaled_unconfined_strength_agrees(rows: list[dict]) -> None:
    ref, coarse, _ = rows
    assert ref["strength"] > 0.1 * CASE.pre_stress  # cohesion gives a real strength
    assert abs(coarse["strength_difference"]) <= STRENGTH_GATE, coarse["strength_difference"]


def test_unscaled_pull_off_force_breaks_agreement(rows: list[dict]) -> None:
    _, coarse, control = rows
    gap = abs(control["strength_difference"])
    assert gap >= CONTROL_FACTOR * abs(coarse["strength_difference"]), gap
    assert control["strength"] < 0.5 * coarse["strength"]


def test_loading_is_quasi_static(rows: list[dict]) -> None:
    for row in rows:
        assert row["inertial_number_pre"] < 1e-3, row
        assert not row["notes"], row["notes"]


def test_cg_reports_broken_similarity(rows: list[dict]) -> None:
    names = {b["name"] for b in rows[1]["broken"]}
    assert {"bond", "size_ratio", "inertial_number"} <= names


def test_l1_relative_on_shifted_curve() -> None:
    x = np.linspace(0, 1, 101)
    assert ea.l1_relative(x, x**2, x, x**2) == 0
    # y = 1.1 x^2 against x^2: 10 % everywhere
    assert ea.l1_relative(x, x**2, x, 1.1 * x**2) == pytest.approx(0.1)
    # the other curve is interpolated on the reference abscissae inside its range
    assert ea.l1_relative(x, x, x[::10], 2 * x[::10]) == pytest.approx(1.0)


def test_secant_unloading_of_a_line() -> None:
    # sigma = 1e4 - 2e6 * strain while the platen rises 1 um per record, H = 0.04 m
    z = 0.03 + 1e-6 * np.arange(100)
    s = 1e4 - 2e6 * (z - z[0]) / 0.04
    assert ea.secant_unloading(z, s, 0.04) == pytest.approx(2e6)


def test_seating_and_binning() -> None:
    s = np.array([0, 0, 0, 500, 0, 0, 300, 300, 300, 300, 300, 400])
    assert ea.seating_index(s, 250.0, window=5) == 6
    c, m = ea.binned(np.array([0.0, 0.001, 0.0025, 0.0031]), np.array([1.0, 3.0, 5.0, 7.0]), 0.002)
    assert c.tolist() == pytest.approx([0.001, 0.003])
    assert m.tolist() == pytest.approx([2.0, 6.0])


def test_bad_case_names_the_parameter() -> None:
    with pytest.raises(ValueError, match=r"Case\.pull_off_force must be <= 0 \(N\), got 0\.1"):
        eu.Case(pull_off_force=0.1)
    with pytest.raises(ValueError, match=r"Case\.platen_speed must be positive"):
        eu.Case(platen_speed=0.0)
