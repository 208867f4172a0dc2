"""Guards under MPI (issue 25): a guard that trips on one rank stops the run on every rank at the
same step with the same RuntimeError, without a rank waiting in a collective call; the emergency
checkpoint is written by all ranks together."""

from __future__ import annotations

import time

import numpy as np
import pytest
from mpi4py import MPI
from mpi_cases import settle

import grainscale as gs


def speed_up_one_particle(sim: gs.Simulation, world: MPI.Intracomm) -> int:
    """Gives one particle of the last rank 150 m/s (1.5 mm per step of 1e-5 s: 1.5 x its radius);
    returns its global id on every rank."""
    last = world.size - 1
    chosen = -1
    with sim.particles() as p:
        if sim.rank == last and len(p):
            p.velocity[0] = (150.0, 0.0, 0.0)
            chosen = int(p.id[0])
    return world.allreduce(chosen, op=MPI.MAX)


def test_displacement_guard_stops_every_rank_at_one_step(world):
    sim = settle(world, 1000)
    sim.run(steps=10)
    chosen = speed_up_one_particle(sim, world)
    assert chosen >= 0
    started = time.perf_counter()
    with pytest.raises(RuntimeError) as err:
        sim.run(steps=100)
    elapsed = world.allreduce(time.perf_counter() - started, op=MPI.MAX)
    text = str(err.value)
    assert f"particle {chosen} moved" in text and "in step 11" in text
    assert f"(raised on rank {world.size - 1})" in text
    assert "reduce the time step (now 1e-05 s" in text
    assert world.allgather(text) == [text] * world.size
    assert world.allgather(sim.step) == [11] * world.size
    assert elapsed < 5.0
    # The ranks are still in step (the particle has hit its neighbour: no more guards).
    sim.guards = False
    sim.lost_particles_policy = "ignore"
    sim.run(steps=2)


def test_emergency_checkpoint_under_mpi(world, shared_tmp):
    path = shared_tmp / "emergency.h5"
    sim = settle(world, 500, guards=gs.Guards(emergency_checkpoint=path))
    sim.run(steps=5)
    speed_up_one_particle(sim, world)
    with pytest.raises(RuntimeError, match=r"Emergency checkpoint of this step written"):
        sim.run(steps=50)
    world.Barrier()
    assert path.exists()
    again = settle(world, 500, particles=False, guards=False)
    again.restart(path)
    assert again.step == sim.step == 6
    assert again.num_particles == sim.num_particles
    n = world.allreduce(again.num_local_particles)
    assert n == 500 and np.isfinite(again.kinetic_energy())


def test_lost_particles_are_reported_with_every_rank_s_ids(world):
    box = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.04, 0.02))
    sim = gs.Simulation(domain=box, time_step=1e-5, comm=world, quiet=True, lost_particles="error")
    x = np.array([[0.005 + 0.01 * k, 0.005 + 0.01 * k, 0.0015] for k in range(4)])
    sim.add_particles(position=x, radius=1e-3, material=gs.Material(2500, 5e7, 0.3))
    with pytest.raises(RuntimeError) as err:
        sim.run(until=0.03)  # no floor: all four fall out
    text = str(err.value)
    assert "4 particle(s) left the domain" in text and "global ids 0, 1, 2, 3;" in text
    assert world.allgather(text) == [text] * world.size
