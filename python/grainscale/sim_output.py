"""Simulation's outputs: the output operations called during ``run()`` (grainscale.io: VTK,
Dump, ContactNetwork, Checkpoints), periodic checkpoints, and the log file that receives every
thermo line and warning. A mixin of :class:`grainscale.simulation.Simulation`, which holds the
state (``_outputs``, ``_log_path``)."""

from __future__ import annotations

import datetime
import os
import time as _time
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from . import parallel

if TYPE_CHECKING:
    from .io.auto_checkpoint import Checkpoints


class Output(Protocol):
    """What Simulation.output() accepts (e.g. grainscale.io.VTK). An output may also have an
    ``attach(sim)`` method, called when it is registered."""

    def next_step(self, step: int, time: float, time_step: float) -> int: ...

    def write(self, sim: Any) -> Any: ...


class OutputMethods:
    """The output methods of a Simulation (see the module docstring)."""

    _outputs: list[tuple[Output, int]]
    _log_path: Path | None
    _run_clock: tuple[float, int, int] | None

    if TYPE_CHECKING:  # Simulation's properties

        @property
        def comm(self) -> Any: ...

        @property
        def rank(self) -> int: ...

        @property
        def ranks(self) -> int: ...

        @property
        def step(self) -> int: ...

        @property
        def time(self) -> float: ...

    def output(self, writer: Output) -> None:
        """Register an output operation, called during run(): ``grainscale.io.VTK`` (particle
        snapshots for ParaView), ``Dump`` (HDF5 particle dumps), ``ContactNetwork`` (contacts
        and forces), ``Checkpoints`` (periodic checkpoints), or any object with
        ``next_step(step, time, time_step)`` and ``write(sim)``."""
        if not hasattr(writer, "next_step") or not hasattr(writer, "write"):
            raise ValueError(f"Simulation.output needs an output operation, got {writer!r}")
        attach = getattr(writer, "attach", None)
        if callable(attach):
            attach(self)
        self._outputs.append((writer, -1))

    @property
    def outputs(self) -> list[Output]:
        """The registered output operations, in registration order."""
        return [w for w, _ in self._outputs]

    def checkpoint_every(
        self,
        path: str | os.PathLike[str],
        every: float | None = None,
        every_steps: int | None = None,
        keep: int | None = 3,
    ) -> Checkpoints:
        """Checkpoint periodically during run(), keeping the newest ``keep`` files; returns the
        registered :class:`grainscale.io.Checkpoints` (its ``files``, ``kept()``).

        Args:
            path: a directory (``checkpoint_<step:010d>.h5`` inside) or a file name pattern
                with a ``{step}`` field, e.g. ``"out/run_{step:08d}.h5"``.
            every: simulated-time interval, s; or
            every_steps: step interval (exactly one of the two).
            keep: files kept (None: all).

        Restart with ``sim.restart(gs.io.latest_checkpoint(path))``.
        """
        from .io.auto_checkpoint import Checkpoints

        parallel.same_arguments(
            self.comm,
            "Simulation.checkpoint_every",
            path=os.fspath(path) if isinstance(path, str | os.PathLike) else path,
            every=every,
            every_steps=every_steps,
            keep=keep,
        )
        writer = Checkpoints(path, every=every, every_steps=every_steps, keep=keep)
        self.output(writer)
        return writer

    def _start_outputs(self, dt: float) -> None:
        self._outputs = [(w, w.next_step(self.step, self.time, dt)) for w, _ in self._outputs]
        self._write_due_outputs(dt)

    def _write_due_outputs(self, dt: float) -> None:
        updated = []
        for writer, due in self._outputs:
            if due == self.step:
                writer.write(self)
                due = writer.next_step(self.step + 1, self.time + dt, dt)
            updated.append((writer, due))
        self._outputs = updated

    # ------------------------------------------------------------------------ log file
    def log(self, path: str | os.PathLike[str] | None, append: bool = True) -> None:
        """Write a log file: every thermo line (whether printed or ``quiet``), every warning
        raised during ``run()``, and a line at the start and end of each run and for each
        periodic checkpoint. Lines other than thermo lines start with ``#`` (the column header
        too), so ``numpy.loadtxt(path, usecols=range(7))`` reads the thermo numbers.

        Args:
            path: the log file (its directory is created); None stops logging.
            append: add to an existing file (a restarted run continues its log); False starts
                it anew.

        Under MPI rank 0 writes the file (collective call; warnings of the other ranks are not
        in it).

        Example:
            >>> import os, tempfile, grainscale as gs
            >>> path = os.path.join(tempfile.mkdtemp(), "run.log")
            >>> box = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01))
            >>> sim = gs.Simulation(domain=box, thermo_every=5, quiet=True)
            >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
            >>> _ = sim.add_particles(position=[[0.005] * 3], radius=1e-3, material=glass)
            >>> sim.log(path)
            >>> sim.run(steps=10, progress=False)
            >>> [line.split()[0] for line in open(path) if not line.startswith("#")]
            ['5', '10']
        """
        parallel.same_arguments(
            self.comm, "Simulation.log", path=None if path is None else os.fspath(path)
        )
        if path is None:
            self._log_path = None
            return
        self._log_path = Path(path)
        self._log_header_written = False
        if self.rank == 0:
            self._log_path.parent.mkdir(parents=True, exist_ok=True)
            if not append:
                self._log_path.write_text("")
        from . import __version__

        when = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        self._log_note(
            f"grainscale {__version__} log opened {when}: step {self.step}, t = {self.time:.9g} s,"
            f" {self.ranks} rank(s)"
        )

    @property
    def log_path(self) -> Path | None:
        """The log file (None when not logging)."""
        return self._log_path

    def _log_write(self, line: str) -> None:
        """Append ``line`` to the log (rank 0; nothing without a log)."""
        if self._log_path is None or self.rank != 0:
            return
        with open(self._log_path, "a", encoding="utf-8") as f:
            f.write(line.rstrip("\n") + "\n")

    def _log_note(self, text: str) -> None:
        """A ``#`` line in the log."""
        for line in str(text).splitlines() or [""]:
            self._log_write(f"# {line}")

    @contextmanager
    def _logged_run(self, target: int) -> Iterator[None]:
        """Around a run to ``target``: the clock of its remaining-time estimate, and with a log
        the run's start and end lines and its warnings (also shown as usual)."""
        start = _time.perf_counter()
        self._run_clock = (start, self.step, int(target))
        if self._log_path is None:
            try:
                yield
            finally:
                self._run_clock = None
            return
        self._log_note(f"run from step {self.step} (t = {self.time:.9g} s) to step {target}")
        shown = warnings.showwarning

        def show(
            message: Any,
            category: Any,
            filename: str,
            lineno: int,
            file: Any = None,
            line: str | None = None,
        ) -> None:
            self._log_note(f"warning ({category.__name__}): {message}")
            shown(message, category, filename, lineno, file, line)

        outcome = "ended"
        with warnings.catch_warnings():
            warnings.showwarning = show
            try:
                yield
            except BaseException as err:
                outcome = f"stopped by {type(err).__name__}: {err}"
                raise
            finally:
                self._run_clock = None
                seconds = _time.perf_counter() - start
                self._log_note(
                    f"run {outcome} at step {self.step} (t = {self.time:.9g} s) after "
                    f"{seconds:.3f} s"
                )

    def _remaining_seconds(self) -> float:
        """Estimated wall-clock seconds until the current run ends (from its rate so far);
        0 outside a run, NaN before the run's first step."""
        clock = self._run_clock
        if clock is None:
            return 0.0
        start, first, target = clock
        done = self.step - first
        if done <= 0:
            return float("nan")
        return (_time.perf_counter() - start) / done * max(0, target - self.step)
