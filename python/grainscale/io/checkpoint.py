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
    state = sim.engine.save_state()
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
        _write_simulation(f, states, extra)
    os.replace(tmp, path)


def _write_simulation(group: Any, states: list[dict[str, Any]], extra: Any) -> None:
    """One simulation's rank parts and Python state into an HDF5 group."""
    group.attrs["ranks"] = len(states)
    group.attrs["python_state"] = json.dumps(extra)
    for rank, state in enumerate(states):
        part = group.create_group(f"rank_{rank}")
        for key, value in state.items():
            if key.startswith("texts/"):
                part.attrs[key] = value
            else:
                part.create_dataset(key, data=np.asarray(value))


def save_hierarchy(sims: list[Any], path: str | os.PathLike[str], coupling_state: str) -> None:
    """Collective: the levels of a hierarchy (groups ``level_<k>``, each like a simulation's
    checkpoint) and the hierarchy's coupling state (JSON text) in one file."""
    import h5py

    from .. import __version__

    parts = []
    for sim in sims:
        state = sim.engine.save_state()
        comm = sim.comm
        parts.append(
            ([state] if comm is None else comm.gather(state, root=0), sim._checkpoint_extra())
        )
    error: BaseException | None = None
    if sims[0].rank == 0:
        try:
            tmp = os.fspath(path) + ".tmp"
            with h5py.File(tmp, "w") as f:
                f.attrs["format"] = FORMAT
                f.attrs["version"] = VERSION
                f.attrs["grainscale"] = __version__
                f.attrs["levels"] = len(sims)
                f.attrs["hierarchy_state"] = coupling_state
                for k, (states, extra) in enumerate(parts):
                    _write_simulation(f.create_group(f"level_{k}"), states, extra)
            os.replace(tmp, path)
        except Exception as err:
            error = err
    parallel.agree(sims[0].comm, error)


def load_hierarchy(sims: list[Any], path: str | os.PathLike[str]) -> str:
    """Collective: restores every level from a file of save_hierarchy; returns the coupling
    state text."""
    error: BaseException | None = None
    text = ""
    loaded: list[tuple[list[dict[str, Any]], bool, Any]] = []
    try:
        f = _open(path)
        with f:
            if int(f.attrs.get("levels", -1)) != len(sims):
                raise ValueError(
                    f"checkpoint holds {f.attrs.get('levels')!r} levels, this hierarchy has "
                    f"{len(sims)}"
                )
            text = str(f.attrs["hierarchy_state"])
            for k, sim in enumerate(sims):
                grid = sim.engine.processor_grid()
                loaded.append(_read_simulation(f[f"level_{k}"], sim.rank, sim.ranks, grid, path))
    except KeyError as err:
        error = ValueError(f"checkpoint {path!r} is not a hierarchy checkpoint ({err})")
    except Exception as err:
        error = err
    parallel.agree(sims[0].comm, error)
    for sim, (parts, exact, extra) in zip(sims, loaded, strict=True):
        sim._restore_checkpoint_extra(extra)
        sim.engine.load_state(parts, exact)
    return text


def load(sim: Any, path: str | os.PathLike[str]) -> None:
    """Restore the state saved in ``path`` into ``sim`` (which must have the same set-up;
    collective).

    Raises:
        ValueError: the file is not a grainscale checkpoint, is corrupt, or was written for a
            different set-up (contact law, materials, walls, inserters).
    """
    grid = sim.engine.processor_grid()
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
    sim.engine.load_state(parts, exact)


def _open(path: str | os.PathLike[str]) -> Any:
    import h5py

    try:
        f = h5py.File(os.fspath(path), "r")
    except OSError as err:
        raise ValueError(
            f"checkpoint.path must be a readable HDF5 file, got {path!r} ({err})"
        ) from None
    if f.attrs.get("format") != FORMAT:
        f.close()
        raise ValueError(f"checkpoint.path is not a grainscale checkpoint: {path!r}")
    if int(f.attrs.get("version", -1)) != VERSION:
        version = f.attrs.get("version")
        f.close()
        raise ValueError(f"checkpoint version must be {VERSION}, got {version!r}")
    return f


def _read(
    path: str | os.PathLike[str], rank: int, ranks: int, grid: tuple[int, ...]
) -> tuple[list[dict[str, Any]], bool, Any]:
    with _open(path) as f:
        return _read_simulation(f, rank, ranks, grid, path)


def _read_simulation(
    group: Any, rank: int, ranks: int, grid: tuple[int, ...], path: Any
) -> tuple[list[dict[str, Any]], bool, Any]:
    """The rank parts this rank needs — its own when the group was written on the same ranks
    and processor grid (exact restart), else all of them — whether that is exact, and the Python
    state."""
    saved = int(group.attrs.get("ranks", 0))
    groups = [group.get(f"rank_{r}") for r in range(saved)]
    if saved < 1 or any(g is None for g in groups):
        raise ValueError(f"checkpoint {path!r} is corrupt: rank groups missing")
    decomposition = groups[0].get("ints/decomposition")
    if decomposition is None or len(decomposition) != 5:
        raise ValueError(f"checkpoint {path!r} is corrupt: no decomposition")
    exact = saved == ranks and tuple(int(g) for g in decomposition[1:4]) == grid
    parts = [_read_group(groups[rank])] if exact else [_read_group(g) for g in groups]
    return parts, exact, json.loads(group.attrs["python_state"])


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
