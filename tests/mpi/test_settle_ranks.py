"""A decomposed run follows the serial one (issue 6): the 'settle' case on all ranks of
COMM_WORLD against the same case run serially in each process."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from mpi_cases import relative_difference, settle


def test_20k_settle_positions_agree_after_1000_steps(world):
    serial = settle(MPI.COMM_SELF, 20000)
    decomposed = settle(world, 20000)
    assert decomposed.ranks == world.size
    counts = decomposed.decomposition()["counts"]
    assert sum(counts) == 20000 and min(counts) > 0  # every rank holds a share
    serial.run(steps=1000)
    decomposed.run(steps=1000)
    a, b = serial.gather(), decomposed.gather()
    assert np.array_equal(a["id"], b["id"])
    size = float(np.max(serial.domain.length))
    assert relative_difference(a["position"], b["position"], size) <= 1e-10
    assert relative_difference(a["velocity"], b["velocity"], np.abs(a["velocity"]).max()) <= 1e-8
    # Reduced quantities are the serial ones up to the order of the sums.
    assert decomposed.num_contacts() == serial.num_contacts()
    assert abs(decomposed.kinetic_energy() / serial.kinetic_energy() - 1) <= 1e-10
    for k in range(6):
        fa, fb = serial.walls[k].force, decomposed.walls[k].force
        assert np.allclose(fb, fa, rtol=1e-9, atol=1e-12 * np.abs(fa).max())


def test_long_settle_gives_the_same_packing(world):
    """Past the first thousand steps round-off differences grow (the dynamics are chaotic), so
    the settled beds are compared statistically: height, packing and coordination."""
    n = 3000
    serial = settle(MPI.COMM_SELF, n, seed=3)
    decomposed = settle(world, n, seed=3)
    for sim in (serial, decomposed):
        sim.run(until=0.12)
    a, b = serial.gather(), decomposed.gather()
    za, zb = a["position"][:, 2], b["position"][:, 2]
    assert abs(zb.mean() / za.mean() - 1) < 0.01
    assert abs(np.percentile(zb, 95) / np.percentile(za, 95) - 1) < 0.01
    ca, cb = serial.num_contacts(), decomposed.num_contacts()
    assert abs(cb / ca - 1) < 0.03
    weight_energy = n * 2500 * np.pi / 6 * 2e-3**3 * 9.81 * 2e-3  # n m g d
    assert decomposed.kinetic_energy() < 1e-3 * weight_energy  # at rest


def test_chunked_run_is_bit_identical(world):
    """Inside a run the forces on ghosts travel back while the other particles are integrated
    (GhostExchange::reverse_begin/end); at the end of a run they are completed at once. Both
    make the same additions in the same order, so how a run is cut into chunks changes no bit."""
    whole, chunked = settle(world, 4000, seed=2), settle(world, 4000, seed=2)
    assert len(chunked.decomposition()["counts"]) == world.size
    whole.run(steps=300)
    for _ in range(3):
        chunked.run(steps=100)
    a, b = whole.gather(), chunked.gather()
    assert np.array_equal(a["id"], b["id"])
    assert np.array_equal(a["position"], b["position"])
    assert np.array_equal(a["velocity"], b["velocity"])
    assert np.array_equal(a["angular_velocity"], b["angular_velocity"])
