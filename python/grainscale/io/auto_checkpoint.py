"""Periodic checkpoints during a run, keeping the newest few: :class:`Checkpoints`, registered
with ``sim.output(...)`` or made by ``sim.checkpoint_every(...)``, and
:func:`latest_checkpoint` to find the one to restart from.

Each checkpoint is an ordinary one (grainscale.io.checkpoint: written to a temporary file and
renamed, so a crash while writing leaves the earlier files whole; collective under MPI, written
by rank 0). File names carry the step, so they sort in the order they were written.
"""

from __future__ import annotations

import os
import re
import string
from pathlib import Path
from typing import Any

from .paths import make_directory
from .schedule import Schedule

DEFAULT_NAME = "checkpoint_{step:010d}.h5"


def _pattern(owner: str, path: str | os.PathLike[str]) -> str:
    """The file name pattern of ``path``: a pattern with a ``{step}`` field (format spec
    allowed, e.g. ``{step:08d}``) in its file name, or a directory (``checkpoint_{step:010d}.h5``
    inside it)."""
    if not isinstance(path, str | os.PathLike):
        raise ValueError(f"{owner}.path must be a directory or a file name pattern, got {path!r}")
    text = os.fspath(path)
    if "{" not in text:
        return os.path.join(text, DEFAULT_NAME)
    head, name = os.path.split(text)
    try:
        fields = [f for _, f, _, _ in string.Formatter().parse(name) if f is not None]
    except ValueError as err:
        raise ValueError(f"{owner}.path: bad pattern {text!r} ({err})") from None
    if fields != ["step"] or "{" in head:
        raise ValueError(
            f"{owner}.path must have exactly one {{step}} field, in its file name (e.g. "
            f"'out/run_{{step:08d}}.h5'), got {text!r}"
        )
    try:
        name.format(step=0)
    except (ValueError, IndexError, KeyError) as err:
        raise ValueError(f"{owner}.path: bad pattern {text!r} ({err})") from None
    return text


def _regex(pattern: str) -> re.Pattern[str]:
    """Matches the file names of ``pattern`` (group 1: the step)."""
    parts = []
    for literal, field, _, _ in string.Formatter().parse(os.path.basename(pattern)):
        parts.append(re.escape(literal))
        if field is not None:
            parts.append(r"\s*(\d+)")
    return re.compile("".join(parts) + r"\Z")


def _existing(pattern: str) -> list[tuple[int, Path]]:
    """(step, path) of the files of ``pattern`` present, by step."""
    directory = Path(os.path.dirname(pattern) or ".")
    regex = _regex(pattern)
    found = []
    if directory.is_dir():
        for p in directory.iterdir():
            m = regex.match(p.name)
            if m and p.is_file():
                found.append((int(m.group(1)), p))
    return sorted(found)


def latest_checkpoint(path: str | os.PathLike[str]) -> Path | None:
    """The checkpoint with the highest step among the files of ``path`` (a directory or a
    pattern, as for :class:`Checkpoints`), or None when there is none.

        >>> import tempfile, grainscale as gs
        >>> gs.io.latest_checkpoint(tempfile.mkdtemp()) is None
        True
    """
    found = _existing(_pattern("latest_checkpoint", path))
    return found[-1][1] if found else None


class Checkpoints:
    """Checkpoints written periodically during ``run()``, the newest ``keep`` kept.

    Args:
        path: a directory (files ``<directory>/checkpoint_<step:010d>.h5``) or a file name
            pattern with a ``{step}`` field, e.g. ``"out/run_{step:08d}.h5"``.
        every, every_steps: exactly one of a simulated-time interval (s; at the first step whose
            time reaches each multiple of ``every``) or a step interval (at the multiples of
            ``every_steps``). Unlike VTK nothing is written at the step the output is attached
            (a run restarted from a checkpoint does not write it again).
        keep: how many files to keep (at least 1; None keeps all). After each write the
            files of ``path`` whose step is at most the current step are pruned to the
            ``keep`` highest steps, those of an earlier run (before a restart) included; files
            of later steps (from a run the restart went back on) are left alone.

    Every write is an ordinary checkpoint (``sim.checkpoint``): atomic, collective under MPI
    (rank 0 writes the file and prunes). Restart from the newest with
    ``sim.restart(gs.io.latest_checkpoint(path))``.

    Example (files in a temporary directory):
        >>> import tempfile, grainscale as gs
        >>> out = tempfile.mkdtemp()
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), quiet=True)
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> _ = sim.add_particles(position=[[0.005, 0.005, 0.005]], radius=1e-3, material=glass)
        >>> ck = sim.checkpoint_every(out, every_steps=10, keep=2)
        >>> sim.run(steps=45, progress=False)
        >>> [p.name for p in ck.kept()]
        ['checkpoint_0000000030.h5', 'checkpoint_0000000040.h5']
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        every: float | None = None,
        every_steps: int | None = None,
        keep: int | None = 3,
    ) -> None:
        self.pattern = _pattern("Checkpoints", path)
        self._schedule = Schedule("Checkpoints", every, every_steps, at_start=False)
        if keep is not None and (isinstance(keep, bool) or not isinstance(keep, int) or keep < 1):
            raise ValueError(f"Checkpoints.keep must be a positive integer or None, got {keep!r}")
        self.keep = keep
        self.files: list[Path] = []  # the checkpoints this output wrote, in order
        self.removed: list[Path] = []  # the files it deleted

    def __repr__(self) -> str:
        sched = self._schedule.describe()
        return f"Checkpoints({self.pattern!r}, {sched}, keep={self.keep!r})"

    def path_for(self, step: int) -> Path:
        """The file of the checkpoint at ``step``."""
        return Path(self.pattern.format(step=int(step)))

    def kept(self) -> list[Path]:
        """The files of the pattern present now, by step."""
        return [p for _, p in _existing(self.pattern)]

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step > the attachment step at which to write (the output protocol)."""
        return self._schedule.next_step(step, time, time_step)

    def write(self, sim: Any) -> Path:
        """Checkpoint ``sim`` now and prune the older files (collective under MPI)."""
        step = int(sim.step)
        path = self.path_for(step)
        if int(getattr(sim, "rank", 0)) == 0:
            make_directory("Checkpoints.path", path.parent)
        sim.checkpoint(path)
        self.files.append(path)
        self._schedule.done(step, sim.time, sim.time_step)
        note = getattr(sim, "_log_note", None)
        if note is not None:
            note(f"checkpoint {os.fspath(path)} (step {step}, t = {float(sim.time):.9g} s)")
        if self.keep is not None and int(getattr(sim, "rank", 0)) == 0:
            older = [p for s, p in _existing(self.pattern) if s <= step]
            for p in older[: -self.keep]:
                p.unlink(missing_ok=True)
                self.removed.append(p)
        return path
