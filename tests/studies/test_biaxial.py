"""Reduced biaxial CG study (CASES.md E2; the full one is studies/biaxial).

Small 2-D specimens (18 x 36 mm: about 660 discs at h = 1, 170 at h = 2, 9 diameters wide),
three random samples per scale, loaded to 0.4 % axial strain. Checks: the lateral servo holds
the confining stress within 2 % at every record; the average contact force at the start of
loading scales as h (Zhang et al. 2021, eq. 35) within 6 %; the gradient of the average contact
force vs axial strain (0-0.3 %) of h = 2 matches 2 x that of h = 1 within 15 % (per-sample
spread about 8 % at both h, so the difference of two means of three has a standard error of
about 7 %; measured -7 %; the 3-D rule k_n x h would double the h = 2 contact stiffness); the
deviator-stress slope, a stress per unit thickness and so invariant, within 20 % (these h = 2
specimens, 9 diameters wide, are looser near the walls: measured -14 %; the full study in
studies/biaxial has larger specimens). About 25 s on one core.
"""

from __future__ import annotations

import numpy as np
import pytest

from studies.biaxial.biaxial import analyse
from studies.biaxial.biaxial_run import BiaxialCase, run_sample

CASE = BiaxialCase(width=0.018, height=0.036, max_strain=0.004, records=20)
SEEDS = (1, 2, 3)


@pytest.fixture(scope="module")
def study() -> dict:
    runs = [run_sample(CASE, h, seed) for h in (1.0, 2.0) for seed in SEEDS]
    for r in runs:
        r["seconds"] = 0.0
    return {"runs": runs, "summary": analyse(runs, fit_strain=0.003)}


def test_servo_holds_the_confining_stress(study: dict) -> None:
    for r in study["runs"]:
        lateral = np.asarray(r["lateral"]) / CASE.confining_stress
        assert np.all(np.abs(lateral - 1) < 0.02), (r["h"], r["seed"], lateral)


def test_cg_specimens_follow_the_exact_scaling(study: dict) -> None:
    row = {r["h"]: r for r in study["summary"]["table"]}[2.0]
    fine = study["summary"]["table"][0]
    assert row["samples"] == 3 and row["particles"] < 0.3 * fine["particles"]
    assert row["initial_force_ratio"] == pytest.approx(1.0, abs=0.06)
    assert row["gradient_mean"] == pytest.approx(row["gradient_theory"], rel=0.15)
    assert row["deviator_slope_ratio"] == pytest.approx(1.0, abs=0.2)
