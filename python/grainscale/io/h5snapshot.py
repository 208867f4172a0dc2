"""One snapshot of per-item arrays (particles, contacts) in HDF5, written by every rank as its
piece, and read back as one table. Used by :class:`~grainscale.io.Dump` and
:class:`~grainscale.io.ContactNetwork`.

Layout of ``<stem>.h5``: root attributes ``format``, ``version``, ``ranks`` and the snapshot's
own (``step``, ``time``, ...); one dataset per array (first axis: the items). Under MPI each
rank writes its items to ``<stem>_r<rank>.h5`` (the same layout, attribute ``piece`` = its
rank) and rank 0 writes ``<stem>.h5`` without datasets: its attribute ``pieces`` lists the
piece files, and its groups ``rank_<r>`` are HDF5 external links to them (h5py follows them:
``f["rank_1/position"]``). :func:`read_snapshot` joins the pieces in rank order.

Every file is written to a temporary sibling and renamed: a reader never sees a partial file.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .paths import make_directory

VERSION = 1


def _atomic_h5(path: Path, fill: Any) -> None:
    import h5py

    tmp = path.with_name(f"{path.name}.tmp.{os.getpid()}")
    try:
        with h5py.File(tmp, "w") as f:
            fill(f)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _set_attrs(f: Any, fmt: str, ranks: int, attrs: Mapping[str, Any]) -> None:
    f.attrs["format"] = fmt
    f.attrs["version"] = VERSION
    f.attrs["ranks"] = int(ranks)
    for key, value in attrs.items():
        f.attrs[key] = json.dumps(value) if isinstance(value, list | dict) else value


def write_snapshot(
    directory: Path,
    stem: str,
    fmt: str,
    arrays: Mapping[str, np.ndarray],
    attrs: Mapping[str, Any],
    rank: int = 0,
    ranks: int = 1,
) -> Path:
    """Write this rank's ``arrays`` (each with the items along its first axis) of the snapshot
    ``<directory>/<stem>.h5``; returns that path (the index under MPI)."""
    make_directory("output directory", directory)
    index = directory / f"{stem}.h5"

    def datasets(f: Any) -> None:
        for name, value in arrays.items():
            f.create_dataset(name, data=np.ascontiguousarray(value))

    if ranks == 1:

        def serial(f: Any) -> None:
            _set_attrs(f, fmt, 1, attrs)
            datasets(f)

        _atomic_h5(index, serial)
        return index

    piece = f"{stem}_r{rank}.h5"

    def own(f: Any) -> None:
        _set_attrs(f, fmt, ranks, attrs)
        f.attrs["piece"] = int(rank)
        datasets(f)

    _atomic_h5(directory / piece, own)
    if rank == 0:
        import h5py

        pieces = [f"{stem}_r{r}.h5" for r in range(ranks)]

        def links(f: Any) -> None:
            _set_attrs(f, fmt, ranks, attrs)
            f.attrs["pieces"] = json.dumps(pieces)
            for r, name in enumerate(pieces):
                f[f"rank_{r}"] = h5py.ExternalLink(name, "/")

        _atomic_h5(index, links)
    return index


def _attrs(f: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in f.attrs.items():
        if isinstance(value, bytes):
            value = value.decode()
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, str) and value[:1] in "[{":
            try:
                value = json.loads(value)
            except ValueError:
                pass
        out[key] = value
    return out


def read_snapshot(
    path: str | os.PathLike[str], fmt: str
) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """``(arrays, attributes)`` of a snapshot file written by :func:`write_snapshot` (its pieces
    joined in rank order). ValueError naming the file when it is not one of format ``fmt`` or a
    piece is missing or differs."""
    import h5py

    path = Path(path)
    try:
        f = h5py.File(path, "r")
    except OSError as err:
        raise ValueError(f"{os.fspath(path)!r} is not a readable HDF5 file ({err})") from None
    with f:
        attrs = _attrs(f)
        if attrs.get("format") != fmt:
            raise ValueError(
                f"{os.fspath(path)!r} is not a {fmt} file (format {attrs.get('format')!r})"
            )
        if "piece" in attrs:
            raise ValueError(
                f"{os.fspath(path)!r} is the piece of rank {attrs['piece']} of a snapshot: read "
                f"the snapshot's index file instead"
            )
        pieces = attrs.pop("pieces", None)
        if pieces is None:
            return {name: f[name][()] for name in f if isinstance(f[name], h5py.Dataset)}, attrs
    parts = []
    for name in pieces:
        where = path.parent / name
        if not where.is_file():
            raise ValueError(f"{os.fspath(path)!r}: its piece {name!r} is missing")
        with h5py.File(where, "r") as g:
            parts.append({k: g[k][()] for k in g if isinstance(g[k], h5py.Dataset)})
    names = list(parts[0])
    for name, part in zip(pieces, parts, strict=True):
        if sorted(part) != sorted(names):
            raise ValueError(
                f"{os.fspath(path)!r}: its piece {name!r} holds the arrays {sorted(part)}, the "
                f"first piece {sorted(names)}"
            )
    return {k: np.concatenate([part[k] for part in parts]) for k in names}, attrs


def snapshot_files(directory: str | os.PathLike[str], prefix: str) -> list[Path]:
    """The snapshot files ``<prefix>_<step>.h5`` in ``directory`` (not the pieces), by step."""
    found = []
    for p in Path(directory).glob(f"{prefix}_*.h5"):
        digits = p.stem[len(prefix) + 1 :]
        if digits.isdigit():
            found.append((int(digits), p))
    return [p for _, p in sorted(found)]
