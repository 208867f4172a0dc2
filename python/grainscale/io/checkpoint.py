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

A file is checked whole before anything changes (grainscale.io.checkpoint_file: checksums of
every dataset and of every group's attributes; the core's structural checks, among them every
owned particle inside the domain along its closed axes and the inverse masses and inertias those
of the saved masses and radii; the set-up): damage, another set-up or a checkpoint of the other
kind (a hierarchy's given to ``load``, a simulation's to ``load_hierarchy``) raises a ValueError
naming the file. A file that cannot be written raises a ValueError naming the call and the path
(the OSError as its cause).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from typing import Any

from .. import parallel
from .checkpoint_file import (
    FORMAT,
    VERSION,
    Damaged,
    open_file,
    read_simulation,
    seal,
    verify_attrs,
    write_simulation,
)

__all__ = ["FORMAT", "VERSION", "load", "load_hierarchy", "save", "save_hierarchy"]


def _gather(comm: Any, state: Any, call: str) -> Any:
    with parallel.waiting(f"{call} (gathering the ranks' states)"):
        return comm.gather(state, root=0)


def save(sim: Any, path: str | os.PathLike[str]) -> None:
    """Write the state of ``sim`` to the HDF5 file ``path`` (atomically; collective). The
    defaults not chosen yet (time step, skin) are chosen first, as ``run`` would."""
    sim._resolve_defaults()
    state = sim.engine.save_state()
    comm = sim.comm
    states = [state] if comm is None else _gather(comm, state, "Simulation.checkpoint")
    error: BaseException | None = None
    if sim.rank == 0:
        try:
            _write(path, [(states, sim._checkpoint_extra())], call="Simulation.checkpoint")
        except Exception as err:
            error = err
    parallel.agree(comm, error)


def save_hierarchy(sims: list[Any], path: str | os.PathLike[str], coupling_state: str) -> None:
    """Collective: the levels of a hierarchy (groups ``level_<k>``, each like a simulation's
    checkpoint) and the hierarchy's coupling state (JSON text) in one file."""
    parts = []
    for sim in sims:
        sim._resolve_defaults()
        state = sim.engine.save_state()
        comm = sim.comm
        parts.append(
            (
                [state] if comm is None else _gather(comm, state, "Hierarchy.checkpoint"),
                sim._checkpoint_extra(),
            )
        )
    error: BaseException | None = None
    if sims[0].rank == 0:
        try:
            _write(path, parts, coupling_state, call="Hierarchy.checkpoint")
        except Exception as err:
            error = err
    parallel.agree(sims[0].comm, error)


def _write(
    path: str | os.PathLike[str],
    parts: list[tuple[list[dict[str, Any]], Any]],
    coupling_state: str | None = None,
    call: str = "Simulation.checkpoint",
) -> None:
    """A simulation's file (one part, in the root group) or a hierarchy's (a group per level),
    written to a temporary file and renamed, so that a crash leaves the old file whole. An
    OSError (a missing or unwritable directory, a full disk) becomes a ValueError naming
    ``call`` and the path, the temporary file removed."""
    import h5py

    from .. import __version__

    tmp = os.fspath(path) + ".tmp"
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["version"] = VERSION
            f.attrs["grainscale"] = __version__
            if coupling_state is None:
                write_simulation(f, *parts[0])
            else:
                f.attrs["levels"] = len(parts)
                f.attrs["hierarchy_state"] = coupling_state
                for k, (states, extra) in enumerate(parts):
                    write_simulation(f.create_group(f"level_{k}"), states, extra)
                seal(f)
        os.replace(tmp, path)
    except OSError as err:
        try:
            os.remove(tmp)
        except OSError:
            pass  # never created, or its directory is the problem
        raise ValueError(
            f"{call}.path must be a file path that can be written, got {os.fspath(path)!r} "
            f"({type(err).__name__}: {err})"
        ) from err


def load(sim: Any, path: str | os.PathLike[str]) -> None:
    """Restore the state saved in ``path`` into ``sim`` (which must have the same set-up;
    collective). Everything is checked before anything changes: the file's checksums, its
    structure, and its set-up against ``sim``'s.

    Raises:
        ValueError: naming the file: it is not a grainscale checkpoint, it is damaged, or it was
            written for a different set-up (domain, dimension, contact law and its parameters,
            materials, walls, inserters).
    """
    loaded: list[tuple[list[dict[str, Any]], bool, Any]] = []
    error: BaseException | None = None
    try:
        f, version = open_file(path)
        with f:
            if "levels" in f.attrs or "level_0" in f:
                levels = f.attrs.get("levels", "?")
                raise ValueError(
                    f"checkpoint {path!r} is a hierarchy checkpoint (written by "
                    f"Hierarchy.checkpoint, {levels} levels), not a simulation checkpoint: "
                    "continue it with Hierarchy.restart on the same hierarchy"
                )
            loaded.append(_read_level(f, sim, path, version))
    except Exception as err:
        error = _named(err, path)
    parallel.agree(sim.comm, error)
    _restore(sim, *loaded[0])


def load_hierarchy(
    sims: list[Any],
    path: str | os.PathLike[str],
    check: Callable[[str], None] | None = None,
    names: Sequence[str] | None = None,
) -> str:
    """Collective: restores every level from a file of save_hierarchy (checked whole before any
    level changes); returns the coupling state text. ``check`` is called with that text before
    the levels are read (it raises ValueError for another set-up); ``names`` say which level a
    level's error is about (default ``level <k>``)."""
    error: BaseException | None = None
    text = ""
    loaded: list[tuple[list[dict[str, Any]], bool, Any]] = []
    try:
        f, version = open_file(path)
        with f:
            if "levels" not in f.attrs and "rank_0" in f:
                raise ValueError(
                    f"checkpoint {path!r} is a simulation checkpoint (written by "
                    "Simulation.checkpoint), not a hierarchy checkpoint: continue it with "
                    "Simulation.restart"
                )
            if int(f.attrs.get("levels", -1)) != len(sims):
                raise ValueError(
                    f"checkpoint holds {f.attrs.get('levels')!r} levels, this hierarchy has "
                    f"{len(sims)}"
                )
            text = str(f.attrs["hierarchy_state"])
            if check is not None:
                check(text)
            for k, sim in enumerate(sims):
                try:
                    loaded.append(_read_level(f[f"level_{k}"], sim, path, version))
                except (ValueError, RuntimeError) as err:
                    name = names[k] if names is not None else f"level {k}"
                    kind = Damaged if isinstance(err, Damaged) else ValueError
                    raise kind(f"{name}: {err}") from None
    except KeyError as err:
        error = ValueError(f"checkpoint {path!r} is not a hierarchy checkpoint ({err})")
    except Exception as err:
        error = _named(err, path)
    parallel.agree(sims[0].comm, error)
    for sim, part in zip(sims, loaded, strict=True):
        _restore(sim, *part)
    return text


def _read_level(
    group: Any, sim: Any, path: Any, version: int
) -> tuple[list[dict[str, Any]], bool, Any]:
    """One simulation's parts, read and checked against ``sim`` (nothing changes yet)."""
    verify_attrs(group, path, version)
    parts, exact, extra = read_simulation(
        group, sim.rank, sim.ranks, sim.engine.processor_grid(), path, version
    )
    n_materials = max(len(sim.materials), len(extra.get("materials", [])))
    for part in parts:
        sim.engine.check_state(part, exact, n_materials)
    sim._check_checkpoint_extra(extra)
    return parts, exact, extra


def _restore(sim: Any, parts: list[dict[str, Any]], exact: bool, extra: Any) -> None:
    sim._restore_checkpoint_extra(extra)
    sim.engine.load_state(parts, exact)


def _named(err: BaseException, path: Any) -> BaseException:
    """A load error as a ValueError that names the file (as it is, if it already does)."""
    if isinstance(err, Damaged) or (isinstance(err, ValueError) and repr(path) in str(err)):
        return err
    if isinstance(err, ValueError | RuntimeError | KeyError | OSError | TypeError):
        return ValueError(f"checkpoint {path!r}: {err}")
    return err
