"""Multi-level coarse graining (grainscale.hierarchy, issue 7): levels built from one reference
set, the exchange grid made from the region, the coarse -> fine mass flux with exact
accounting, the coupled fields, several levels, and checkpoints of the whole hierarchy."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
D = 2e-3  # reference diameter (m)


def pouring_reference(rate: float = 0.08) -> gs.scaling.ParameterSet:
    """A stream of d = 2 mm spheres poured into a closed box 40 x 40 x 80 mm."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.04, 0.08))
    stream = gs.insert.Stream(
        gs.insert.DiscFace(centre=(0.02, 0.02, 0.075), normal=(0, 0, -1), radius=0.012),
        mass_rate=rate,
        radius=gs.dist.Uniform(0.95e-3, 1.05e-3),
        material=GLASS,
        velocity=(0, 0, -1.0),
        seed=5,
    )
    return gs.scaling.ParameterSet(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        walls=tuple(gs.geometry.box_walls(box, GLASS)),
        insertions=(stream,),
        size=gs.dist.Uniform(0.95e-3, 1.05e-3),
    )


FINE_REGION = gs.Box(lo=(0.008, 0.008, 0.0), hi=(0.032, 0.032, 0.03))


def two_level(**exchange) -> gs.Hierarchy:
    return gs.Hierarchy(
        base=pouring_reference(),
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=FINE_REGION)],
        exchange=gs.Exchange(every=1e-3, **exchange),
    )


def test_levels_come_from_the_scaling_module():
    h = two_level()
    coarse, fine = h.level(0), h.level(1)
    assert h.sizes[0].max_radius == pytest.approx(2 * 1.05e-3)
    assert h.sizes[1].max_radius == pytest.approx(1.05e-3)
    # Each level its own step, both dividing the exchange interval.
    assert coarse.time_step * h.steps[0] == pytest.approx(1e-3)
    assert fine.time_step * h.steps[1] == pytest.approx(1e-3)
    assert coarse.time_step > 1.5 * fine.time_step
    # The fine level lives around its region only and inserts nothing of its own.
    assert np.all(np.asarray(fine.domain.lo) >= 0) and fine.domain.hi[2] < 0.05
    assert fine.streams == [] and len(coarse.streams) == 1


def test_exchange_grid_of_a_box_region():
    h = two_level(cell_size=0.006)
    g = h.couplings[0].grid
    assert tuple(g["dims"]) == (4, 4, 5)
    assert np.all(g["inside"] > 0)
    # Every face of the box region except the floor, which lies on the closed side z = 0.
    assert len(g["face_cell"]) == 4 * 4 + 4 * (4 * 5)
    normals = g["face_normal"]
    assert np.allclose(np.linalg.norm(normals, axis=1), 1)
    top = normals[:, 2] < -0.5  # the top face's normal points down, into the region
    assert np.count_nonzero(top) == 16
    assert np.allclose(g["face_area"], 0.006 * 0.006)


def test_exchange_grid_of_a_cylinder_region():
    cyl = gs.geometry.Cylinder(point=(0.02, 0.02, 0.005), axis=(0, 0, 1), radius=0.012, length=0.02)
    h = gs.Hierarchy(
        base=pouring_reference(),
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=cyl)],
        exchange=gs.Exchange(every=1e-3, cell_size=0.004),
    )
    g = h.couplings[0].grid
    dims = np.array(g["dims"])
    c = np.arange(np.prod(dims))
    ijk = np.stack([c % dims[0], (c // dims[0]) % dims[1], c // (dims[0] * dims[1])], 1)
    centre = np.array(g["origin"]) + (ijk + 0.5) * np.array(g["edge"])
    r = np.hypot(centre[:, 0] - 0.02, centre[:, 1] - 0.02)
    assert np.array_equal(g["inside"] > 0, r <= 0.012)
    # A boundary cell has an interface face; the staircase surface has faces on four sides.
    assert {tuple(n) for n in np.round(g["face_normal"], 6) + 0.0} >= {
        (1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, -1.0)
    }  # fmt: skip


def test_invalid_hierarchies_are_refused():
    ref = pouring_reference()
    with pytest.raises(ValueError, match="levels\\[1\\].cg must be smaller"):
        gs.Hierarchy(base=ref, levels=[gs.Level(cg=2), gs.Level(cg=2, region=FINE_REGION)])
    with pytest.raises(ValueError, match="levels\\[0\\] \\(the coarsest\\) must cover"):
        gs.Hierarchy(base=ref, levels=[gs.Level(cg=2, region=FINE_REGION)])
    outside = gs.Box(lo=(0.01, 0.01, 0.05), hi=(0.03, 0.03, 0.1))
    with pytest.raises(ValueError, match="must lie inside the domain"):
        gs.Hierarchy(base=ref, levels=[gs.Level(cg=2), gs.Level(cg=1, region=outside)])
    with pytest.raises(ValueError, match="Exchange.fade must be at most layer"):
        gs.Exchange(layer=1.0, fade=1.5)


def test_mass_entering_the_region_is_inserted_exactly():
    """The coarse stream falls into the fine region: every kilogram the coarse level carries
    across the interface is inserted as fine particles or still pending, none is lost."""
    h = two_level()
    h.run(until=0.12)
    (bal,) = h.mass_balance()
    assert bal["expected"] > 0.004  # kg carried in (0.08 kg/s for ~0.07 s after the fall)
    assert abs(bal["unaccounted"]) <= 1e-12 * bal["expected"]
    assert bal["inserted"] > 0.9 * bal["expected"]
    assert bal["pending"] < 0.1 * bal["expected"]
    assert bal["held"] == pytest.approx(
        bal["inserted"] - bal["deleted_leaving"] - bal["removed_by_outlets"], rel=1e-9
    )
    # The fine level holds about the coarse mass of its region (both fill the same bin).
    f = h.fields()
    inside = f["grid"]["inside"] > 0
    coarse_mass = f["parent"]["mass"][inside].sum()
    fine_mass = f["child"]["mass"][inside].sum()
    assert fine_mass == pytest.approx(coarse_mass, rel=0.25)


def test_three_levels_in_a_chain():
    middle = gs.Box(lo=(0.004, 0.004, 0.0), hi=(0.036, 0.036, 0.04))
    inner = gs.Box(lo=(0.012, 0.012, 0.0), hi=(0.028, 0.028, 0.02))
    h = gs.Hierarchy(
        base=pouring_reference(rate=0.1),
        levels=[gs.Level(cg=4), gs.Level(cg=2, region=middle), gs.Level(cg=1, region=inner)],
        exchange=gs.Exchange(every=2e-3),
    )
    assert h.parents == [-1, 0, 1]
    h.run(until=0.14)
    balances = h.mass_balance()
    assert [(b["parent"], b["child"]) for b in balances] == [(0, 1), (1, 2)]
    for b in balances:
        assert b["expected"] > 0
        assert abs(b["unaccounted"]) <= 1e-12 * b["expected"]
    assert h.level(2).num_particles > 0


def test_hierarchy_checkpoint_continues_bit_identically(tmp_path):
    a = two_level()
    a.run(until=0.09)
    path = tmp_path / "hierarchy.h5"
    a.checkpoint(path)
    a.run(intervals=15)
    b = two_level()
    b.restart(path)
    b.run(intervals=15)
    for k in (0, 1):
        pa = a.level(k).gather(("position", "velocity"))
        pb = b.level(k).gather(("position", "velocity"))
        assert np.array_equal(pa["id"], pb["id"])
        assert np.array_equal(pa["position"], pb["position"])
        assert np.array_equal(pa["velocity"], pb["velocity"])
    assert a.mass_balance() == b.mass_balance()
