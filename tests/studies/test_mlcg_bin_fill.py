"""Reduced MLCG bin fill (issue 7; python -m studies.mlcg_bin_fill.mlcg_bin_fill --quick, CASES.md
F2): a bin filled and settled, resolved and as a hierarchy with a resolved window at its bottom
that feels the coarse bed above only through the stress boundary condition. The window's solid
fraction follows the resolved run within 10 %; its vertical stress is checked at 25 % here, one
seed of a small bin (0.137 at the time of writing; a single resolved seed scatters by 7-10 %
about the mean of others): the issue's 10 % is the full-size study's, over three seeds (0.065,
studies/mlcg_bin_fill); the books of the material close exactly."""

from __future__ import annotations

import numpy as np
import pytest

from studies.mlcg_bin_fill import mlcg_bin_fill


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("mlcg_bin_fill")
    return mlcg_bin_fill.study(mlcg_bin_fill.QUICK, out, ["resolved", "mlcg"])


def test_window_fields_follow_the_resolved_run(study):
    mlcg = study["runs"]["mlcg"]
    assert mlcg["interior_l1_solid_fraction"] < 0.10
    assert mlcg["interior_l1_stress_zz"] < 0.25
    # The weight of the coarse bed reaches the window: its top cells carry stress.
    top = np.asarray(mlcg["stress_zz"]).reshape(mlcg["dims"][2], -1)[-1]
    resolved_top = np.asarray(study["runs"]["resolved"]["stress_zz"]).reshape(mlcg["dims"][2], -1)[
        -1
    ]
    assert np.mean(top) == pytest.approx(np.mean(resolved_top), rel=0.2)


def test_window_mass_balance(study):
    (balance,) = study["runs"]["mlcg"]["mass_balance"]
    (window,) = balance["interfaces"]
    assert window["carried_in"] > 0.02  # kg
    assert window["inserted"] > 0.95 * (window["carried_in"] - window["carried_out"])
    total = balance["initial"] + balance["inserted"]
    assert abs(balance["unaccounted"]) <= 1e-12 * total
    # The coarse bed holds the window's material: its shadow is the fine mass plus what the
    # interface still owes (nothing is discharged, so no debt).
    assert window["shadow"] == pytest.approx(window["child_mass"] + window["pending"], abs=1e-12)
