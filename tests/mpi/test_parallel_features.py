"""Walls, servo walls, insertion, outlets, output and load balancing behave on any number of
ranks as on one (issue 6)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
from mpi4py import MPI
from mpi_cases import GLASS, relative_difference, settle

import grainscale as gs


def silo(comm) -> tuple[gs.Simulation, gs.insert.StreamHandle, gs.insert.OutletHandle]:
    """A partly filled bin: a packed bed below, a stream pouring in at the top, an outlet."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.03, 0.03, 0.12))
    sim = gs.Simulation(domain=box, time_step=2e-5, skin=2e-4, comm=comm, quiet=True)
    for wall in gs.geometry.box_walls(box, GLASS):
        sim.add_wall(wall)
    ids = sim.insert(
        gs.insert.Pack(
            region=gs.Box(lo=(0, 0, 0), hi=(0.03, 0.03, 0.03)),
            radius=gs.dist.Uniform(0.9e-3, 1.1e-3),
            count=1200,
            material=GLASS,
            seed=4,
        )
    )
    assert len(ids) == 1200
    stream = sim.insert(
        gs.insert.Stream(
            face=gs.insert.DiscFace(centre=(0.015, 0.015, 0.11), normal=(0, 0, -1), radius=0.01),
            radius=gs.dist.Uniform(0.9e-3, 1.1e-3),
            mass_rate=0.05,
            velocity=(0, 0, -1.0),
            material=GLASS,
            seed=9,
        )
    )
    outlet = sim.add_outlet(gs.insert.Outlet(region=gs.Box(lo=(0, 0, 0), hi=(0.03, 0.03, 0.004))))
    return sim, stream, outlet


def test_insertion_walls_and_outlets_match_the_serial_run(world):
    serial, s_stream, s_outlet = silo(MPI.COMM_SELF)
    decomposed, d_stream, d_outlet = silo(world)
    a, b = serial.gather(("position", "radius")), decomposed.gather(("position", "radius"))
    assert np.array_equal(a["id"], b["id"])  # Pack: the same particles on any number of ranks
    assert np.array_equal(a["position"], b["position"]) and np.array_equal(a["radius"], b["radius"])
    for sim in (serial, decomposed):
        sim.run(steps=1500)
    assert d_stream.inserted_count == s_stream.inserted_count > 0
    assert d_stream.pending_count == s_stream.pending_count
    assert d_outlet.removed_count == s_outlet.removed_count
    a, b = serial.gather(("position", "radius")), decomposed.gather(("position", "radius"))
    assert np.array_equal(a["id"], b["id"])  # streamed particles: the same ids and places
    assert relative_difference(a["position"], b["position"], 0.12) <= 1e-10
    floor_a, floor_b = serial.walls[4].force, decomposed.walls[4].force
    assert np.allclose(floor_b, floor_a, rtol=1e-9)


def test_servo_wall_sees_the_global_force(world):
    def press(comm) -> gs.Simulation:
        sim = settle(comm, 2000, seed=2)
        lid = gs.Plane(point=(0, 0, sim.domain.hi[2] - 1e-4), normal=(0, 0, -1), material=GLASS)
        area = float(sim.domain.length[0] * sim.domain.length[1])
        servo = gs.geometry.Servo(
            gain=1.0, max_speed=0.3, target_stress=500, area=area, integral_gain=100.0
        )
        sim.add_wall(lid, servo=servo)
        return sim

    serial, decomposed = press(MPI.COMM_SELF), press(world)
    pressed = 0.0
    for _ in range(8):
        for sim in (serial, decomposed):
            sim.run(steps=500)
        pressed = max(pressed, serial.walls[6].force[2])  # the bed pushes the lid up
    za, zb = serial.walls[6].position[2], decomposed.walls[6].position[2]
    assert za < serial.domain.hi[2] - 5e-3  # the lid moved down onto the bed
    assert pressed > 0  # and pressed on it
    assert abs(zb - za) <= 1e-10 * serial.domain.hi[2]
    assert np.allclose(decomposed.walls[6].force, serial.walls[6].force, rtol=1e-8)
    ia, ib = serial.walls[6].servo_integral, decomposed.walls[6].servo_integral
    assert ia != 0 and abs(ib - ia) <= 1e-8 * abs(ia)  # the PI state follows the global load


def test_vtk_pieces_and_parallel_index(world, shared_tmp):
    sim = settle(world, 1500)
    out = gs.io.VTK(shared_tmp / "vtk", every_steps=50)
    sim.output(out)
    sim.run(steps=100)
    world.Barrier()
    if world.rank == 0:
        pvd = ET.parse(shared_tmp / "vtk" / "particles.pvd").getroot()
        files = [d.get("file") for d in pvd.iter("DataSet")]
        assert files == [f"particles_{s:08d}.pvtp" for s in (0, 50, 100)]
        index = ET.parse(shared_tmp / "vtk" / files[-1]).getroot()
        pieces = [p.get("Source") for p in index.iter("Piece")]
        assert pieces == [f"particles_00000100_r{r}.vtp" for r in range(world.size)]
        names = {a.get("Name") for a in index.iter("PDataArray")} - {None}
        assert {"radius", "velocity", "id", "rank"} <= names
        total = 0
        for piece in pieces:
            root = ET.parse(shared_tmp / "vtk" / piece).getroot()
            total += int(next(root.iter("Piece")).get("NumberOfPoints"))
        assert total == 1500
    world.Barrier()


def test_load_balancing_evens_out_a_partly_filled_box(world):
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.2))
    sim = gs.Simulation(domain=box, time_step=2e-5, comm=world, quiet=True)
    for wall in gs.geometry.box_walls(box, GLASS):
        sim.add_wall(wall)
    sim.insert(
        gs.insert.Pack(
            region=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.04)),
            radius=1e-3,
            count=1000,
            material=GLASS,
            seed=1,
        )
    )
    before = sim.decomposition()["counts"]
    assert max(before) == 1000  # the bed fills the lowest slab only
    report = sim.balance()
    assert report["before"] == world.size
    assert report["after"] < 1.1
    sim.run(steps=50)
    counts = sim.decomposition()["counts"]
    assert sum(counts) == 1000
    assert max(counts) * world.size / 1000 < 1.15
