"""The HDF5 layout of a checkpoint file, its checksums and the checks made when it is read.

A file is untrusted input: every dataset carries the SHA-256 of its dtype, shape and bytes
(attribute ``sha256``) and every group the SHA-256 of its own attributes (``attrs_sha256``), so
that a flipped byte or a truncation is refused with a ``ValueError`` naming the file and the
dataset instead of loading wrong data. Files of version 2 (written before the checksums)
are read without them.

Layout: root attributes ``format``, ``version``, ``grainscale``; a simulation's group holds
``ranks``, ``python_state`` (JSON) and one group ``rank_<r>`` per rank of the run that wrote
it, whose datasets are the C++ level's named arrays (``reals/...`` float64, ``ints/...``
int64) and whose attributes ``texts/...`` its texts.
"""

from __future__ import annotations

import hashlib
import json
import os
from typing import Any

import numpy as np

FORMAT = "grainscale-checkpoint"
VERSION = 3
READABLE = (2, 3)  # 2: before the checksums


class Damaged(ValueError):
    """A checkpoint file that cannot be trusted (its message names the file and the part)."""


def digest(value: Any) -> str:
    """SHA-256 of an array's dtype, shape and bytes."""
    a = np.ascontiguousarray(value)
    h = hashlib.sha256(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())
    return h.hexdigest()


def _attrs_digest(attrs: Any) -> str:
    h = hashlib.sha256()
    for key in sorted(k for k in attrs.keys() if k != "attrs_sha256"):
        h.update(f"{key}={attrs[key]!r};".encode())
    return h.hexdigest()


def seal(obj: Any) -> None:
    """Stores the checksum of an HDF5 object's attributes (set them all first)."""
    obj.attrs["attrs_sha256"] = _attrs_digest(obj.attrs)


def write_simulation(group: Any, states: list[dict[str, Any]], extra: Any) -> None:
    """One simulation's rank parts and Python state into an HDF5 group, checksummed."""
    group.attrs["ranks"] = len(states)
    group.attrs["python_state"] = json.dumps(extra)
    for rank, state in enumerate(states):
        part = group.create_group(f"rank_{rank}")
        names = []
        for key, value in state.items():
            if key.startswith("texts/"):
                part.attrs[key] = value
            else:
                data = np.asarray(value)
                part.create_dataset(key, data=data).attrs["sha256"] = digest(data)
                names.append(key)
        part.attrs["datasets"] = ",".join(sorted(names))
        seal(part)
    seal(group)


def open_file(path: str | os.PathLike[str]) -> tuple[Any, int]:
    """The open HDF5 file and its format version; Damaged for anything else."""
    import h5py

    try:
        f = h5py.File(os.fspath(path), "r")
    except Exception as err:  # h5py raises OSError, and others for damaged metadata
        raise Damaged(
            f"checkpoint.path must be a readable HDF5 file, got {path!r} ({err})"
        ) from None
    try:
        if f.attrs.get("format") != FORMAT:
            raise Damaged(f"checkpoint.path is not a grainscale checkpoint: {path!r}")
        version = int(f.attrs.get("version", -1))
        if version not in READABLE:
            raise Damaged(
                f"checkpoint {path!r} has version {f.attrs.get('version')!r}, this grainscale "
                f"reads versions {READABLE}"
            )
        verify_attrs(f, path, version)
    except Damaged:
        f.close()
        raise
    except Exception as err:
        f.close()
        raise Damaged(f"checkpoint {path!r} is damaged: {err}") from None
    return f, version


def verify_attrs(obj: Any, path: Any, version: int) -> None:
    """Refuses an object whose attributes changed since they were sealed (version 3)."""
    if version < 3:
        return
    if obj.attrs.get("attrs_sha256") != _attrs_digest(obj.attrs):
        raise Damaged(f"checkpoint {path!r}: the attributes of '{obj.name}' are damaged")


def read_simulation(
    group: Any, rank: int, ranks: int, grid: tuple[int, ...], path: Any, version: int
) -> tuple[list[dict[str, Any]], bool, Any]:
    """The rank parts this rank needs — its own when the group was written on the same ranks
    and processor grid (exact restart), else all of them — whether that is exact, and the Python
    state; every part verified."""
    verify_attrs(group, path, version)
    saved = int(group.attrs.get("ranks", 0))
    groups = [group.get(f"rank_{r}") for r in range(saved)]
    if saved < 1 or any(g is None for g in groups):
        raise Damaged(f"checkpoint {path!r} is damaged: rank groups missing")
    decomposition = groups[0].get("ints/decomposition")
    if decomposition is None or decomposition.shape != (5,):
        raise Damaged(f"checkpoint {path!r} is damaged: no decomposition")
    exact = saved == ranks and tuple(int(g) for g in decomposition[1:4]) == grid
    wanted = [groups[rank]] if exact else groups
    parts = [read_group(g, path, version) for g in wanted]
    try:
        extra = json.loads(group.attrs["python_state"])
    except (KeyError, ValueError) as err:
        raise Damaged(f"checkpoint {path!r}: its Python state is damaged ({err})") from None
    if not isinstance(extra, dict):
        raise Damaged(f"checkpoint {path!r}: its Python state is damaged")
    return parts, exact, extra


def read_group(group: Any, path: Any, version: int) -> dict[str, Any]:
    """A rank part as the C++ level's named arrays, each checked (dtype, shape, checksum)."""
    import h5py

    verify_attrs(group, path, version)
    state: dict[str, Any] = {}
    for key, value in group.attrs.items():
        if key.startswith("texts/"):
            state[key] = str(value)
    datasets: list[tuple[str, Any]] = []
    group.visititems(
        lambda name, obj: datasets.append((name, obj)) if isinstance(obj, h5py.Dataset) else None
    )
    if version >= 3:
        listed = set(str(group.attrs.get("datasets", "")).split(","))
        found = {name for name, _ in datasets}
        if listed != found:
            missing = sorted(listed - found) or sorted(found - listed)
            raise Damaged(
                f"checkpoint {path!r}: group '{group.name}' is damaged (datasets missing or "
                f"added: {', '.join(missing[:5])})"
            )
    for name, obj in datasets:
        where = f"checkpoint {path!r}: dataset '{group.name}/{name}'"
        value = obj[()]
        kind = "f" if name.startswith("reals/") else "i" if name.startswith("ints/") else None
        if kind is None or np.asarray(value).dtype.kind != kind or np.ndim(value) != 1:
            raise Damaged(f"{where} has the wrong type or shape")
        if version >= 3 and obj.attrs.get("sha256") != digest(value):
            raise Damaged(f"{where} is damaged (checksum mismatch)")
        state[name] = value
    return state
