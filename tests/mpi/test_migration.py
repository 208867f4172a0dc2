"""Migration with contact histories (issue 6): a settled bed in a box periodic in x and y, set
sliding along x over a floor that holds it back by friction (so it shears), carries its
particles across the rank boundaries (cut along x) and the periodic boundary; the tangential
forces of its contacts stay those of the serial run.

Both runs start from one checkpoint of the settled bed (the decomposed one reads it with its
contact histories redistributed): settling itself is chaotic, and after thousands of steps of
it the round-off of differently ordered force sums has grown to visible differences."""

from __future__ import annotations

import numpy as np
from mpi4py import MPI
from mpi_cases import GLASS

import grainscale as gs


def sheared_packing(comm, grid=None, particles: bool = True) -> gs.Simulation:
    box = gs.Box(lo=(0, 0, 0), hi=(0.024, 0.012, 0.012), periodic=(True, True, False))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        gravity=(0, 0, -9.81),
        time_step=1e-5,
        skin=2e-4,
        comm=comm,
        processor_grid=grid,
        quiet=True,
        record_contacts=True,
    )
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    if not particles:
        return sim
    sim.insert(
        gs.insert.Pack(
            region=gs.Box(lo=(0, 0, 0), hi=(0.024, 0.012, 0.012)),
            radius=gs.dist.Uniform(0.9e-3, 1.0e-3),
            count=300,
            material=GLASS,
            seed=7,
        )
    )
    return sim


def set_moving(sim: gs.Simulation) -> None:
    """The bed slides along x at 0.6 m/s."""
    with sim.particles() as p:
        p.velocity[:, 0] = 0.6


def gathered_contacts(sim: gs.Simulation) -> dict[tuple[int, int], np.ndarray]:
    c = sim.contacts()
    local = {(int(i), int(j)): f for i, j, f in zip(c["id_i"], c["id_j"], c["force"], strict=True)}
    if sim.comm is None:
        return local
    merged: dict[tuple[int, int], np.ndarray] = {}
    for part in sim.comm.allgather(local):
        assert not set(part) & set(merged)  # every contact computed on one rank only
        merged.update(part)
    return merged


def test_sheared_periodic_packing_keeps_tangential_forces(world, shared_tmp):
    path = shared_tmp / "settled.h5"
    if world.rank == 0:
        bed = sheared_packing(MPI.COMM_SELF)
        bed.run(steps=6000)
        bed.checkpoint(path)
    world.Barrier()
    serial = sheared_packing(MPI.COMM_SELF, particles=False)
    decomposed = sheared_packing(world, grid=(world.size, 1, 1), particles=False)
    for sim in (serial, decomposed):
        sim.restart(path)
        set_moving(sim)
    owner_before = owners(decomposed)
    for sim in (serial, decomposed):
        sim.run(steps=1000)
    moved = sum(owners(decomposed)[k] != r for k, r in owner_before.items())
    assert moved > 50  # particles did migrate (and crossed the periodic boundary)
    a, b = gathered_contacts(serial), gathered_contacts(decomposed)
    assert len(a) > 150
    # Contacts that just open or close may differ by the round-off of the force sums; every
    # other contact is in both runs.
    scale = max(np.abs(f).max() for f in a.values())
    for key in set(a) ^ set(b):
        force = a[key] if key in a else b[key]
        assert np.abs(force).max() <= 1e-6 * scale, key
    pairs = [k for k in set(a) & set(b) if k[1] >= 0]  # particle-particle contacts
    fa = np.array([a[k] for k in pairs])
    fb = np.array([b[k] for k in pairs])
    normal = serial.gather(("position",))  # tangential part: remove the normal component
    pos = dict(zip(normal["id"], normal["position"], strict=True))
    box = serial.domain.length
    n = []
    for i, j in pairs:
        d = pos[i] - pos[j]
        d[:2] -= box[:2] * np.round(d[:2] / box[:2])  # nearest periodic image
        n.append(d / np.linalg.norm(d))
    n = np.array(n)
    ta = fa - np.sum(fa * n, axis=1)[:, None] * n
    tb = fb - np.sum(fb * n, axis=1)[:, None] * n
    scale = np.abs(ta).max()
    assert scale > 0 and np.abs(tb - ta).max() <= 1e-9 * scale
    assert np.median(np.linalg.norm(ta, axis=1)) > 1e-3 * scale  # the springs are loaded


def owners(sim: gs.Simulation) -> dict[int, int]:
    with sim.particles(writable=False) as p:
        local = {int(i): sim.rank for i in p.id}
    merged: dict[int, int] = {}
    for part in sim.comm.allgather(local) if sim.comm is not None else [local]:
        merged.update(part)
    return merged
