"""Tests of grainscale.io.vtk: VTK XML writers (round trip through an independent parser),
the .pvd index, and the VTK output operation's schedule."""

from __future__ import annotations

import base64
import contextlib
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from grainscale.io import VTK, PVDSeries, write_vtp, write_vtp_mesh

# --------------------------------------------------------------------------------------------
# independent reader for VTK XML PolyData (ascii, base64 "binary", raw appended)
# --------------------------------------------------------------------------------------------

VTK_TO_NUMPY = {
    "Float64": "<f8",
    "Float32": "<f4",
    "Int64": "<i8",
    "Int32": "<i4",
    "Int16": "<i2",
    "Int8": "i1",
    "UInt64": "<u8",
    "UInt32": "<u4",
    "UInt16": "<u2",
    "UInt8": "u1",
}

MODES = {
    "ascii": {"binary": False},
    "base64": {"binary": True},
    "appended": {"binary": True, "appended": True},
}


def _split_appended(raw: bytes) -> tuple[bytes, bytes | None]:
    """Return (xml text, appended blob or None). The blob starts after the '_' marker."""
    start = raw.find(b"<AppendedData")
    if start < 0:
        return raw, None
    head = raw[:start] + b"</VTKFile>"
    tag_end = raw.index(b">", start)
    assert b'encoding="raw"' in raw[start:tag_end]
    marker = raw.index(b"_", tag_end)
    assert raw[tag_end + 1 : marker].strip() == b""
    end = raw.rindex(b"</AppendedData>")
    return head, raw[marker + 1 : end]


def _decode(da: ET.Element, blob: bytes | None) -> np.ndarray:
    dtype = np.dtype(VTK_TO_NUMPY[da.get("type")])
    ncomp = int(da.get("NumberOfComponents", "1"))
    fmt = da.get("format")
    if fmt == "ascii":
        tokens = (da.text or "").split()
        if dtype.kind == "f":
            values = np.array([float(t) for t in tokens], dtype=dtype)
        else:
            values = np.array([int(t) for t in tokens], dtype=dtype)
    elif fmt == "binary":
        data = base64.b64decode("".join((da.text or "").split()), validate=True)
        nbytes = int(np.frombuffer(data[:8], dtype="<u8")[0])
        assert nbytes == len(data) - 8, "UInt64 header must equal the byte count"
        values = np.frombuffer(data[8:], dtype=dtype)
    elif fmt == "appended":
        assert blob is not None
        off = int(da.get("offset"))
        nbytes = int(np.frombuffer(blob[off : off + 8], dtype="<u8")[0])
        values = np.frombuffer(blob[off + 8 : off + 8 + nbytes], dtype=dtype)
        assert len(values) * dtype.itemsize == nbytes
    else:
        raise AssertionError(f"unknown format {fmt}")
    return values.reshape(-1, ncomp) if ncomp > 1 else values


def read_vtp(path: Path) -> dict:
    """Parse a .vtp file into plain numpy arrays, checking the header attributes."""
    head, blob = _split_appended(Path(path).read_bytes())
    root = ET.fromstring(head)
    assert root.tag == "VTKFile"
    assert root.get("type") == "PolyData"
    assert root.get("byte_order") == "LittleEndian"
    assert root.get("header_type") == "UInt64"
    assert root.get("version") == "1.0"
    pieces = root.findall("./PolyData/Piece")
    assert len(pieces) == 1
    piece = pieces[0]
    out: dict = {"counts": {k: int(v) for k, v in piece.attrib.items()}}
    out["points"] = _decode(piece.find("./Points/DataArray"), blob)
    for section in ("PointData", "CellData"):
        node = piece.find(section)
        out[section] = (
            {}
            if node is None
            else {da.get("Name"): _decode(da, blob) for da in node.findall("DataArray")}
        )
    for cells in ("Verts", "Lines", "Strips", "Polys"):
        node = piece.find(cells)
        if node is not None:
            arrays = {da.get("Name"): _decode(da, blob) for da in node.findall("DataArray")}
            out[cells] = (arrays["connectivity"], arrays["offsets"])
    return out


def read_pvd(path: Path) -> list[tuple[float, str, int]]:
    root = ET.parse(path).getroot()
    assert root.get("type") == "Collection"
    return [
        (float(ds.get("timestep")), ds.get("file"), int(ds.get("part")))
        for ds in root.findall("./Collection/DataSet")
    ]


def _sample(n: int = 9, seed: int = 3) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3)) * 1e-3
    points[0] = [1e-300, -0.0, math.pi]  # values that a lossy formatter would change
    points[1] = [5e-324, 1.0 / 3.0, -1.7976931348623157e308]
    data = {
        "radius": rng.uniform(1e-4, 2e-3, n),
        "velocity": rng.normal(size=(n, 3)),
        "id": np.arange(n, dtype=np.int64) * 3 + 2**53 + 1,  # not representable as float64
        "material": (np.arange(n) % 4).astype(np.int32) - 1,
        "f32": rng.normal(size=n).astype(np.float32),
        "tensor": rng.normal(size=(n, 9)),
    }
    return points, data


# --------------------------------------------------------------------------------------------
# write_vtp / write_vtp_mesh
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", list(MODES))
def test_write_vtp_round_trip_exact(tmp_path: Path, mode: str) -> None:
    points, data = _sample()
    path = tmp_path / "p.vtp"
    write_vtp(path, points, data, **MODES[mode])
    got = read_vtp(path)

    n = len(points)
    assert got["counts"]["NumberOfPoints"] == n
    assert got["counts"]["NumberOfVerts"] == n
    assert got["counts"]["NumberOfPolys"] == 0
    assert got["points"].dtype == np.float64
    np.testing.assert_array_equal(got["points"], points)
    assert np.signbit(got["points"][0, 1])  # -0.0 kept
    assert set(got["PointData"]) == set(data)
    for name, expected in data.items():
        value = got["PointData"][name]
        assert value.dtype == expected.dtype, name
        assert value.shape == expected.shape, name
        np.testing.assert_array_equal(value, expected, err_msg=name)
    # one vertex cell per point
    connectivity, offsets = got["Verts"]
    np.testing.assert_array_equal(connectivity, np.arange(n))
    np.testing.assert_array_equal(offsets, np.arange(1, n + 1))


@pytest.mark.parametrize("mode", list(MODES))
def test_write_vtp_empty_and_bool(tmp_path: Path, mode: str) -> None:
    path = tmp_path / "e.vtp"
    write_vtp(path, np.zeros((0, 3)), {"radius": np.zeros(0)}, **MODES[mode])
    got = read_vtp(path)
    assert got["counts"]["NumberOfPoints"] == 0
    assert got["points"].size == 0
    assert got["PointData"]["radius"].size == 0

    write_vtp(path, np.ones((3, 3)), {"flag": np.array([True, False, True])}, **MODES[mode])
    flag = read_vtp(path)["PointData"]["flag"]
    assert flag.dtype == np.uint8
    np.testing.assert_array_equal(flag, [1, 0, 1])


def test_write_vtp_encodings_differ(tmp_path: Path) -> None:
    points, data = _sample()
    texts = {}
    for mode, kwargs in MODES.items():
        write_vtp(tmp_path / f"{mode}.vtp", points, data, **kwargs)
        texts[mode] = (tmp_path / f"{mode}.vtp").read_bytes()
    assert b'format="ascii"' in texts["ascii"] and b'format="binary"' not in texts["ascii"]
    assert b'format="binary"' in texts["base64"] and b"AppendedData" not in texts["base64"]
    assert b'format="appended"' in texts["appended"] and b'encoding="raw"' in texts["appended"]
    # raw appended data is the plain little-endian bytes of the arrays
    assert data["velocity"].astype("<f8").tobytes() in texts["appended"]


def test_write_vtp_atomic_overwrite(tmp_path: Path) -> None:
    path = tmp_path / "p.vtp"
    write_vtp(path, np.zeros((5, 3)), {"a": np.arange(5)})
    write_vtp(path, np.ones((2, 3)), {"a": np.arange(2)})
    got = read_vtp(path)
    np.testing.assert_array_equal(got["points"], np.ones((2, 3)))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.vtp"]  # no temporary files left


def test_write_vtp_failed_write_leaves_old_file(tmp_path: Path) -> None:
    path = tmp_path / "p.vtp"
    write_vtp(path, np.zeros((2, 3)), {"a": np.arange(2)})
    before = path.read_bytes()
    with pytest.raises(ValueError, match=r"'a' must have shape \(2,\)"):
        write_vtp(path, np.zeros((2, 3)), {"a": np.arange(3)})
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.vtp"]


def test_write_vtp_rejects_bad_input(tmp_path: Path) -> None:
    path = tmp_path / "bad.vtp"
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        write_vtp(path, np.zeros((4, 2)))
    with pytest.raises(TypeError, match="unsupported dtype"):
        write_vtp(path, np.zeros((2, 3)), {"c": np.zeros(2, dtype=complex)})
    with pytest.raises(ValueError, match="appended=True requires binary=True"):
        write_vtp(path, np.zeros((2, 3)), binary=False, appended=True)
    assert not path.exists()


@pytest.mark.parametrize("mode", list(MODES))
def test_write_vtp_mesh_round_trip(tmp_path: Path, mode: str) -> None:
    vertices = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0.1, 0.1, 0.05]])
    triangles = np.array([[0, 1, 2], [1, 3, 2]], dtype=np.int32)
    cell_data = {"force": np.array([[1.5, -2.0, 3.25], [0.0, 1e-9, 7.0]]), "wall": np.int32([4, 9])}
    path = tmp_path / "wall.vtp"
    write_vtp_mesh(path, vertices, triangles, cell_data=cell_data, **MODES[mode])
    got = read_vtp(path)
    assert got["counts"]["NumberOfPoints"] == 4
    assert got["counts"]["NumberOfPolys"] == 2
    assert got["counts"]["NumberOfVerts"] == 0
    np.testing.assert_array_equal(got["points"], vertices)
    connectivity, offsets = got["Polys"]
    np.testing.assert_array_equal(connectivity, [0, 1, 2, 1, 3, 2])
    np.testing.assert_array_equal(offsets, [3, 6])
    for name, expected in cell_data.items():
        assert got["CellData"][name].dtype == expected.dtype
        np.testing.assert_array_equal(got["CellData"][name], expected)
    assert got["PointData"] == {}


def test_write_vtp_mesh_rejects_bad_triangles(tmp_path: Path) -> None:
    vertices = np.zeros((3, 3))
    with pytest.raises(ValueError, match=r"\(T, 3\)"):
        write_vtp_mesh(tmp_path / "m.vtp", vertices, np.array([[0, 1]]))
    with pytest.raises(ValueError, match=r"in \[0, 3\)"):
        write_vtp_mesh(tmp_path / "m.vtp", vertices, np.array([[0, 1, 3]]))
    with pytest.raises(ValueError, match=r"'force' must have shape \(1,\)"):
        write_vtp_mesh(tmp_path / "m.vtp", vertices, [[0, 1, 2]], cell_data={"force": np.ones(3)})


# --------------------------------------------------------------------------------------------
# PVDSeries
# --------------------------------------------------------------------------------------------


def test_pvd_series_rewritten_after_each_add(tmp_path: Path) -> None:
    series = PVDSeries(tmp_path / "sub" / "run.pvd")
    series.add(0.0, "a_0.vtp")
    assert read_pvd(tmp_path / "sub" / "run.pvd") == [(0.0, "a_0.vtp", 0)]
    series.add(0.1 + 0.2, "a_1.vtp")
    series.add(0.5, "b_1.vtp", part=1)
    assert read_pvd(tmp_path / "sub" / "run.pvd") == [
        (0.0, "a_0.vtp", 0),
        (0.30000000000000004, "a_1.vtp", 0),  # time kept exactly
        (0.5, "b_1.vtp", 1),
    ]
    series.add(0.25, "a_1.vtp")  # same file and part: replaced, not duplicated
    assert read_pvd(tmp_path / "sub" / "run.pvd") == [
        (0.0, "a_0.vtp", 0),
        (0.5, "b_1.vtp", 1),
        (0.25, "a_1.vtp", 0),
    ]
    assert sorted(p.name for p in (tmp_path / "sub").iterdir()) == ["run.pvd"]


def test_pvd_series_escapes_file_names(tmp_path: Path) -> None:
    series = PVDSeries(tmp_path / "x.pvd")
    series.add(1.0, 'we"ird&<name>.vtp')
    assert read_pvd(tmp_path / "x.pvd") == [(1.0, 'we"ird&<name>.vtp', 0)]


# --------------------------------------------------------------------------------------------
# VTK output operation
# --------------------------------------------------------------------------------------------


class FakeParticles:
    """Mimics the zero-copy view: fields are unusable after the ``with`` block."""

    def __init__(self, fields: dict[str, np.ndarray]) -> None:
        self._fields = fields
        self._open = True

    def __getattr__(self, name: str) -> np.ndarray:
        fields = self.__dict__["_fields"]
        if name not in fields:
            raise AttributeError(name)
        if not self.__dict__["_open"]:
            raise RuntimeError("particle view used outside its with block")
        return fields[name]


class FakeSim:
    """Minimal stand-in for grainscale.Simulation: step, time, time_step and particles()."""

    def __init__(self, n: int = 6, time_step: float = 1e-5, torque: bool = True) -> None:
        rng = np.random.default_rng(11)
        self.step = 0
        self.time = 0.0
        self.time_step = time_step
        self.fields = {
            "position": rng.uniform(0, 0.1, (n, 3)),
            "velocity": rng.normal(size=(n, 3)),
            "angular_velocity": rng.normal(size=(n, 3)),
            "force": rng.normal(size=(n, 3)),
            "radius": rng.uniform(1e-3, 2e-3, n),
            "mass": rng.uniform(1e-5, 2e-5, n),
            "id": np.arange(n, dtype=np.int64)[::-1] + 100,
            "material": (np.arange(n) % 2).astype(np.int32),
        }
        if torque:
            self.fields["torque"] = rng.normal(size=(n, 3))

    @contextlib.contextmanager
    def particles(self, writable: bool = True):
        view = FakeParticles(self.fields)
        try:
            yield view
        finally:
            view._open = False

    def advance(self) -> None:
        self.step += 1
        self.time += self.time_step  # accumulated, with round-off, as an integrator would


def drive(vtk: VTK, sim: FakeSim, until_step: int) -> list[int]:
    """Run the output protocol the way Simulation.run() does; return the steps written."""
    written = []
    due = vtk.next_step(sim.step, sim.time, sim.time_step)
    while True:
        assert due >= sim.step
        if sim.step == due:
            vtk.write(sim)
            written.append(sim.step)
            due = vtk.next_step(sim.step, sim.time, sim.time_step)
            assert due > sim.step, "must not ask to write twice at the same step"
        if sim.step >= until_step:
            return written
        sim.advance()


def test_vtk_every_steps_schedule(tmp_path: Path) -> None:
    vtk = VTK(tmp_path, every_steps=100)
    assert vtk.next_step(0, 0.0, 1e-5) == 0  # first call writes at once
    assert vtk.next_step(0, 0.0, 1e-5) == 0  # still due: nothing written yet
    assert drive(vtk, FakeSim(), 350) == [0, 100, 200, 300]
    assert vtk.next_step(350, 0.0035, 1e-5) == 400
    assert vtk.next_step(400, 0.004, 1e-5) == 400


def test_vtk_every_steps_attached_late(tmp_path: Path) -> None:
    sim = FakeSim()
    sim.step, sim.time = 150, 150 * sim.time_step
    vtk = VTK(tmp_path, every_steps=100)
    assert drive(vtk, sim, 420) == [150, 200, 300, 400]


def test_vtk_every_time_schedule_exact_multiple(tmp_path: Path) -> None:
    # every is an exact multiple of dt in real numbers but not in floating point
    sim = FakeSim(time_step=1e-5)
    written = drive(VTK(tmp_path, every=1e-3), sim, 520)
    assert written == [0, 100, 200, 300, 400, 500]


def test_vtk_every_time_schedule_rounds_up(tmp_path: Path) -> None:
    # dt = 0.3 ms, every = 1 ms: first step with time >= n ms
    sim = FakeSim(time_step=3e-4)
    written = drive(VTK(tmp_path, every=1e-3), sim, 20)
    expected = [0] + [math.ceil(n / 0.3 - 1e-9) for n in range(1, 7)]
    assert expected == [0, 4, 7, 10, 14, 17, 20]
    assert written == expected


def test_vtk_every_time_attached_late(tmp_path: Path) -> None:
    sim = FakeSim(time_step=1e-4)
    sim.step, sim.time = 123, 0.0123
    vtk = VTK(tmp_path, every=0.01)
    assert vtk.next_step(sim.step, sim.time, sim.time_step) == 123
    assert drive(vtk, sim, 330) == [123, 200, 300]


def test_vtk_every_shorter_than_time_step(tmp_path: Path) -> None:
    # several output times per step: one snapshot per step, none duplicated
    sim = FakeSim(time_step=0.25)
    assert drive(VTK(tmp_path, every=0.1), sim, 4) == [0, 1, 2, 3, 4]


def test_vtk_every_follows_time_step_change(tmp_path: Path) -> None:
    vtk = VTK(tmp_path, every=1.0)
    sim = FakeSim(time_step=0.1)
    assert drive(vtk, sim, 10) == [0, 10]
    assert vtk.next_step(10, 1.0, 0.1) == 20
    assert vtk.next_step(10, 1.0, 0.5) == 12  # next output at t = 2 s with the new step


def test_vtk_write_contents_and_pvd(tmp_path: Path) -> None:
    out = tmp_path / "new" / "dir"
    sim = FakeSim(n=6, time_step=1e-3)
    vtk = VTK(out, every_steps=2, prefix="grains")
    assert drive(vtk, sim, 5) == [0, 2, 4]

    names = ["grains_00000000.vtp", "grains_00000002.vtp", "grains_00000004.vtp"]
    assert vtk.files == [out / n for n in names]
    assert sorted(p.name for p in out.iterdir()) == sorted(names + ["grains.pvd"])
    entries = read_pvd(out / "grains.pvd")
    assert [e[1] for e in entries] == names
    assert [e[0] for e in entries] == [0.0, sim.time_step * 2, sim.time_step * 4]
    assert [e[2] for e in entries] == [0, 0, 0]

    got = read_vtp(out / names[-1])
    f = sim.fields
    np.testing.assert_array_equal(got["points"], f["position"])
    expected = {
        name: f[name]
        for name in (
            "radius",
            "velocity",
            "angular_velocity",
            "force",
            "torque",
            "id",
            "material",
            "mass",
        )
    }
    assert set(got["PointData"]) == set(expected)
    for name, value in expected.items():
        assert got["PointData"][name].dtype == value.dtype, name
        np.testing.assert_array_equal(got["PointData"][name], value, err_msg=name)
    assert got["counts"]["NumberOfVerts"] == 6


@pytest.mark.parametrize("mode", list(MODES))
def test_vtk_write_without_torque(tmp_path: Path, mode: str) -> None:
    sim = FakeSim(torque=False)
    sim.step, sim.time = 7, 0.5
    vtk = VTK(tmp_path, every=1.0, **MODES[mode])
    path = vtk.write(sim)
    assert path == tmp_path / "particles_00000007.vtp"
    got = read_vtp(path)
    assert "torque" not in got["PointData"]
    np.testing.assert_array_equal(got["PointData"]["id"], sim.fields["id"])
    assert read_pvd(tmp_path / "particles.pvd") == [(0.5, "particles_00000007.vtp", 0)]


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({}, "exactly one of every"),
        ({"every": 0.1, "every_steps": 10}, "exactly one of every"),
        ({"every_steps": 0}, "VTK.every_steps must be a positive integer, got 0"),
        ({"every_steps": -5}, "VTK.every_steps must be a positive integer, got -5"),
        ({"every_steps": 2.5}, "VTK.every_steps must be a positive integer, got 2.5"),
        ({"every_steps": True}, "VTK.every_steps must be a positive integer, got True"),
        ({"every": 0.0}, r"VTK.every must be a positive finite time in s, got 0.0"),
        ({"every": -1}, r"VTK.every must be a positive finite time in s, got -1"),
        ({"every": math.inf}, r"VTK.every must be a positive finite time in s, got inf"),
        ({"every": "1"}, r"VTK.every must be a positive finite time in s, got '1'"),
        ({"every": 1, "prefix": ""}, "VTK.prefix must be a non-empty file name"),
        ({"every": 1, "prefix": "a/b"}, "VTK.prefix must be a non-empty file name"),
        ({"every": 1, "binary": False, "appended": True}, "VTK.appended=True requires binary"),
    ],
)
def test_vtk_validation(tmp_path: Path, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        VTK(tmp_path, **kwargs)


def test_vtk_accepts_numpy_numbers(tmp_path: Path) -> None:
    assert VTK(tmp_path, every_steps=np.int64(5)).every_steps == 5
    assert VTK(tmp_path, every=np.float32(0.5)).every == 0.5
    assert not (tmp_path / "particles.pvd").exists()  # nothing written before write()
