"""MPI support: which communicator a simulation runs on, and errors that reach every rank.

A script runs unchanged under ``mpirun -np N python script.py`` (SPMD): every rank builds the
same simulation with the same calls, and each ``Simulation`` is decomposed over the ranks of its
communicator. ``comm=None`` (the default) means ``MPI.COMM_WORLD`` when the process was started
by an MPI launcher with more than one rank, and a serial run otherwise; pass an mpi4py
communicator (``MPI.COMM_SELF`` for a serial simulation on every rank, or a sub-communicator)
to choose. mpi4py is imported only when a run is parallel.

Errors: the C++ core turns an error on one rank into the same exception on every rank at its
next collective step. Python-side errors between run chunks (an output writer, a callback) go
through :func:`agree`, which raises on every rank: the original exception where it happened,
the same exception type with the original message (and the rank) elsewhere.

A rank that stops answering (stuck in a loop, killed, or in a different call) would leave the
others waiting for ever in their next collective. Every wait for other ranks, in the core and
here, is watched: after :func:`timeout` seconds (600 by default, ``GRAINSCALE_MPI_TIMEOUT`` or
:func:`set_timeout`) the waiting rank writes what it waited for to stderr and aborts the whole
job with ``MPI_Abort``. Computation or output on one rank is never timed, only waits.
"""

from __future__ import annotations

import builtins
import dataclasses
import hashlib
import os
import sys
from typing import Any

import numpy as np

from . import _core
from ._optional import mpi

# Launchers' environment variables that give the number of ranks (Open MPI, MPICH/Hydra, PMIx).
_SIZE_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE")


def set_timeout(seconds: float) -> None:
    """Seconds a rank may wait for the other ranks in one collective call before the whole job
    is aborted with a message naming the wait (0 switches the watchdog off). Process-wide.

    >>> import grainscale as gs
    >>> gs.parallel.set_timeout(120.0)
    >>> gs.parallel.timeout()
    120.0
    >>> gs.parallel.set_timeout(600.0)
    """
    from ._validate import real

    _core.set_mpi_timeout(real("parallel.set_timeout", "seconds", seconds))


def timeout() -> float:
    """The watchdog's limit in seconds (see :func:`set_timeout`)."""
    return float(_core.mpi_timeout())


def waiting(what: str) -> Any:
    """Context manager around a blocking mpi4py call of the package: watched by the timeout
    (``what`` names the call in the abort message)."""
    return _core.MpiWait(what)


def launched_ranks() -> int:
    """Number of ranks the MPI launcher started (1 when not started by one)."""
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        return int(mpi.COMM_WORLD.Get_size())
    for name in _SIZE_VARIABLES:
        value = os.environ.get(name)
        if value and value.isdigit():
            return int(value)
    return 1


def world_rank() -> int:
    """This process's rank in ``MPI.COMM_WORLD`` when started by an MPI launcher, else 0 (for
    scripts that write their own files or print from one rank only)."""
    if launched_ranks() <= 1:
        return 0
    return int(mpi().COMM_WORLD.Get_rank())


def resolve(comm: Any) -> Any:
    """The communicator a simulation runs on: an mpi4py communicator of more than one rank, or
    None for a serial run. Raises ValueError for anything else."""
    if comm is None:
        if launched_ranks() <= 1:
            return None
        comm = mpi().COMM_WORLD
    if not (hasattr(comm, "py2f") and hasattr(comm, "Get_size")):
        raise ValueError(f"Simulation.comm must be an mpi4py communicator or None, got {comm!r}")
    if comm.Get_size() == 1:
        return None
    if not _core.with_mpi():
        raise ValueError(
            f"Simulation.comm must have one rank in this build of grainscale (built without MPI), "
            f"got a communicator of {comm.Get_size()} ranks"
        )
    _abort_on_uncaught_exception()
    return comm


_previous_hook: Any = None


def _abort_on_uncaught_exception() -> None:
    """From the first parallel simulation on, an exception that reaches the top of a rank's
    script ends the whole job (as ``python -m mpi4py`` does): the traceback is printed, then
    ``MPI_Abort``. Otherwise the other ranks would wait for this one in their next collective
    until the watchdog's timeout."""
    global _previous_hook
    if _previous_hook is not None:
        return
    _previous_hook = sys.excepthook

    def hook(kind: type[BaseException], value: BaseException, trace: Any) -> None:
        _previous_hook(kind, value, trace)
        MPI = mpi()
        if MPI.Is_initialized() and not MPI.Is_finalized():
            rank = MPI.COMM_WORLD.Get_rank()
            sys.stderr.write(
                f"grainscale: uncaught {kind.__name__} on rank {rank}; aborting every rank "
                "(MPI_Abort)\n"
            )
            sys.stderr.flush()
            MPI.COMM_WORLD.Abort(1)

    sys.excepthook = hook


def agree(comm: Any, error: BaseException | None) -> None:
    """Collective: raise on every rank if ``error`` is set on any (see the module docstring)."""
    if comm is None:
        if error is not None:
            raise error
        return
    with waiting("grainscale.parallel.agree (error agreement between run chunks)"):
        reports = comm.allgather(None if error is None else (type(error).__name__, str(error)))
    failed = [r for r, rep in enumerate(reports) if rep is not None]
    if not failed:
        return
    if error is not None:
        raise error
    rank = failed[0]
    name, message = reports[rank]
    text = f"{message} (raised on rank {rank})"
    kind = getattr(builtins, name, None)
    try:
        same = kind(text) if isinstance(kind, type) and issubclass(kind, Exception) else None
    except Exception:  # an exception type with other constructor arguments
        same = None
    raise same if same is not None else RuntimeError(f"{name}: {text}")


def _feed(digest: Any, value: Any, depth: int = 0) -> None:
    """Every byte of ``value`` into ``digest``: arrays by content, dataclasses (walls, meshes,
    materials) field by field, containers element by element (a repr would abbreviate)."""
    if depth > 8:  # deeper structures (cycles) count by type only
        digest.update(type(value).__qualname__.encode())
    elif isinstance(value, np.ndarray):
        digest.update(f"array{value.dtype}{value.shape}".encode())
        digest.update(np.ascontiguousarray(value).tobytes())
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        digest.update(type(value).__qualname__.encode())
        for f in dataclasses.fields(value):
            _feed(digest, getattr(value, f.name), depth + 1)
    elif isinstance(value, list | tuple):
        digest.update(b"(")
        for item in value:
            _feed(digest, item, depth + 1)
        digest.update(b")")
    elif isinstance(value, dict):
        for key in sorted(value, key=repr):
            _feed(digest, key, depth + 1)
            _feed(digest, value[key], depth + 1)
    elif " at 0x" in repr(value) and hasattr(value, "__dict__"):  # an address differs by rank
        digest.update(type(value).__qualname__.encode())
        _feed(digest, vars(value), depth + 1)
    else:
        digest.update(f"{type(value).__qualname__}:{value!r};".encode())


def _fingerprint(value: Any) -> str:
    """A short text that differs when ``value`` differs: its repr when short and plain, else
    a digest of its content."""
    if not isinstance(value, np.ndarray | list | tuple | dict):
        text = repr(value)
        if len(text) <= 60 and " at 0x" not in text:
            return text
    digest = hashlib.sha256()
    _feed(digest, value)
    shape = f"array{value.shape}:" if isinstance(value, np.ndarray) else ""
    return shape + digest.hexdigest()[:16]


def same_arguments(comm: Any, call: str, **arguments: Any) -> None:
    """Collective: the arguments of a collective ``call`` compared over the ranks before it
    starts, so that ranks that disagree raise the same ValueError instead of waiting for each
    other forever. Arrays are compared by content (a digest of their bytes)."""
    if comm is None:
        return
    mine = {k: _fingerprint(v) for k, v in arguments.items()}
    with waiting(f"the argument agreement of {call}"):
        every = comm.allgather(mine)
    differ = sorted(k for k in mine if len({str(e.get(k)) for e in every}) > 1)
    if differ:
        values = "; ".join(
            f"rank {r}: " + ", ".join(f"{k}={e[k]}" for k in differ) for r, e in enumerate(every)
        )
        raise ValueError(
            f"{call} is collective: every rank must pass the same {', '.join(differ)}, got {values}"
        )
