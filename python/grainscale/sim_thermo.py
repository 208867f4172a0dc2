"""Simulation's thermo quantities: what ``sim.thermo()`` returns, what a run records in
``thermo_log`` and prints as thermo lines. A mixin of :class:`grainscale.simulation.Simulation`,
which holds the state (``thermo_log``, ``_rate_clock``, ``_header_printed``)."""

from __future__ import annotations

import time as _time
from typing import TYPE_CHECKING, Any

from . import _core


class ThermoMethods:
    """The thermo methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _rate_clock: tuple[float, int]
    _header_printed: bool
    thermo_log: list[dict[str, float]]
    step: int
    time: float
    num_particles: int
    lost_particles: int
    rank: int

    if TYPE_CHECKING:

        def kinetic_energy(self) -> float: ...

        def num_contacts(self) -> int: ...

    def thermo(self) -> dict[str, float]:
        """Current thermo quantities (see ``thermo_log``)."""
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
        }

    # ----------------------------------------------------------------- running
    def _log_thermo(self, print_line: bool, bar: Any = None) -> None:
        entry = self.thermo()
        self._rate_clock = (_time.perf_counter(), self.step)
        self.thermo_log.append(entry)
        if print_line and self.rank == 0:
            # Lines go through the progress bar when one is shown, so they do not tear it.
            write = bar.write if bar is not None else (lambda s: print(s, flush=True))
            if not self._header_printed:
                write(
                    f"{'step':>10} {'time':>11} {'kinetic_energy':>15} {'contacts':>9} "
                    f"{'max_overlap/r':>13} {'particle_steps/s':>16} {'lost':>6}"
                )
                self._header_printed = True
            write(
                f"{entry['step']:>10d} {entry['time']:>11.5g} {entry['kinetic_energy']:>15.6g} "
                f"{entry['contacts']:>9d} {entry['max_overlap_ratio']:>13.4g} "
                f"{entry['particle_steps_per_second']:>16.4g} {entry['lost']:>6d}"
            )
