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


def test_restart_refusals_and_warnings_reach_every_rank(world, shared_tmp):
    """What a restart refuses (a wall set up elsewhere) or warns about (particles it replaces),
    and a path that cannot be written, are said on every rank: none waits for another."""
    import dataclasses

    import pytest

    n = 200
    path = shared_tmp / "small.h5"
    first = settle(world, n)
    first.run(steps=20)
    first.checkpoint(path)
    populated = settle(world, n, seed=2)
    with pytest.warns(UserWarning, match=rf"replaced the {n} particle\(s\) .* with the {n} of"):
        populated.restart(path)
    assert populated.step == 20 and populated.num_particles == n

    base = settle(world, n, particles=False)
    moved = gs.Simulation(domain=base.domain, contact=base.contact, time_step=1e-5, skin=2e-4,
                          comm=world, quiet=True)  # fmt: skip
    for k, wall in enumerate(base.walls):
        floor = dataclasses.replace(wall.geometry, point=(0.0, 0.0, 0.001))
        moved.add_wall(floor if k == 4 else wall.geometry)
    with pytest.raises(ValueError, match=r"small.h5.*checkpoint wall 4 was set up as Plane"):
        moved.restart(path)
    assert moved.num_particles == 0

    blocker = shared_tmp / "a_file"
    if world.rank == 0:
        blocker.write_text("not a directory")
    world.Barrier()
    with pytest.raises(ValueError, match=r"Simulation.checkpoint.path must be a file path"):
        first.checkpoint(blocker / "c.h5")
