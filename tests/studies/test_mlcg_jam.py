"""Reduced jamming-orifice study (issue 23; python -m studies.mlcg_jam.mlcg_jam --quick): a
silo whose orifice is 6 resolved diameters wide and 3 parcels at h = 2. Pure coarse graining
jams; the hierarchy 2 -> 1 discharges while the coarse level follows it: the coarse outflow from
the region (its own outlet, plus the debt it pays by removing its particles where it holds more
than the fine level) equals the fine level's within 5 %, the coarse inventory holds the material
of the equipment to within the allowed lag, and the books of the hierarchy close to round-off at
every sample. The discharge rate, a mean over three seeds of this short, shallow run (one seed's
rate scatters by about 20 % here), is held within 15 % of the resolved run's; the issue's 5 % is
measured on the full run (studies/mlcg_jam). The shallower bed here keeps the smaller fine
region (2.5 x 1.25 D0), whose top stays below the bed.
Before the books were exact, the fine region drained to 30 % of the rate without mass from
nowhere."""

from __future__ import annotations

import math

import pytest

from studies.mlcg_jam import mlcg_jam


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("mlcg_jam")
    return mlcg_jam.study(mlcg_jam.QUICK, out, ["resolved", "cg2", "mlcg"], seeds=(1, 2, 3))


def test_pure_coarse_graining_jams(study):
    assert study["W_resolved"] > 0.015  # kg/s
    assert study["runs"]["cg2"]["rate"] < 0.3 * study["W_resolved"]


def test_the_hierarchy_discharges_at_the_resolved_rate(study):
    assert study["runs"]["mlcg"]["rate_ratio"] == pytest.approx(1.0, abs=0.15)


def test_the_coarse_level_follows_the_fine_one(study):
    for (following,) in study["runs"]["mlcg"]["following"]:  # per seed
        assert following["outflow_ratio"] == pytest.approx(1.0, abs=0.05)
        assert following["parent_paid_rate"] > 0  # the jam is paid for where it holds
        assert following["parent_vz"] < 0  # the coarse bed above the orifice moves down


def test_the_books_close_and_the_coarse_level_holds_the_inventory(study):
    run = study["runs"]["mlcg"]
    assert run["max_unaccounted"] <= 1e-12
    balance = run["mass_balance"]
    (interface,) = balance["interfaces"]
    assert balance["discharged"] > 0.005  # kg, through the fine level's outlet
    # The coarse level holds what the hierarchy holds (outside the region itself, inside it as the
    # fine level's shadow), up to the debt it may still owe: at most max_lag + 1 parcels.
    coarse_total = balance["held"][0] + interface["shadow"]
    in_equipment = sum(balance["held"]) + balance["pending"]
    parcel = 2500 * 4 / 3 * math.pi * (2 * 1.05e-3) ** 3
    assert abs(coarse_total - in_equipment) == pytest.approx(abs(interface["debt"]), abs=1e-12)
    assert interface["debt"] <= 4 * parcel
