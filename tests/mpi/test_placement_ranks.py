"""Set-up checks under MPI (issue 25): particles added by hand that overlap each other or the
particles present (each owned by one rank) raise the same ValueError on every rank."""

from __future__ import annotations

import numpy as np
import pytest
from mpi_cases import GLASS, lattice, settle


def test_overlapping_particles_raise_the_same_error_on_every_rank(world):
    n = 500
    sim = settle(world, n)
    side = int(np.ceil((n / 2) ** (1 / 3)))
    sites, _ = lattice(n, 2.2e-3, side, seed=1)  # the sites settle() filled, ids 0 .. n-1
    owners = world.allgather(sim.num_local_particles)
    assert sum(owners) == n and min(owners) > 0  # the particles are spread over the ranks
    with sim.particles(writable=False) as p:
        held = world.allgather({0, n - 1} & set(p.id.tolist()))
    assert held.index({0}) != held.index({n - 1})  # found on two ranks, reported by every one
    above = sites[n - 1] + [0, 0, 2.2e-3]  # above the top particle, clear of the lid
    position = np.array(
        [
            sites[0],  # on particle 0, at the bottom
            sites[n - 1],  # on particle n - 1, at the top
            above,
            above + [0.3e-3, 0, 0],  # onto the one before
        ]
    )
    with pytest.raises(ValueError) as raised:
        sim.add_particles(position=position, radius=1e-3, material=GLASS)
    message = str(raised.value)
    assert world.allgather(message) == [message] * world.size
    assert (
        "Simulation.add_particles: 3 pair(s) of particles overlap by more than 10% of the "
        f"smaller radius (first: index 0 and id 0, index 1 and id {n - 1}, index 2 and index 3)"
    ) in message
    assert sim.num_particles == n
    ids = sim.add_particles(position=position[2:3], radius=1e-3, material=GLASS)
    assert sim.num_particles == n + 1 and ids.tolist() == [n]
    sim.run(steps=5)  # the ranks are still in step
