"""Simulation's thermo quantities: what ``sim.thermo()`` returns, what a run records in
``thermo_log`` and prints as thermo lines (also written to the log file, grainscale.sim_output).
A mixin of :class:`grainscale.simulation.Simulation`, which holds the state (``thermo_log``,
``_rate_clock``, ``_header_printed``)."""

from __future__ import annotations

import math
import time as _time
from typing import TYPE_CHECKING, Any

from . import _core


class ThermoMethods:
    """The thermo methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _rate_clock: tuple[float, int]
    _header_printed: bool
    thermo_log: list[dict[str, float]]

    if TYPE_CHECKING:  # Simulation's properties

        @property
        def step(self) -> int: ...

        @property
        def time(self) -> float: ...

        @property
        def num_particles(self) -> int: ...

        @property
        def lost_particles(self) -> int: ...

        @property
        def rank(self) -> int: ...

        def kinetic_energy(self) -> float: ...

        def num_contacts(self) -> int: ...

        def _remaining_seconds(self) -> float: ...

        def _log_write(self, line: str) -> None: ...

    def thermo(self) -> dict[str, float]:
        """Current thermo quantities (see ``thermo_log``): step, time (s), kinetic_energy (J),
        contacts, max_overlap_ratio (largest overlap / smaller radius), particle_steps_per_second
        (since the last entry), particles, lost, and remaining_seconds (wall-clock estimate of
        the time left in the current run from its rate so far; 0 outside a run)."""
        now = _time.perf_counter()
        t0, s0 = self._rate_clock
        rate = (self.step - s0) * self.num_particles / (now - t0) if now > t0 else 0.0
        return {
            "step": self.step,
            "time": self.time,
            "kinetic_energy": self.kinetic_energy(),
            "contacts": self.num_contacts(),
            "max_overlap_ratio": float(self._level.last_max_overlap_ratio()),
            "particle_steps_per_second": rate,
            "particles": self.num_particles,
            "lost": self.lost_particles,
            "remaining_seconds": self._remaining_seconds(),
        }

    # ----------------------------------------------------------------- running
    def _log_thermo(self, print_line: bool, bar: Any = None, log_line: bool = True) -> None:
        """Record a thermo entry; print its line (``print_line``, rank 0) and write it to the
        log file (``log_line``)."""
        entry = self.thermo()
        self._rate_clock = (_time.perf_counter(), self.step)
        self.thermo_log.append(entry)
        if self.rank != 0:
            return
        header = (
            f"{'step':>10} {'time':>11} {'kinetic_energy':>15} {'contacts':>9} "
            f"{'max_overlap/r':>13} {'particle_steps/s':>16} {'lost':>6} {'remaining':>10}"
        )
        line = (
            f"{entry['step']:>10d} {entry['time']:>11.5g} {entry['kinetic_energy']:>15.6g} "
            f"{entry['contacts']:>9d} {entry['max_overlap_ratio']:>13.4g} "
            f"{entry['particle_steps_per_second']:>16.4g} {entry['lost']:>6d} "
            f"{format_remaining(entry['remaining_seconds']):>10}"
        )
        if log_line:
            if not getattr(self, "_log_header_written", False):
                self._log_write("#" + header[1:])
                self._log_header_written = True
            self._log_write(line)
        if print_line:
            # Lines go through the progress bar when one is shown, so they do not tear it.
            write = bar.write if bar is not None else (lambda s: print(s, flush=True))
            if not self._header_printed:
                write(header)
                self._header_printed = True
            write(line)


def format_remaining(seconds: float) -> str:
    """Wall-clock seconds as ``h:mm:ss`` (``-`` when unknown).

    >>> format_remaining(3725.4), format_remaining(float("nan"))
    ('1:02:05', '-')
    """
    if not math.isfinite(seconds) or seconds < 0:
        return "-"
    s = int(round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"
