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
    with pytest.raises(
        ValueError, match=r"Exchange.boundary_velocity_gain must be in \[0, 1\], got 1.5"
    ):
        gs.Exchange(boundary_velocity_gain=1.5)
    with pytest.raises(ValueError, match="Exchange.top_up must be non-negative and finite, got -1"):
        gs.Exchange(top_up=-1)
    with pytest.raises(
        ValueError, match=r"Exchange.top_up_min_fraction must be in \[0, 1\), got 1.2"
    ):
        gs.Exchange(top_up_min_fraction=1.2)


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
        bal["inserted"] + bal["topped_up"] - bal["deleted_leaving"] - bal["removed_by_outlets"],
        rel=1e-9,
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


# The defaults run the boundary velocity condition; the second set also tops up on every interval
# (the dilute stream), so that the top-up state (budgets, velocities, booked mass) is restored.
@pytest.mark.parametrize(
    "exchange",
    [{}, {"boundary_velocity_gain": 0.5, "top_up_min_fraction": 0.0}],
    ids=["defaults", "top-up-every-interval"],
)
def test_hierarchy_checkpoint_continues_bit_identically(tmp_path, exchange):
    a = two_level(**exchange)
    a.run(until=0.09)
    path = tmp_path / "hierarchy.h5"
    a.checkpoint(path)
    a.run(intervals=15)
    if exchange:
        assert a.mass_balance()[0]["topped_up"] > 0
    b = two_level(**exchange)
    b.restart(path)
    b.run(intervals=15)
    for k in (0, 1):
        pa = a.level(k).gather(("position", "velocity"))
        pb = b.level(k).gather(("position", "velocity"))
        assert np.array_equal(pa["id"], pb["id"])
        assert np.array_equal(pa["position"], pb["position"])
        assert np.array_equal(pa["velocity"], pb["velocity"])
    assert a.mass_balance() == b.mass_balance()


def test_boundary_cells_are_relaxed_towards_the_coarse_velocity():
    """Exchange.boundary_velocity_gain: every component of the fine Favre velocity of a boundary
    cell is pulled towards the coarse one, a = k (u_c - u_f) / T, limited by the fine cell's
    velocity range; interior cells and cells empty on either level feel nothing."""
    h = two_level(cell_size=0.006, boundary_velocity_gain=0.5, velocity_gain=0.0, stress_gain=0.0)
    h.run(intervals=1)
    c = h.couplings[0]
    n = len(c.grid["inside"])
    boundary = c.grid["boundary"] > 0
    rng = np.random.default_rng(3)
    fine = {k: np.array(v, copy=True) for k, v in c.child_fields.items()}
    coarse = {k: np.array(v, copy=True) for k, v in c.parent_fields.items()}
    fine["mass"][:] = coarse["mass"][:] = 1e-3
    fine["mass"][0] = 0.0  # a boundary cell without fine particles
    coarse["velocity"] = rng.normal(size=(n, 3))
    fine["velocity"] = rng.normal(size=(n, 3))
    fine["velocity_min"] = fine["velocity"] - 0.3
    fine["velocity_max"] = fine["velocity"] + 0.3
    c.parent_fields, c.child_fields = coarse, fine
    h._control(c)
    expected = np.clip(0.5 * (coarse["velocity"] - fine["velocity"]), -0.6, 0.6) / h.every
    expected[~boundary] = 0.0
    expected[0] = 0.0
    assert boundary[0] and np.count_nonzero(~boundary) > 0
    np.testing.assert_allclose(c.child_acceleration, expected, rtol=1e-12, atol=0)
    assert np.any(np.abs(expected) == 0.6 / h.every)  # the limiter acted somewhere


def test_top_up_feeds_a_dense_bed_only_and_is_booked_apart():
    """Exchange.top_up: while the stream falls through the region's top face dilute, the flux
    alone feeds the fine level (topping up a dilute stream would add its deficit again every
    interval while the same grains cross the cell); once the bed above the face is dense, the
    fine level adds particles up to the solid-fraction deficit, booked as topped_up, and the
    mass it holds stays accounted for exactly."""
    low = gs.Box(lo=(0.008, 0.008, 0.0), hi=(0.032, 0.032, 0.012))

    def hierarchy(**exchange) -> gs.Hierarchy:
        return gs.Hierarchy(
            base=pouring_reference(rate=0.1),
            levels=[gs.Level(cg=2), gs.Level(cg=1, region=low)],
            exchange=gs.Exchange(
                every=1e-3, cell_size=0.006, top_up=1.0, boundary_velocity_gain=0.0, **exchange
            ),
        )

    dense_only, always = hierarchy(), hierarchy(top_up_min_fraction=0.0)
    for h in (dense_only, always):
        h.run(until=0.12)  # the stream has crossed the top face to the floor
    (a,), (b,) = dense_only.mass_balance(), always.mass_balance()
    assert a["expected"] > 0.005 and b["expected"] > 0.005
    assert b["topped_up"] > 0.3 * b["expected"]
    assert a["topped_up"] < 0.02 * a["expected"]
    dense_only.run(until=0.45)  # the bed has grown over the region
    g = dense_only.couplings[0].grid
    top = g["face_cell"][g["face_normal"][:, 2] < -0.5].astype(int)
    assert dense_only.fields()["parent"]["solid_fraction"][top].mean() > 0.5
    (a,) = dense_only.mass_balance()
    assert a["topped_up"] > 0.02 * a["expected"]
    assert abs(a["unaccounted"]) <= 1e-12 * a["expected"]
    assert a["held"] == pytest.approx(
        a["inserted"] + a["topped_up"] - a["deleted_leaving"] - a["removed_by_outlets"], rel=1e-9
    )


def test_inserter_state_reads_the_format_before_the_top_up():
    """Inserter states of checkpoints written before the top-up ("flux-v1", without its booked
    mass) still load; anything else is refused with a clear error."""
    h = two_level(top_up_min_fraction=0.0)
    h.run(until=0.09)
    itf = h.couplings[0].interface
    before = itf.inserter_status()
    assert before["topped_up_mass"].sum() > 0
    states = list(itf.inserter_states())
    assert all(s.startswith("flux-v2 ") for s in states)
    old = ["flux-v1 " + " ".join(s.split(" ")[2:]) for s in states]
    itf.load_inserter_states(old)
    after = itf.inserter_status()
    assert np.array_equal(after["fed_mass"], before["fed_mass"])
    assert np.array_equal(after["inserted_mass"], before["inserted_mass"])
    assert np.array_equal(after["pending_mass"], before["pending_mass"])
    assert np.all(after["topped_up_mass"] == 0)
    with pytest.raises(ValueError, match="FluxInserter state"):
        itf.load_inserter_states(["flux-v9 " + " ".join(s.split(" ")[2:]) for s in states])
