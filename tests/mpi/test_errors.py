"""Errors under MPI (issue 6): an error on one rank is raised on every rank as the same Python
exception, quickly, and never leaves a rank waiting in a collective call."""

from __future__ import annotations

import time

import numpy as np
import pytest
from mpi_cases import settle

import grainscale as gs


def test_error_on_one_rank_reaches_every_rank_within_a_second(world):
    sim = settle(world, 2000)
    sim.run(steps=10)
    last = world.size - 1
    with sim.particles() as p:
        if sim.rank == last and len(p):
            p.velocity[0] = np.nan  # only this rank's particle goes bad
    started = time.perf_counter()
    with pytest.raises(RuntimeError, match=rf"non-finite position or velocity.*rank {last}"):
        sim.run(steps=100)
    elapsed = world.allreduce(time.perf_counter() - started, op=max_op())
    assert elapsed < 1.0


class FailingOutput:
    """An output operation that fails on one rank only (a full disk, say)."""

    def __init__(self, rank: int) -> None:
        self.rank = rank

    def next_step(self, step: int, time: float, time_step: float) -> int:
        return step + 5

    def write(self, sim: gs.Simulation) -> None:
        if sim.rank == self.rank:
            raise OSError("no space left on device")


def test_python_error_on_one_rank_is_raised_on_all(world):
    sim = settle(world, 1000)
    sim.output(FailingOutput(rank=world.size - 1))
    with pytest.raises(OSError, match="no space left on device"):
        sim.run(steps=50)
    assert world.allreduce(sim.step) == world.size * sim.step  # every rank stopped at one step


def test_invalid_input_is_refused_on_every_rank(world):
    sim = settle(world, 500)
    with pytest.raises(ValueError, match="Simulation.processor_grid"):
        gs.Simulation(domain=sim.domain, comm=world, processor_grid=(world.size + 1, 1, 1))
    sim.run(steps=5)  # the ranks are still in step


def max_op():
    from mpi4py import MPI

    return MPI.MAX


def test_mismatched_collective_arguments_raise_the_same_error_on_every_rank(world, tmp_path):
    """Ranks that call run() (or checkpoint()) with different arguments would wait for each
    other forever; the arguments are compared first and every rank raises the same error."""
    sim = settle(world, 500)
    started = time.perf_counter()
    with pytest.raises(ValueError, match=r"Simulation.run is collective: .*same steps, got rank 0"):
        sim.run(steps=10 + sim.rank)
    with pytest.raises(ValueError, match=r"Simulation.run is collective: .*until"):
        sim.run(until=1e-4 * (1 + sim.rank))
    path = world.bcast(str(tmp_path), root=0)
    with pytest.raises(ValueError, match="Simulation.checkpoint is collective: .*path"):
        sim.checkpoint(f"{path}/state_{sim.rank}.h5")
    sim.run(steps=10)  # agreeing ranks still run
    assert sim.step == 10
    elapsed = world.allreduce(time.perf_counter() - started, op=max_op())
    assert elapsed < 30.0


def test_set_up_calls_that_differ_between_ranks_are_refused_on_every_rank(world):
    """Set-up calls change state every rank must hold alike (particles with global ids, wall
    motion, the time step): different arguments raise the same ValueError everywhere, and a
    bad value on one rank only never leaves the others waiting."""
    sim = settle(world, 500)
    glass = sim.materials[0]
    rank = sim.rank
    position = np.array([[0.001, 0.001, 0.001 + 1e-4 * rank]])
    with pytest.raises(ValueError, match="add_particles is collective: .*same position, got rank"):
        sim.add_particles(position=position, radius=1e-4, material=glass)
    bad = np.array([[np.nan if rank == 1 else 0.001, 0.001, 0.001]])
    with pytest.raises(ValueError, match="add_particles is collective: .*position"):
        sim.add_particles(position=bad, radius=1e-4, material=glass)
    floor = sim.walls[0]
    with pytest.raises(ValueError, match="set_motion is collective: .*velocity"):
        floor.set_motion(velocity=(0.0, 0.0, 1e-3 * rank))
    with pytest.raises(ValueError, match="time_step is collective: .*value"):
        sim.time_step = 1e-6 * (1 + rank)
    with pytest.raises(ValueError, match="remove_particles is collective"):
        sim.remove_particles([rank])
    n = sim.num_particles
    sim.run(steps=5)  # the ranks are still in step, nothing was added or removed
    assert sim.num_particles == n
