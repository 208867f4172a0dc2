"""The outputs of issue 26 point 5 on several ranks: the contact network, particle dumps, VTK
user arrays, periodic checkpoints and the log file, each rank writing its piece (or rank 0 the
file), read back as the serial run's (grainscale.io)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
from mpi4py import MPI
from mpi_cases import relative_difference, settle

import grainscale as gs

FIELDS = ("position", "velocity", "angular_velocity", "radius", "id", "material")


def oriented(table: dict) -> dict[tuple[int, int], np.ndarray]:
    """Every contact keyed by (smaller id, larger id) (walls: (id, -1 - wall)), with the force
    on the first."""
    out = {}
    for a, b, f in zip(table["id_i"], table["id_j"], table["force"], strict=True):
        a, b = int(a), int(b)
        out[(a, b) if (b < 0 or a < b) else (b, a)] = f if (b < 0 or a < b) else -f
    return out


def test_contact_network_pieces_read_as_the_serial_network(world, shared_tmp):
    runs = {}
    for name, comm in (("serial", MPI.COMM_SELF), ("ranks", world)):
        out = shared_tmp / (f"serial{world.rank}" if comm is MPI.COMM_SELF else "ranks")
        sim = settle(comm, 600, seed=3)
        sim.output(gs.io.ContactNetwork(out, every_steps=1500))
        sim.run(steps=3000)
        runs[name] = (sim, out)
    sim, out = runs["ranks"]
    tables = gs.io.read_contacts(out)
    assert [t["step"] for t in tables] == [0, 1500, 3000]
    table = tables[-1]
    assert len(table["id_i"]) == sim.num_contacts() > 500
    serial = oriented(gs.io.read_contacts(runs["serial"][1])[-1])
    mine = oriented(table)
    assert set(mine) == set(serial)
    scale = max(float(np.abs(f).max()) for f in serial.values())
    assert max(float(np.abs(mine[k] - serial[k]).max()) for k in serial) <= 1e-8 * scale
    # every rank wrote its piece of the VTK lines; the .pvtp index lists them
    index = out / "contacts_00003000.pvtp"
    root = ET.parse(index).getroot()
    pieces = [p.get("Source") for p in root.iter("Piece")]
    assert pieces == [f"contacts_00003000_r{r}.vtp" for r in range(world.size)]
    names = [a.get("Name") for a in root.find("PPolyData/PCellData")]
    assert {"id_i", "id_j", "force", "normal_force", "overlap"} <= set(names)
    series = ET.parse(out / "contacts.pvd").getroot()
    assert [d.get("file") for d in series.iter("DataSet")][-1] == "contacts_00003000.pvtp"


def test_dump_pieces_read_as_the_gathered_particles(world, shared_tmp):
    out = shared_tmp / "dumps"
    sim = settle(world, 500, seed=2)
    dump = gs.io.Dump(out, every_steps=400, extra={"rank": lambda p: np.full(len(p), world.rank)})
    sim.output(dump)
    sim.run(steps=800)
    snaps = gs.io.read_dump(out)
    assert [s.step for s in snaps] == [0, 400, 800]
    last = snaps[-1]
    assert last.attrs["ranks"] == world.size
    expected = sim.gather(FIELDS)
    for name in FIELDS:
        assert np.array_equal(last[name], expected[name]), name
    counts = np.bincount(last["rank"], minlength=world.size)
    assert counts.tolist() == world.allgather(sim.num_local_particles)
    serial = settle(MPI.COMM_SELF, 500, seed=2)
    serial.run(steps=800)
    alone = serial.gather(FIELDS)
    assert np.array_equal(alone["id"], last["id"])
    assert relative_difference(alone["position"], last["position"], 0.02) <= 1e-10


def test_vtk_user_arrays_in_every_piece(world, shared_tmp):
    out = shared_tmp / "vtk"
    sim = settle(world, 300, seed=4)
    speed = {"speed": lambda p: np.linalg.norm(p.velocity, axis=1)}
    sim.output(gs.io.VTK(out, every_steps=100, fields=["id", "velocity"], extra=speed))
    sim.run(steps=100)
    root = ET.parse(out / "particles_00000100.pvtp").getroot()
    names = [a.get("Name") for a in root.find("PPolyData/PPointData")]
    assert names == ["id", "velocity", "rank", "speed"]


def test_periodic_checkpoints_restart_exactly(world, shared_tmp):
    ck = shared_tmp / "ck"
    # Automatic load balancing at its default (every 500 steps) rebalances in both runs at the
    # same steps: the checkpoint carries its schedule.
    ran = settle(world, 400, seed=5)
    ran.checkpoint_every(ck, every_steps=200, keep=2)
    ran.output(gs.io.VTK(shared_tmp / "vtk_ck", every_steps=200))
    ran.run(steps=600)
    kept = [p.name for p in gs.io.Checkpoints(ck, every_steps=1).kept()]
    assert kept == ["checkpoint_0000000400.h5", "checkpoint_0000000600.h5"]
    ran.run(steps=200)
    again = settle(world, 400, seed=5, particles=False)
    again.restart(gs.io.latest_checkpoint(ck))
    assert again.step == 800
    again.output(gs.io.VTK(shared_tmp / "vtk_ck", every_steps=200))
    ran.run(steps=400)
    again.run(steps=400)
    a, b = ran.gather(FIELDS), again.gather(FIELDS)
    for name in FIELDS:
        assert np.array_equal(a[name], b[name]), name
    series = ET.parse(shared_tmp / "vtk_ck" / "particles.pvd").getroot()
    files = [d.get("file") for d in series.iter("DataSet")]
    assert files == [f"particles_{s:08d}.pvtp" for s in range(0, 1201, 200)]


def test_log_written_by_rank_zero(world, shared_tmp):
    log = shared_tmp / "run.log"
    sim = settle(world, 200, seed=6, thermo_every=100)
    sim.log(log)
    sim.run(steps=300)
    world.Barrier()
    lines = log.read_text().splitlines()
    assert sum("log opened" in line for line in lines) == 1
    assert f"{world.size} rank(s)" in lines[0]
    assert np.loadtxt(log, usecols=range(7))[:, 0].tolist() == [100, 200, 300]
