"""Reduced MLCG silo study (issue 7; python -m studies.mlcg_silo.mlcg_silo --quick): a small
square silo three orifices wide with an orifice of 10 diameters, resolved, coarse grained at
h = 2 and as a two-level hierarchy (h = 2 everywhere, h = 1 around the orifice). Pure CG misses
the resolved discharge rate by more than 20 % (5 parcels across the orifice); the hierarchy,
whose orifice is resolved, comes within 5 %, with the cell solid fraction and velocity of the
resolved region within 10 % (CASES.md F1) over the region proper and within 15 % over all its
cells, the transition cells included; the books of the material close after every sample and the
coarse level's outflow from the region follows the fine level's discharge (the full-size study
is in studies/mlcg_silo)."""

from __future__ import annotations

import pytest

from studies.mlcg_silo import mlcg_silo


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("mlcg_silo")
    return mlcg_silo.study(mlcg_silo.QUICK, out, ["resolved", "cg2", "mlcg"])


def test_pure_coarse_graining_misses_the_resolved_rate(study):
    resolved = study["runs"]["resolved"]["rate"]
    assert resolved > 0.05  # kg/s
    assert study["runs"]["cg2"]["rate"] < 0.8 * resolved


def test_multi_level_recovers_the_resolved_rate(study):
    assert study["runs"]["mlcg"]["rate_ratio"] == pytest.approx(1.0, abs=0.05)


def test_the_books_close_and_the_coarse_level_follows(study):
    run = study["runs"]["mlcg"]
    (interface,) = run["mass_balance"]["interfaces"]
    assert interface["carried_in"] > 0.05  # kg
    assert run["max_unaccounted"] <= 1e-12
    # What the fine level discharges leaves the coarse level's inventory too: its own outlet
    # carries most of it (5 parcels across the orifice pass), the paid debt the rest.
    (following,) = run["following"]
    assert following["outflow_ratio"] == pytest.approx(1.0, abs=0.05)
    assert following["parent_outlet_rate"] > 0.5 * following["child_outflow_rate"]
    assert following["parent_vz"] < 0 and following["child_vz"] < 0


def test_fields_of_the_resolved_region(study):
    errors = study["runs"]["mlcg"]["field_errors"]
    assert errors["interior_cells"] >= 8
    assert errors["interior_solid_fraction"] < 0.10
    assert errors["interior_velocity"] < 0.10
    assert errors["cells"] > errors["interior_cells"]
    assert errors["solid_fraction"] < 0.15
    assert errors["velocity"] < 0.15
