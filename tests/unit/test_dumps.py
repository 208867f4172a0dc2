"""HDF5 particle dumps (grainscale.io.Dump, read_dump; issue 26 point 5): what is read back is
what the simulation held, sorted by id, whatever wrote it."""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import numpy as np
import pytest
from output_cases import column

import grainscale as gs
from grainscale.io.h5snapshot import read_snapshot, write_snapshot

FIELDS = ("position", "velocity", "angular_velocity", "radius", "id", "material")


def test_dump_reads_back_what_gather_returns(tmp_path: Path) -> None:
    sim, _ = column(n=60)
    speed = {"speed": lambda p: np.linalg.norm(p.velocity, axis=1)}
    dump = gs.io.Dump(tmp_path, every=0.05, extra=speed)
    sim.output(dump)
    sim.run(until=0.12)
    snaps = gs.io.read_dump(tmp_path)
    assert isinstance(snaps, list)
    assert snaps[0].step == 0 and len(snaps) == 3
    assert [round(s.time / 0.05) for s in snaps] == [0, 1, 2]
    assert [s.path for s in snaps] == dump.files
    sim.run(until=0.15)  # the last snapshot (t = 0.15 s) is the state now
    last = gs.io.read_dump(dump.files[-1])
    assert isinstance(last, gs.io.DumpSnapshot)
    assert last.step == sim.step and last.time == sim.time
    expected = sim.gather(FIELDS)
    assert set(last) == {*FIELDS, "speed"}
    for name in FIELDS:
        assert last[name].dtype == expected[name].dtype, name
        assert np.array_equal(last[name], expected[name]), name
    assert np.array_equal(last["speed"], np.linalg.norm(expected["velocity"], axis=1))
    assert len(last) == 60 and np.all(np.diff(last["id"]) > 0)
    assert last.attrs["time_step"] == sim.time_step and last.attrs["dimension"] == 3
    assert last.attrs["materials"][0]["name"] == "glass"
    assert last.attrs["materials"][0]["density"] == 2500.0
    with h5py.File(dump.files[-1]) as f:  # plain h5py reads it too
        assert f.attrs["format"] == "grainscale-dump" and f["position"].shape == (60, 3)


def test_chosen_fields(tmp_path: Path) -> None:
    sim, _ = column(n=10)
    sim.output(gs.io.Dump(tmp_path, every_steps=5, fields=["force", "mass"], prefix="d"))
    sim.run(steps=5)
    snap = gs.io.read_dump(tmp_path / "d_00000005.h5")
    assert isinstance(snap, gs.io.DumpSnapshot)
    assert set(snap) == {"force", "mass", "id"}
    got = sim.gather(("force", "mass"))
    assert np.array_equal(snap["force"], got["force"]) and np.array_equal(snap["mass"], got["mass"])


def test_per_rank_pieces_are_joined(tmp_path: Path) -> None:
    """The layout written under MPI (one piece per rank and an index), read back as one."""
    ids = [np.array([5, 1]), np.array([3, 0, 4])]
    for rank in (1, 0):
        write_snapshot(
            tmp_path,
            "dump_00000007",
            "grainscale-dump",
            {"id": ids[rank], "radius": ids[rank] * 1e-3},
            {"step": 7, "time": 0.25},
            rank,
            2,
        )
    snap = gs.io.read_dump(tmp_path / "dump_00000007.h5")
    assert isinstance(snap, gs.io.DumpSnapshot)
    assert snap.step == 7 and snap.time == 0.25 and snap.attrs["ranks"] == 2
    assert snap["id"].tolist() == [0, 1, 3, 4, 5]
    assert np.array_equal(snap["radius"], snap["id"] * 1e-3)
    assert [s.step for s in gs.io.read_dump(tmp_path)] == [7]  # the pieces are not snapshots
    here = os.getcwd()
    try:  # the index's external links resolve beside the index, from any directory
        os.chdir("/")
        with h5py.File(tmp_path / "dump_00000007.h5") as f:
            assert f["rank_1/id"][()].tolist() == [3, 0, 4]
    finally:
        os.chdir(here)
    with pytest.raises(ValueError, match="is the piece of rank 1 of a snapshot"):
        gs.io.read_dump(tmp_path / "dump_00000007_r1.h5")
    (tmp_path / "dump_00000007_r1.h5").unlink()
    with pytest.raises(ValueError, match="its piece 'dump_00000007_r1.h5' is missing"):
        gs.io.read_dump(tmp_path / "dump_00000007.h5")
    with pytest.raises(ValueError, match="is not a grainscale-contacts file"):
        read_snapshot(tmp_path / "dump_00000007.h5", "grainscale-contacts")


def test_validation(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="Dump needs exactly one of every"):
        gs.io.Dump(tmp_path)
    with pytest.raises(ValueError, match=r"Dump.fields must name particle fields .*, got 'speed'"):
        gs.io.Dump(tmp_path, every=1.0, fields=["speed"])
    with pytest.raises(ValueError, match="Dump.fields names 'radius' twice"):
        gs.io.Dump(tmp_path, every=1.0, fields=["radius", "radius"])
    with pytest.raises(ValueError, match=r"Dump.extra\['radius'\] has the name of a field"):
        gs.io.Dump(tmp_path, every=1.0, extra={"radius": lambda p: p.radius})
    with pytest.raises(ValueError, match=r"Dump.extra\['x'\] must be a callable"):
        gs.io.Dump(tmp_path, every=1.0, extra={"x": 3})
    sim, _ = column(n=4)
    sim.output(gs.io.Dump(tmp_path, every_steps=1, extra={"bad": lambda p: np.zeros(3)}))
    with pytest.raises(ValueError, match=r"Dump.extra\['bad'\] must return one number .* \(4,\)"):
        sim.run(steps=1)
    (tmp_path / "junk.h5").write_bytes(b"not hdf5")
    with pytest.raises(ValueError, match="is not a readable HDF5 file"):
        gs.io.read_dump(tmp_path / "junk.h5")
    with pytest.raises(ValueError, match="no dump files"):
        gs.io.read_dump(tmp_path / "..", prefix="nothing")
    with pytest.raises(ValueError, match="must be a dump file or directory"):
        gs.io.read_dump(tmp_path / "missing.h5")
