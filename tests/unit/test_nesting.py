"""gs.nested_levels: a chain of regions nested around a region of interest, each margin whole
exchange cells of the hierarchy's own rule, clipped to the domain, and refused with the level
and the amount where it cannot be."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import grainscale as gs
from grainscale.levels import cell_size_range

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
SIZE = gs.dist.Uniform(0.95e-3, 1.05e-3)  # radius (m): largest diameter 2.1 mm
D_MAX = 2.1e-3
SILO = gs.Box(lo=(0, 0, -0.02), hi=(0.4, 0.4, 0.6))  # the floor of the domain under the orifice
ORIFICE = gs.Box(lo=(0.17, 0.17, -0.02), hi=(0.23, 0.23, 0.04))  # touches the domain's floor
TOL = 1e-12


def reference(domain: gs.Box = SILO, rate: float = 0.1) -> gs.scaling.ParameterSet:
    """Spheres of d = 2 mm +/- 5 % poured through a face under the top of a closed box."""
    lo, hi = np.asarray(domain.lo), np.asarray(domain.hi)
    c = 0.5 * (lo + hi)
    stream = gs.insert.Stream(
        gs.insert.RectangleFace(
            corner=(c[0] - 0.01, lo[1] + 0.005, hi[2] - 0.01),
            edge1=(0.02, 0, 0),
            edge2=(0, min(0.02, hi[1] - lo[1] - 0.01), 0),
        ),
        mass_rate=rate,
        radius=SIZE,
        material=GLASS,
        velocity=(0, 0, -2.0),
        seed=5,
    )
    return gs.scaling.ParameterSet(
        domain=domain,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        walls=tuple(gs.geometry.box_walls(domain, GLASS)),
        insertions=(stream,),
        size=SIZE,
    )


def bounds(box: gs.Box) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(box.lo, float), np.asarray(box.hi, float)


def check_chain(
    levels: list[gs.Level], roi: gs.Box, domain: gs.Box, cells: list[float], margin: int = 1
) -> None:
    """Each region holds the next finer one (the finest the ROI) with at least ``margin`` whole
    cells between the two along every interface face, is whole cells along every axis with an
    interface (at least 4 between two, 2 with one), and keeps its open faces at least a cell
    from the domain's closed sides."""
    dlo, dhi = bounds(domain)
    assert levels[0].region is None
    inner = bounds(roi)
    for k in range(len(levels) - 1, 0, -1):
        region = levels[k].region
        assert isinstance(region, gs.Box)
        lo, hi = bounds(region)
        e = cells[k - 1]
        assert np.all(lo >= dlo - TOL) and np.all(hi <= dhi + TOL)
        for a in range(3):
            on_lo, on_hi = lo[a] == dlo[a], hi[a] == dhi[a]
            if on_lo and on_hi:
                continue
            n = (hi[a] - lo[a]) / e
            assert n == pytest.approx(round(n), abs=1e-9), (k, a, n)
            assert round(n) >= (2 if on_lo or on_hi else 4)
            if not on_lo:
                assert lo[a] >= dlo[a] + e * (1 - 1e-9)  # no sliver beside a wall
                assert inner[0][a] - lo[a] >= margin * e * (1 - 1e-9), (k, a)
            if not on_hi:
                assert hi[a] <= dhi[a] - e * (1 - 1e-9)
                assert hi[a] - inner[1][a] >= margin * e * (1 - 1e-9), (k, a)
        inner = (lo, hi)


def default_cells(ratios: tuple[float, ...]) -> list[float]:
    """The hierarchy's default cell edges of a chain (scheme "cg": diameters h d)."""
    return [
        cell_size_range(h * D_MAX, c * D_MAX)[1] for h, c in zip(ratios, ratios[1:], strict=False)
    ]


def test_a_chain_of_four_nests_around_an_orifice_on_the_floor():
    ratios = (8, 4, 2, 1)
    levels = gs.nested_levels(reference(), ORIFICE, ratios)
    assert [lv.cg for lv in levels] == list(ratios)
    assert all(lv.exchange is None for lv in levels)
    cells = default_cells(ratios)  # 2 parent diameters: 33.6, 16.8, 8.4 mm
    assert cells == pytest.approx([0.0336, 0.0168, 0.0084])
    check_chain(levels, ORIFICE, SILO, cells)
    for lv in levels[1:]:  # every region stands on the domain's floor, as the ROI does
        assert lv.region.lo[2] == SILO.lo[2]
    # The finest holds the 60 mm ROI with one 8.4 mm cell each side: 76.8 mm -> 10 cells, the
    # 4 mm of slack split; above the floor 60 + 8.4 mm -> 9 cells.
    lo, hi = bounds(levels[3].region)
    assert (lo[0], hi[0]) == pytest.approx((0.17 - 0.0084 - 0.0036, 0.23 + 0.0084 + 0.0036))
    assert (hi[2] - lo[2]) / 0.0084 == pytest.approx(9)


def test_the_hierarchy_accepts_the_chain_and_uses_the_same_cells():
    """Every rule the Hierarchy applies holds (regions nested, cells across, clearance), and its
    exchange grids have exactly the cell edges the margins were counted in."""
    ratios = (8, 4, 2, 1)
    ref = reference()
    h = gs.Hierarchy(base=ref, levels=gs.nested_levels(ref, ORIFICE, ratios))
    assert h.parents == [-1, 0, 1, 2]
    for c, e in zip(h.couplings, default_cells(ratios), strict=True):
        open_axes = [a for a in range(3) if np.any(np.abs(c.grid["face_normal"][:, a]) > 0.5)]
        assert open_axes
        assert np.asarray(c.grid["edge"])[open_axes] == pytest.approx(e, rel=1e-12)


def test_regions_are_clipped_to_the_domain_sides():
    """A ROI in a corner, a face less than a cell from a side: the faces go onto the sides, the
    open ones stay whole cells from them."""
    ref = reference()
    corner = gs.Box(lo=(0.0, 0.0, -0.02), hi=(0.03, 0.03, 0.01))
    levels = gs.nested_levels(ref, corner, (4, 2, 1))
    check_chain(levels, corner, SILO, default_cells((4, 2, 1)))
    for lv in levels[1:]:
        assert lv.region.lo == SILO.lo
    near = gs.Box(lo=(0.1, 0.005, 0.1), hi=(0.13, 0.02, 0.12))  # 5 mm from the side y = 0
    levels = gs.nested_levels(ref, near, (2, 1))
    lo, hi = bounds(levels[1].region)
    assert lo[1] == 0.0 and hi[1] == pytest.approx(4 * 0.0084)  # on the side, whole cells
    assert lo[0] > 0 and lo[2] > SILO.lo[2]  # the other faces are interfaces
    check_chain(levels, near, SILO, default_cells((2, 1)))
    gs.Hierarchy(base=ref, levels=levels)


def test_margins_follow_the_exchange_cells_and_the_layer():
    """Explicit cell sizes set the cells the margins are counted in; a stress layer thicker than
    a cell takes more of them."""
    ref = reference()
    exchanges = [gs.Exchange(cell_size=0.04), gs.Exchange(cell_size=0.02)]
    levels = gs.nested_levels(ref, ORIFICE, (4, 2, 1), exchange=exchanges)
    assert [lv.exchange for lv in levels[1:]] == exchanges
    check_chain(levels, ORIFICE, SILO, [0.04, 0.02])
    thick = gs.Exchange(layer=6.0)  # 6 fine diameters: 12.6 mm > one cell of 8.4 mm
    levels = gs.nested_levels(ref, ORIFICE, (2, 1), exchange=thick)
    check_chain(levels, ORIFICE, SILO, [0.0084], margin=2)
    gs.Hierarchy(base=ref, levels=levels, exchange=thick)


def test_one_ratio_is_the_coarsest_level_everywhere():
    (level,) = gs.nested_levels(reference(), ORIFICE, [2])
    assert level.cg == 2 and level.region is None


@pytest.mark.parametrize(
    ("ratios", "words"),
    [
        ((4, 4, 1), "strictly decreasing"),
        ((1, 2), "strictly decreasing"),
        ((2, 0.5), "at least at 1"),
        ((), "finite ratios"),
        (("four", 1), "sequence of coarse-graining ratios"),
    ],
)
def test_bad_ratio_sequences_are_refused(ratios, words):
    with pytest.raises(ValueError, match=f"nested_levels.ratios must .*{words}"):
        gs.nested_levels(reference(), ORIFICE, ratios)


def test_bad_rois_and_exchanges_are_refused():
    ref = reference()
    with pytest.raises(ValueError, match=r"nested_levels.roi must lie inside the domain"):
        gs.nested_levels(ref, gs.Box(lo=(0.3, 0.3, 0.5), hi=(0.5, 0.35, 0.55)), (2, 1))
    with pytest.raises(ValueError, match=r"nested_levels.roi must be a gs.Box"):
        gs.nested_levels(ref, ((0, 0, 0), (0.1, 0.1, 0.1)), (2, 1))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"nested_levels.base must be"):
        gs.nested_levels(SILO, ORIFICE, (2, 1))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"one per finer level \(2\), got 1 items"):
        gs.nested_levels(ref, ORIFICE, (4, 2, 1), exchange=[gs.Exchange()])
    with pytest.raises(
        ValueError,
        match=r"exchange.cell_size of level 1 \(cg=1\) must be at least 0.0063 m.*got 0.005",
    ):
        gs.nested_levels(ref, ORIFICE, (2, 1), exchange=gs.Exchange(cell_size=0.005))


def test_margins_that_do_not_fit_name_the_level_and_the_shortfall():
    """In a box 0.2 m wide the level at h = 4 of (8, 4, 2, 1) would reach every side: its parent
    would hold nothing."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.2, 0.2, 0.2))
    roi = gs.Box(lo=(0.08, 0.08, 0.08), hi=(0.12, 0.12, 0.12))
    with pytest.raises(ValueError) as err:
        gs.nested_levels(reference(box), roi, (8, 4, 2, 1))
    text = str(err.value)
    assert "region of level 1 (cg=4)" in text and "covers the whole domain" in text
    assert "parent (cg=8) would hold nothing" in text and "0.0176 m too short" in text
    gs.nested_levels(reference(box), roi, (4, 2, 1))  # without h = 8 it fits
    periodic = dataclasses.replace(box, periodic=(True, False, False))
    near = gs.Box(lo=(0.005, 0.08, 0.08), hi=(0.05, 0.12, 0.12))
    with pytest.raises(ValueError, match=r"level 1 \(cg=1\).*periodic axis x.*by 0.0061 m"):
        gs.nested_levels(reference(periodic), near, (2, 1))


def test_a_small_chain_from_the_helper_runs_with_exact_books():
    """(4, 2, 1) around a ROI on the floor of a slot 120 x 30 x 100 mm: the pour crosses both
    interfaces and the hierarchy's books close to round-off after every few intervals."""
    slot = gs.Box(lo=(0, 0, 0), hi=(0.12, 0.03, 0.1))
    ref = reference(slot, rate=0.2)
    roi = gs.Box(lo=(0.054, 0.0, 0.0), hi=(0.066, 0.03, 0.01))
    levels = gs.nested_levels(ref, roi, (4, 2, 1))
    check_chain(levels, roi, slot, default_cells((4, 2, 1)))
    h = gs.Hierarchy(base=ref, levels=levels, exchange=gs.Exchange(every=2e-3))
    for _ in range(8):
        h.run(intervals=5)
        b = h.mass_balance()
        scale = b["initial"] + b["inserted"]
        assert abs(b["unaccounted"]) <= 1e-12 * scale, b
        for i in b["interfaces"]:
            assert i["shadow"] == pytest.approx(
                i["child_mass"] + i["pending"] + i["debt"], rel=0, abs=1e-12 * scale
            )
    assert all(i["carried_in"] > 0 for i in b["interfaces"])
    assert h.level(2).num_particles > 100
