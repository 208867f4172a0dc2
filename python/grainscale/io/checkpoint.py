"""HDF5 checkpoints: save a simulation's state and continue it, on any number of ranks.

A checkpoint holds the dynamic state — particles (in their current order, with forces),
contact histories and neighbour lists, ghosts, wall positions, motion and servo state, insertion
state, step and time — as one group per rank (``rank_<r>/...``) of the run that wrote it. The
set-up (materials, contact law, walls, inserters, outputs) comes from the script: build the
simulation as before, then ``load(sim, path)`` instead of adding particles.

    gs.io.checkpoint.save(sim, "run.h5")
    ...
    sim = build()                      # the same set-up, no particles
    gs.io.checkpoint.load(sim, "run.h5")
    sim.run(steps=...)                 # identical to never having stopped

Under MPI both calls are collective. Rank 0 writes the file (every rank's part is gathered to
it). A restart on the same number of ranks with the same processor grid continues
bit-identically; on any other number of ranks every rank reads all parts and keeps the
particles (with their contact histories) of its subdomain, and the continuation then equals the
uninterrupted run up to round-off (the neighbour lists are rebuilt for the new decomposition).
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from .. import parallel

FORMAT = "grainscale-checkpoint"
VERSION = 2


def save(sim: Any, path: str | os.PathLike[str]) -> None:
    """Write the state of ``sim`` to the HDF5 file ``path`` (atomically; collective)."""
    state = sim._level.save_state()
    comm = sim.comm
    states = [state] if comm is None else comm.gather(state, root=0)
    error: BaseException | None = None
    if sim.rank == 0:
        try:
            _write(path, states, sim._checkpoint_extra())
        except Exception as err:
            error = err
    parallel.agree(comm, error)


def _write(path: str | os.PathLike[str], states: list[dict[str, Any]], extra: Any) -> None:
    import h5py

    from .. import __version__

    tmp = os.fspath(path) + ".tmp"
    with h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["version"] = VERSION
        f.attrs["grainscale"] = __version__
        f.attrs["ranks"] = len(states)
        f.attrs["python_state"] = json.dumps(extra)
        for rank, state in enumerate(states):
            group = f.create_group(f"rank_{rank}")
            for key, value in state.items():
                if key.startswith("texts/"):
                    group.attrs[key] = value
                else:
                    group.create_dataset(key, data=np.asarray(value))
    os.replace(tmp, path)


def load(sim: Any, path: str | os.PathLike[str]) -> None:
    """Restore the state saved in ``path`` into ``sim`` (which must have the same set-up;
    collective).

    Raises:
        ValueError: the file is not a grainscale checkpoint, is corrupt, or was written for a
            different set-up (contact law, materials, walls, inserters).
    """
    grid = tuple(sim._level.decomposition()["grid"])
    error: BaseException | None = None
    parts: list[dict[str, Any]] = []
    exact = False
    extra: Any = None
    try:
        parts, exact, extra = _read(path, sim.rank, sim.ranks, grid)
    except Exception as err:
        error = err
    parallel.agree(sim.comm, error)
    sim._restore_checkpoint_extra(extra)
    if exact:
        sim._level.load_state(parts[0])
    else:
        sim._level.load_redistributed(parts)


def _read(
    path: str | os.PathLike[str], rank: int, ranks: int, grid: tuple[int, ...]
) -> tuple[list[dict[str, Any]], bool, Any]:
    """The rank parts this rank needs — its own when the file was written on the same ranks
    and processor grid (exact restart), else all of them — whether that is exact, and the Python
    state."""
    import h5py

    try:
        f = h5py.File(os.fspath(path), "r")
    except OSError as err:
        raise ValueError(
            f"checkpoint.path must be a readable HDF5 file, got {path!r} ({err})"
        ) from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"checkpoint.path is not a grainscale checkpoint: {path!r}")
        if int(f.attrs.get("version", -1)) != VERSION:
            raise ValueError(
                f"checkpoint version must be {VERSION}, got {f.attrs.get('version')!r}"
            )
        saved = int(f.attrs.get("ranks", 0))
        groups = [f.get(f"rank_{r}") for r in range(saved)]
        if saved < 1 or any(g is None for g in groups):
            raise ValueError(f"checkpoint {path!r} is corrupt: rank groups missing")
        decomposition = groups[0].get("ints/decomposition")
        if decomposition is None or len(decomposition) != 5:
            raise ValueError(f"checkpoint {path!r} is corrupt: no decomposition")
        exact = saved == ranks and tuple(int(g) for g in decomposition[1:4]) == grid
        parts = [_read_group(groups[rank])] if exact else [_read_group(g) for g in groups]
        extra = json.loads(f.attrs["python_state"])
    return parts, exact, extra


def _read_group(group: Any) -> dict[str, Any]:
    import h5py

    state: dict[str, Any] = {}
    for key, value in group.attrs.items():
        if key.startswith("texts/"):
            state[key] = str(value)

    def visit(name: str, obj: Any) -> None:
        if isinstance(obj, h5py.Dataset):
            state[name] = obj[()]

    group.visititems(visit)
    return state
