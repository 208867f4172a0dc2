"""ParaView output without the VTK library: VTK XML PolyData (.vtp) and .pvd time series.

Low-level writers (pure numpy):

* :func:`write_vtp` - points with point data, one vertex cell per point (Verts), so ParaView
  renders them directly (use a Glyph filter scaled by ``radius`` for spheres).
* :func:`write_vtp_mesh` - a triangle surface (Polys) with optional cell / point data.
* :class:`PVDSeries` - the .pvd "Collection" index that ParaView opens as one time series.
* :func:`write_pvtp` - the parallel index (.pvtp) of per-rank pieces of one snapshot.

The output operation used by ``Simulation.output()`` is :class:`VTK`.

Files follow the VTK XML format (version 1.0, ``byte_order="LittleEndian"``,
``header_type="UInt64"``). Data arrays are written in one of three encodings:

* ``binary=True`` (default): base64 inline, each array is ``base64(UInt64 byte count + data)``;
* ``binary=True, appended=True``: raw binary in an ``<AppendedData encoding="raw">`` section
  (smallest and fastest; each block is ``UInt64 byte count + data``, ``offset`` is counted
  from the byte after the ``_`` marker);
* ``binary=False``: ASCII, values printed with full round-trip precision.

Every file is written to a temporary file in the same directory and moved into place with
:func:`os.replace`, so a reader never sees a partly written file.
"""

from __future__ import annotations

import base64
import math
import numbers
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .wall_surfaces import wall_surfaces

_ATTRIBUTE_ESCAPES = str.maketrans(
    {
        "&": "&amp;",
        "<": "&lt;",
        ">": "&gt;",
        '"': "&quot;",
        "\n": "&#10;",
        "\r": "&#13;",
        "\t": "&#9;",
    }
)


def _quoteattr(value: str) -> str:
    """``value`` as a double-quoted XML attribute (&, <, >, " and whitespace escaped). Written
    here because xml.sax.saxutils pulls in urllib, http, email and ssl (about 6.6 MiB of peak
    memory and 25 ms at import)."""
    return '"' + value.translate(_ATTRIBUTE_ESCAPES) + '"'


__all__ = ["VTK", "PVDSeries", "write_pvtp", "write_vtp", "write_vtp_mesh"]

PathLike = str | os.PathLike

# numpy dtype kind+size -> VTK XML type name. bool is stored as UInt8 (VTK has no bool type).
_VTK_TYPES: dict[np.dtype, str] = {
    np.dtype(np.float64): "Float64",
    np.dtype(np.float32): "Float32",
    np.dtype(np.int64): "Int64",
    np.dtype(np.int32): "Int32",
    np.dtype(np.int16): "Int16",
    np.dtype(np.int8): "Int8",
    np.dtype(np.uint64): "UInt64",
    np.dtype(np.uint32): "UInt32",
    np.dtype(np.uint16): "UInt16",
    np.dtype(np.uint8): "UInt8",
}
_HEADER_DTYPE = np.dtype("<u8")  # header_type="UInt64"


# --------------------------------------------------------------------------------------------
# atomic file writing
# --------------------------------------------------------------------------------------------


def _atomic_write(path: PathLike, chunks: list[bytes]) -> None:
    """Write ``chunks`` to ``path`` via a temporary sibling file and :func:`os.replace`."""
    path = os.fspath(path)
    tmp = f"{path}.tmp.{os.getpid()}"
    try:
        with open(tmp, "wb") as f:
            for chunk in chunks:
                f.write(chunk)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise


# --------------------------------------------------------------------------------------------
# DataArray encoding
# --------------------------------------------------------------------------------------------


def _as_vtk_array(name: str, values: Any, n: int) -> np.ndarray:
    """Validate one data array: shape (n,) or (n, k), supported dtype, little-endian, C order."""
    arr = np.asarray(values)
    if arr.dtype == np.bool_:
        arr = arr.astype(np.uint8)
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise ValueError(f"data array {name!r} must have shape ({n},) or ({n}, k), got {arr.shape}")
    if arr.ndim == 2 and arr.shape[1] < 1:
        raise ValueError(f"data array {name!r} must have at least one component, got {arr.shape}")
    native = arr.dtype.newbyteorder("=")
    if native not in _VTK_TYPES:
        raise TypeError(f"data array {name!r} has unsupported dtype {arr.dtype}")
    return np.ascontiguousarray(arr, dtype=native.newbyteorder("<"))


def _ascii_values(arr: np.ndarray) -> str:
    """Whitespace separated values; ``repr`` of Python floats round-trips exactly."""
    flat = arr.reshape(-1).tolist()
    if arr.dtype.kind == "f":
        return " ".join(map(repr, flat))
    return " ".join(map(str, flat))


class _ArrayEncoder:
    """Builds ``<DataArray>`` elements and, for the appended encoding, the raw data blob."""

    def __init__(self, binary: bool, appended: bool) -> None:
        if appended and not binary:
            raise ValueError("appended=True requires binary=True")
        self.binary = binary
        self.appended = appended
        self.blocks: list[bytes] = []
        self.offset = 0

    def element(self, name: str, arr: np.ndarray, indent: str) -> str:
        """Return the XML for one DataArray (``arr`` already validated by _as_vtk_array)."""
        ncomp = 1 if arr.ndim == 1 else arr.shape[1]
        head = (
            f"{indent}<DataArray type={_quoteattr(_VTK_TYPES[arr.dtype.newbyteorder('=')])} "
            f'Name={_quoteattr(name)} NumberOfComponents="{ncomp}"'
        )
        if not self.binary:
            return f'{head} format="ascii">\n{_ascii_values(arr)}\n{indent}</DataArray>\n'
        header = np.array([arr.nbytes], dtype=_HEADER_DTYPE).tobytes()
        if self.appended:
            block = header + arr.tobytes()
            text = f'{head} format="appended" offset="{self.offset}"/>\n'
            self.blocks.append(block)
            self.offset += len(block)
            return text
        data = base64.b64encode(header + arr.tobytes()).decode("ascii")
        return f'{head} format="binary">\n{data}\n{indent}</DataArray>\n'


def _data_section(
    tag: str, data: Mapping[str, Any] | None, n: int, enc: _ArrayEncoder, indent: str
) -> str:
    """``<PointData>`` / ``<CellData>`` with one DataArray per entry of ``data``."""
    if not data:
        return f"{indent}<{tag}/>\n"
    parts = [f"{indent}<{tag}>\n"]
    for name, values in data.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"data array names must be non-empty strings, got {name!r}")
        parts.append(enc.element(name, _as_vtk_array(name, values, n), indent + "  "))
    parts.append(f"{indent}</{tag}>\n")
    return "".join(parts)


def _write_polydata(
    path: PathLike,
    points: Any,
    cell_kind: str,
    connectivity: np.ndarray,
    offsets: np.ndarray,
    point_data: Mapping[str, Any] | None,
    cell_data: Mapping[str, Any] | None,
    binary: bool,
    appended: bool,
) -> None:
    """Write a PolyData file whose cells are all of one section (``Verts`` or ``Polys``)."""
    pts = np.asarray(points)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {pts.shape}")
    if pts.dtype != np.float32:
        pts = pts.astype(np.float64)
    n_points = pts.shape[0]
    n_cells = offsets.shape[0]
    counts = {"Verts": 0, "Lines": 0, "Strips": 0, "Polys": 0}
    counts[cell_kind] = n_cells

    enc = _ArrayEncoder(binary, appended)
    piece_attrs = " ".join(f'NumberOf{k}="{v}"' for k, v in counts.items())
    xml = [
        '<?xml version="1.0"?>\n',
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n',
        "  <PolyData>\n",
        f'    <Piece NumberOfPoints="{n_points}" {piece_attrs}>\n',
        _data_section("PointData", point_data, n_points, enc, "      "),
        _data_section("CellData", cell_data, n_cells, enc, "      "),
        "      <Points>\n",
        enc.element("Points", _as_vtk_array("Points", pts, n_points), "        "),
        "      </Points>\n",
        f"      <{cell_kind}>\n",
        enc.element(
            "connectivity",
            _as_vtk_array("connectivity", connectivity, connectivity.size),
            "        ",
        ),
        enc.element("offsets", _as_vtk_array("offsets", offsets, n_cells), "        "),
        f"      </{cell_kind}>\n",
        "    </Piece>\n",
        "  </PolyData>\n",
    ]
    chunks = ["".join(xml).encode("utf-8")]
    if appended:
        chunks.append(b'  <AppendedData encoding="raw">\n   _')
        chunks.extend(enc.blocks)
        chunks.append(b"\n  </AppendedData>\n")
    chunks.append(b"</VTKFile>\n")
    _atomic_write(path, chunks)


# --------------------------------------------------------------------------------------------
# public writers
# --------------------------------------------------------------------------------------------


def write_vtp(
    path: PathLike,
    points: Any,
    point_data: Mapping[str, Any] | None = None,
    binary: bool = True,
    appended: bool = False,
) -> None:
    """Write points as VTK XML PolyData with one vertex cell per point.

    Args:
        path: output file, conventionally ``*.vtp``.
        points: (N, 3) coordinates (float64, or float32 kept as is), in m for grainscale.
        point_data: name -> (N,) scalar or (N, k) k-component array (e.g. velocity, m/s).
            float64/float32/int64/int32 (and other fixed-size ints) are stored with their own
            type, bool as UInt8.
        binary: base64 inline binary (True) or ASCII (False).
        appended: with ``binary=True``, store raw binary in an ``<AppendedData>`` section
            instead of base64 inline.
    """
    n = np.shape(points)[0] if np.ndim(points) >= 1 else 0
    connectivity = np.arange(n, dtype=np.int64)
    offsets = np.arange(1, n + 1, dtype=np.int64)
    _write_polydata(
        path, points, "Verts", connectivity, offsets, point_data, None, binary, appended
    )


def write_vtp_mesh(
    path: PathLike,
    vertices: Any,
    triangles: Any,
    cell_data: Mapping[str, Any] | None = None,
    point_data: Mapping[str, Any] | None = None,
    binary: bool = True,
    appended: bool = False,
) -> None:
    """Write a triangle surface as VTK XML PolyData (triangles in the ``Polys`` section).

    Args:
        path: output file, conventionally ``*.vtp``.
        vertices: (V, 3) vertex coordinates, m.
        triangles: (T, 3) integer vertex indices (0-based, each in [0, V)).
        cell_data: name -> (T,) or (T, k) array, one value per triangle (e.g. force, N).
        point_data: name -> (V,) or (V, k) array, one value per vertex.
        binary, appended: encoding, as in :func:`write_vtp`.
    """
    tri = np.asarray(triangles)
    if tri.ndim != 2 or tri.shape[1] != 3 or (tri.size and tri.dtype.kind not in "iu"):
        raise ValueError(f"triangles must be an integer array of shape (T, 3), got {tri.shape}")
    n_vertices = np.shape(vertices)[0] if np.ndim(vertices) >= 1 else 0
    tri = tri.astype(np.int64)
    if tri.size and (tri.min() < 0 or tri.max() >= n_vertices):
        raise ValueError(f"triangle vertex indices must be in [0, {n_vertices})")
    offsets = np.arange(1, tri.shape[0] + 1, dtype=np.int64) * 3
    _write_polydata(
        path, vertices, "Polys", tri.reshape(-1), offsets, point_data, cell_data, binary, appended
    )


def write_pvtp(
    path: PathLike, pieces: list[str], point_data: Mapping[str, Any], points_dtype: Any = np.float64
) -> None:
    """Write the parallel index (PPolyData) of a snapshot written as one .vtp piece per rank.

    Args:
        path: output file, conventionally ``*.pvtp``; ParaView reads the pieces through it.
        pieces: file names of the pieces, relative to the directory of ``path``.
        point_data: name -> an array (or an empty array) with the dtype and number of components
            of that point-data array in the pieces.
        points_dtype: dtype of the pieces' points.
    """

    def describe(name: str | None, values: Any) -> str:
        arr = np.asarray(values)
        kind = _VTK_TYPES[np.dtype(arr.dtype).newbyteorder("=")]
        components = arr.shape[1] if arr.ndim == 2 else 1
        label = "" if name is None else f" Name={_quoteattr(name)}"
        return f'      <PDataArray type="{kind}"{label} NumberOfComponents="{components}"/>\n'

    lines = [
        '<?xml version="1.0"?>\n',
        '<VTKFile type="PPolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n',
        '  <PPolyData GhostLevel="0">\n',
        "    <PPointData>\n",
    ]
    lines += [describe(name, values) for name, values in point_data.items()]
    lines += ["    </PPointData>\n", "    <PPoints>\n"]
    lines.append(describe(None, np.zeros((0, 3), dtype=points_dtype)))
    lines.append("    </PPoints>\n")
    lines += [f"    <Piece Source={_quoteattr(Path(p).as_posix())}/>\n" for p in pieces]
    lines += ["  </PPolyData>\n", "</VTKFile>\n"]
    _atomic_write(path, ["".join(lines).encode("utf-8")])


class PVDSeries:
    """A ParaView ``.pvd`` collection: a list of (time, file, part) data sets.

    The index is rewritten (atomically) after every :meth:`add`, so an interrupted run still
    leaves a valid file that ParaView opens as a time series.
    """

    def __init__(self, path: PathLike) -> None:
        """``path``: the .pvd file; data set file names are given relative to its directory."""
        self.path = Path(path)
        self.entries: list[tuple[float, str, int]] = []

    def add(self, time: float, relative_file: str, part: int = 0) -> None:
        """Add a data set at ``time`` (s) and rewrite the index.

        Adding the same (file, part) again replaces the earlier entry.
        """
        time = float(time)
        if not math.isfinite(time):
            raise ValueError(f"PVDSeries.add time must be finite, got {time}")
        relative_file = Path(relative_file).as_posix()
        part = int(part)
        self.entries = [e for e in self.entries if (e[1], e[2]) != (relative_file, part)]
        self.entries.append((time, relative_file, part))
        self.write()

    def write(self) -> None:
        """Write the .pvd file (creating its directory if needed)."""
        lines = [
            '<?xml version="1.0"?>\n',
            '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n',
            "  <Collection>\n",
        ]
        for time, file, part in self.entries:
            attrs = f'timestep="{time!r}" group="" part="{part}" file={_quoteattr(file)}'
            lines.append(f"    <DataSet {attrs}/>\n")
        lines += ["  </Collection>\n", "</VTKFile>\n"]
        self.path.parent.mkdir(parents=True, exist_ok=True)
        _atomic_write(self.path, ["".join(lines).encode("utf-8")])


# --------------------------------------------------------------------------------------------
# Simulation output operation
# --------------------------------------------------------------------------------------------


class VTK:
    """Particle snapshots for ParaView: ``<directory>/<prefix>_<step:08d>.vtp`` + ``<prefix>.pvd``.

    Register with ``sim.output(gs.io.VTK("out/", every=0.01))``. Each snapshot holds, per
    particle: position (points, m), ``radius`` (m), ``velocity`` (m/s), ``angular_velocity``
    (rad/s), ``force`` (N), ``torque`` (N m, when available), ``id`` (int64), ``material``
    (int32) and ``mass`` (kg). In ParaView open the .pvd and apply Glyph (Sphere, scale by
    ``radius``, scale factor 2) to see the grains.

    ``level``: the level of a :class:`~grainscale.Hierarchy` the simulation is (written as an
    int32 ``level`` array, to colour the levels in ParaView).

    Under MPI every rank writes its particles as ``<prefix>_<step:08d>_r<rank>.vtp`` (with a
    ``rank`` array) and rank 0 writes the parallel index ``<prefix>_<step:08d>.pvtp``, which
    the .pvd lists. Rank 0 writes the walls, every type where it is at the snapshot (planes
    clipped to the domain, rectangles, cylinders, meshes; grainscale.io.wall_surfaces), as
    ``<prefix>_walls_<step:08d>.vtp`` with a cell array ``wall`` (the wall's index), listed in
    ``<prefix>_walls.pvd``; once if no wall moves, else at every snapshot.

    Schedule (exactly one of):

    * ``every``: simulated-time interval, s. Snapshots at the first step whose time reaches each
      multiple of ``every`` (t = 0, every, 2 every, ...).
    * ``every_steps``: step interval. Snapshots at the steps that are multiples of
      ``every_steps``.

    In both cases the first scheduled call writes at once (the step when the writer is attached).

    Protocol used by the Simulation: ``next_step(step, time, time_step)`` returns the next step
    at which to call ``write(sim)``; call it again after each write and whenever the time step
    changes (it depends only on its arguments and on the last write).
    """

    def __init__(
        self,
        directory: PathLike,
        every: float | None = None,
        every_steps: int | None = None,
        prefix: str = "particles",
        binary: bool = True,
        appended: bool = False,
        level: int | None = None,
    ) -> None:
        if level is not None and (isinstance(level, bool) or not isinstance(level, int)):
            raise ValueError(f"VTK.level must be an integer or None, got {level!r}")
        self.level = level
        if (every is None) == (every_steps is None):
            raise ValueError(
                "VTK needs exactly one of every (s) or every_steps, "
                f"got every={every!r}, every_steps={every_steps!r}"
            )
        if every is not None:
            if (
                isinstance(every, bool)
                or not isinstance(every, numbers.Real)
                or not math.isfinite(every)
                or every <= 0
            ):
                raise ValueError(f"VTK.every must be a positive finite time in s, got {every!r}")
            every = float(every)
        if every_steps is not None:
            if isinstance(every_steps, bool) or not isinstance(every_steps, numbers.Integral):
                raise ValueError(f"VTK.every_steps must be a positive integer, got {every_steps!r}")
            if every_steps <= 0:
                raise ValueError(f"VTK.every_steps must be a positive integer, got {every_steps!r}")
            every_steps = int(every_steps)
        if not isinstance(prefix, str) or not prefix or "/" in prefix or os.sep in prefix:
            raise ValueError(
                f"VTK.prefix must be a non-empty file name without path separators, got {prefix!r}"
            )
        if appended and not binary:
            raise ValueError("VTK.appended=True requires binary=True, got binary=False")

        self.directory = Path(directory)
        self.every = every
        self.every_steps = every_steps
        self.prefix = prefix
        self.binary = bool(binary)
        self.appended = bool(appended)
        self.files: list[Path] = []  # snapshot files written, in order
        self.pvd = PVDSeries(self.directory / f"{prefix}.pvd")
        self._last_step: int | None = None  # step of the last write
        self._next_index = 0  # index n of the next output time n * every not yet covered
        self._time_step: float | None = None  # last time step seen by next_step, s

    def __repr__(self) -> str:
        if self.every is not None:
            sched = f"every={self.every!r}"
        else:
            sched = f"every_steps={self.every_steps}"
        return f"VTK({str(self.directory)!r}, {sched}, prefix={self.prefix!r})"

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step >= ``step`` at which to write.

        Args:
            step: current step number.
            time: simulated time at ``step``, s.
            time_step: integration time step, s (assumed constant until the returned step).
        """
        step = int(step)
        self._time_step = float(time_step)
        if self._last_step is None:
            return step  # never written yet: write now
        earliest = max(step, self._last_step + 1)
        if self.every_steps is not None:
            k = self.every_steps
            return -(-earliest // k) * k  # ceil to a multiple of k
        assert self.every is not None
        target = self._next_index * self.every
        # first step whose time reaches the target (tolerance 1e-6 step for round-off)
        steps_ahead = math.ceil((target - float(time)) / float(time_step) - 1e-6)
        return max(step + steps_ahead, earliest)

    def _write_walls(self, sim: Any, step: int, time: float) -> None:
        """Every wall (planes clipped to the domain, rectangles, cylinders, meshes): one .vtp
        per snapshot (cell data ``wall``, the wall's index) in ``<prefix>_walls.pvd``; written
        once when no wall moves."""
        if not getattr(sim, "walls", None) or getattr(sim, "rank", 0) != 0:
            return
        surfaces = wall_surfaces(sim)
        if not surfaces.moving and getattr(self, "_walls_written", False):
            return
        if len(surfaces.triangles) == 0:
            return
        name = f"{self.prefix}_walls_{step:08d}.vtp"
        write_vtp_mesh(
            self.directory / name,
            surfaces.vertices,
            surfaces.triangles,
            cell_data={"wall": surfaces.wall},
            binary=self.binary,
            appended=self.appended,
        )
        if not hasattr(self, "walls_pvd"):
            self.walls_pvd = PVDSeries(self.directory / f"{self.prefix}_walls.pvd")
        self.walls_pvd.add(time, name)
        self._walls_written = True

    def write(self, sim: Any) -> Path:
        """Write the snapshot of ``sim`` at its current step and add it to the .pvd index.

        ``sim`` must provide ``step``, ``time`` (s) and the ``particles()`` context manager.
        Returns the path of the .vtp file.
        """
        step = int(sim.step)
        time = float(sim.time)
        self.directory.mkdir(parents=True, exist_ok=True)
        rank, ranks = int(getattr(sim, "rank", 0)), int(getattr(sim, "ranks", 1))
        name = f"{self.prefix}_{step:08d}.vtp"
        if ranks > 1:
            name = f"{self.prefix}_{step:08d}_r{rank}.vtp"
        path = self.directory / name
        with sim.particles(writable=False) as p:
            point_data = {
                "radius": p.radius,
                "velocity": p.velocity,
                "angular_velocity": p.angular_velocity,
                "force": p.force,
            }
            torque = getattr(p, "torque", None)
            if torque is not None:
                point_data["torque"] = torque
            point_data.update({"id": p.id, "material": p.material, "mass": p.mass})
            if ranks > 1:
                point_data["rank"] = np.full(len(p), rank, dtype=np.int32)
            if self.level is not None:
                point_data["level"] = np.full(len(p), self.level, dtype=np.int32)
            write_vtp(path, p.position, point_data, binary=self.binary, appended=self.appended)
            if ranks > 1 and rank == 0:
                index = f"{self.prefix}_{step:08d}.pvtp"
                pieces = [f"{self.prefix}_{step:08d}_r{r}.vtp" for r in range(ranks)]
                write_pvtp(self.directory / index, pieces, point_data)
                name, path = index, self.directory / index
        if rank == 0:
            self.pvd.add(time, name)
        if not self.files or self.files[-1] != path:
            self.files.append(path)
        self._write_walls(sim, step, time)
        self._last_step = step
        if self.every is not None:
            dt = self._time_step if self._time_step is not None else getattr(sim, "time_step", 0)
            # output times up to time (+ 1e-3 step for round-off) are covered by this snapshot
            covered = math.floor((time + 1e-3 * float(dt or 0.0)) / self.every)
            self._next_index = max(self._next_index, covered + 1)
        return path
