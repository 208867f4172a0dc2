"""A hierarchy decomposed over the ranks (issue 7: every level under MPI) follows the serial one:
the same fine particles inserted, the same mass balance."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from mpi_cases import GLASS

import grainscale as gs


def pouring(comm) -> gs.Hierarchy:
    box = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.04, 0.08))
    stream = gs.insert.Stream(
        gs.insert.DiscFace(centre=(0.02, 0.02, 0.075), normal=(0, 0, -1), radius=0.012),
        mass_rate=0.08,
        radius=gs.dist.Uniform(0.95e-3, 1.05e-3),
        material=GLASS,
        velocity=(0, 0, -1.0),
        seed=5,
    )
    ref = gs.scaling.ParameterSet(
        domain=box,
        walls=tuple(gs.geometry.box_walls(box, GLASS)),
        insertions=(stream,),
        size=gs.dist.Uniform(0.95e-3, 1.05e-3),
    )
    region = gs.Box(lo=(0.008, 0.008, 0.0), hi=(0.032, 0.032, 0.03))
    return gs.Hierarchy(
        base=ref,
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=region)],
        # With the boundary velocity condition and a top-up on every interval (the dilute
        # stream) so that both run decomposed too.
        exchange=gs.Exchange(
            every=1e-3, boundary_velocity_gain=0.5, top_up=1.0, top_up_min_fraction=0.0
        ),
        comm=comm,
    )


def test_decomposed_hierarchy_matches_the_serial_one(world):
    serial, decomposed = pouring(MPI.COMM_SELF), pouring(world)
    assert decomposed.level(1).ranks == world.size
    for h in (serial, decomposed):
        h.run(until=0.08)
    a, b = serial.mass_balance()[0], decomposed.mass_balance()[0]
    assert a["topped_up"] > 0
    for key in ("expected", "inserted", "pending", "topped_up", "deleted_leaving", "held"):
        assert abs(a[key] - b[key]) <= 1e-9 * max(a["expected"], 1e-12), key
    for k in (0, 1):
        pa, pb = serial.level(k).gather(), decomposed.level(k).gather()
        assert np.array_equal(pa["id"], pb["id"])
        assert np.abs(pa["position"] - pb["position"]).max() <= 1e-9
