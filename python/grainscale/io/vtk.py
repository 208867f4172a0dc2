"""ParaView output without the VTK library: VTK XML PolyData (.vtp) and .pvd time series.

Low-level writers (pure numpy):

* :func:`write_vtp` - points with point data, one vertex cell per point (Verts), so ParaView
  renders them directly (use a Glyph filter scaled by ``radius`` for spheres).
* :func:`write_vtp_mesh` - a triangle surface (Polys) with optional cell / point data.
* :func:`write_vtp_lines` - line segments (Lines) with optional cell / point data (the contact
  network: grainscale.io.contact_network).
* :class:`PVDSeries` - the .pvd "Collection" index that ParaView opens as one time series.
* :func:`write_pvtp` - the parallel index (.pvtp) of per-rank pieces of one snapshot.

The output operation used by ``Simulation.output()`` is :class:`VTK`
(grainscale.io.vtk_output).

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
import os
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

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


__all__ = ["PVDSeries", "write_pvtp", "write_vtp", "write_vtp_lines", "write_vtp_mesh"]


def __getattr__(name: str) -> Any:
    """``VTK`` lives in grainscale.io.vtk_output (which imports this module's writers)."""
    if name == "VTK":
        from .vtk_output import VTK

        return VTK
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


PathLike = str | os.PathLike[str]

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


def _cell_indices(
    cells: Any, corners: int, name: str, shape: str, what: str, points: Any
) -> np.ndarray:
    """``cells`` as an int64 (n, corners) array of point indices in [0, len(points))."""
    c = np.asarray(cells)
    if c.ndim != 2 or c.shape[1] != corners or (c.size and c.dtype.kind not in "iu"):
        raise ValueError(f"{name} must be an integer array of shape {shape}, got {c.shape}")
    n_points = np.shape(points)[0] if np.ndim(points) >= 1 else 0
    c = c.astype(np.int64)
    if c.size and (c.min() < 0 or c.max() >= n_points):
        raise ValueError(f"{what} indices must be in [0, {n_points})")
    return c


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
    tri = _cell_indices(triangles, 3, "triangles", "(T, 3)", "triangle vertex", vertices)
    offsets = np.arange(1, tri.shape[0] + 1, dtype=np.int64) * 3
    _write_polydata(
        path, vertices, "Polys", tri.reshape(-1), offsets, point_data, cell_data, binary, appended
    )


def write_vtp_lines(
    path: PathLike,
    points: Any,
    segments: Any,
    cell_data: Mapping[str, Any] | None = None,
    point_data: Mapping[str, Any] | None = None,
    binary: bool = True,
    appended: bool = False,
) -> None:
    """Write line segments as VTK XML PolyData (two-point cells in the ``Lines`` section).

    Args:
        path: output file, conventionally ``*.vtp``.
        points: (V, 3) end points, m.
        segments: (L, 2) integer point indices (0-based, each in [0, V)).
        cell_data: name -> (L,) or (L, k) array, one value per segment (e.g. force, N).
        point_data: name -> (V,) or (V, k) array, one value per point.
        binary, appended: encoding, as in :func:`write_vtp`.
    """
    seg = _cell_indices(segments, 2, "segments", "(L, 2)", "segment point", points)
    offsets = np.arange(1, seg.shape[0] + 1, dtype=np.int64) * 2
    _write_polydata(
        path, points, "Lines", seg.reshape(-1), offsets, point_data, cell_data, binary, appended
    )


def write_pvtp(
    path: PathLike,
    pieces: list[str],
    point_data: Mapping[str, Any],
    points_dtype: Any = np.float64,
    cell_data: Mapping[str, Any] | None = None,
) -> None:
    """Write the parallel index (PPolyData) of a snapshot written as one .vtp piece per rank.

    Args:
        path: output file, conventionally ``*.pvtp``; ParaView reads the pieces through it.
        pieces: file names of the pieces, relative to the directory of ``path``.
        point_data: name -> an array (or an empty array) with the dtype and number of components
            of that point-data array in the pieces.
        points_dtype: dtype of the pieces' points.
        cell_data: name -> an array describing a cell-data array of the pieces, as point_data.
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
    lines.append("    </PPointData>\n")
    if cell_data:
        lines.append("    <PCellData>\n")
        lines += [describe(name, values) for name, values in cell_data.items()]
        lines.append("    </PCellData>\n")
    lines.append("    <PPoints>\n")
    lines.append(describe(None, np.zeros((0, 3), dtype=points_dtype)))
    lines.append("    </PPoints>\n")
    lines += [f"    <Piece Source={_quoteattr(Path(p).as_posix())}/>\n" for p in pieces]
    lines += ["  </PPolyData>\n", "</VTKFile>\n"]
    _atomic_write(path, ["".join(lines).encode("utf-8")])


class PVDSeries:
    """A ParaView ``.pvd`` collection: a list of (time, file, part) data sets.

    The index is rewritten (atomically) after every :meth:`add`, so an interrupted run still
    leaves a valid file that ParaView opens as a time series. :meth:`resume` continues the
    series an earlier run left in the file (a restarted run appends to it).
    """

    def __init__(self, path: PathLike) -> None:
        """``path``: the .pvd file; data set file names are given relative to its directory."""
        self.path = Path(path)
        self.entries: list[tuple[float, str, int]] = []

    def resume(self, before: float) -> None:
        """Continue the series already in the file: keep its entries whose time is earlier than
        ``before`` (s) and whose data set file still exists; the entries added next follow
        them. Without a file nothing is kept; an unreadable one is replaced (with a warning).

        A run restarted at time t that writes into the directory of the run it continues thus
        lists the earlier run's snapshots before t, then its own; a run starting at t = 0 starts
        a new series.
        """
        before = float(before)
        self.entries = []
        if not self.path.is_file():
            return
        try:
            root = ET.parse(self.path).getroot()
            kept = []
            for ds in root.iter("DataSet"):
                time, file = float(ds.get("timestep", "nan")), str(ds.get("file"))
                if time < before and (self.path.parent / file).is_file():
                    kept.append((time, Path(file).as_posix(), int(ds.get("part", "0"))))
        except (ET.ParseError, ValueError, OSError) as err:
            warnings.warn(
                f"PVDSeries: {os.fspath(self.path)!r} is not a readable .pvd index ({err}); "
                "it is replaced by a new series",
                UserWarning,
                stacklevel=2,
            )
            return
        self.entries = sorted(kept, key=lambda e: e[0])

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
