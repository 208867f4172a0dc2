"""Checkpoints across rank counts (issue 6): written on all ranks and read on one, written on one
and read on all, written and read on all (bit-identical); the continuation equals the serial
run."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from mpi_cases import relative_difference, settle

import grainscale as gs

N, STEPS = 3000, 400


def restarted(comm, path) -> gs.Simulation:
    sim = settle(comm, N, particles=False)  # the set-up, as a restart script builds it
    sim.restart(path)
    return sim


def reference(world) -> dict[str, np.ndarray]:
    sim = settle(MPI.COMM_SELF, N)
    sim.run(steps=2 * STEPS)
    return sim.gather()


def test_written_on_all_ranks_read_on_one(world, shared_tmp):
    path = shared_tmp / "all.h5"
    first = settle(world, N)
    first.run(steps=STEPS)
    first.checkpoint(path)
    serial = restarted(MPI.COMM_SELF, path)
    assert serial.num_particles == N and serial.step == STEPS
    serial.run(steps=STEPS)
    ref = reference(world)
    got = serial.gather()
    assert np.array_equal(got["id"], ref["id"])
    assert relative_difference(got["position"], ref["position"], 0.05) <= 1e-10


def test_written_on_one_rank_read_on_all(world, shared_tmp):
    path = shared_tmp / "one.h5"
    if world.rank == 0:
        first = settle(MPI.COMM_SELF, N)
        first.run(steps=STEPS)
        first.checkpoint(path)
    world.Barrier()
    decomposed = restarted(world, path)
    assert decomposed.num_particles == N and decomposed.step == STEPS
    assert sum(decomposed.decomposition()["counts"]) == N
    decomposed.run(steps=STEPS)
    ref = reference(world)
    got = decomposed.gather()
    assert np.array_equal(got["id"], ref["id"])
    assert relative_difference(got["position"], ref["position"], 0.05) <= 1e-10


def test_same_ranks_continue_bit_identically(world, shared_tmp):
    path = shared_tmp / "same.h5"
    straight = settle(world, N)
    straight.run(steps=STEPS)
    straight.checkpoint(path)
    straight.run(steps=STEPS)
    again = restarted(world, path)
    again.run(steps=STEPS)
    a, b = (
        straight.gather(("position", "velocity", "force")),
        again.gather(("position", "velocity", "force")),
    )
    for name in ("position", "velocity", "force"):
        assert np.array_equal(a[name], b[name]), name
