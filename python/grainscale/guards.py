"""Guarded runs: checks that stop a run instead of letting it fail unnoticed, and the report of
particles lost through closed sides.

:class:`Guards` (``Simulation(guards=...)``) sets the checks the C++ core makes while a run
advances (cpp/level/guards.hpp):

- a particle that moves more than ``max_step_displacement`` x its radius in one step (it could
  pass through a wall or another particle unseen: tunnelling) or whose position or velocity
  becomes non-finite, checked every step from the largest speed the integrator already finds;
- a contact that overlaps more than ``max_overlap`` x the smaller radius (x the particle's radius
  for a wall), checked at the last step of every run chunk (chunks last 0.25-1 s of wall-clock
  time, and end at every thermo line and output);
- a wall that moves more than ``max_step_displacement`` x the smallest radius in one step
  (its current translation, a servo's included, and rotation times the wall's reach; a drum
  spinning about its own axis stays in place), checked when every run chunk starts.

A guard that trips stops the run with a ``RuntimeError`` on every rank naming the particle's
global id, the step, the value against the limit and a remedy; with ``emergency_checkpoint`` set,
a checkpoint of the state at that step is written first (and the message says where). The checks
only read: a run they do not stop gives the same bits as a run without them.

``Simulation(lost_particles=...)`` says what happens when particles leave through a closed side
of the box (they are removed and counted in ``Simulation.lost_particles``): ``"warn"`` (default)
issues one ``UserWarning`` per run chunk that lost any, with the count and the first global ids;
``"error"`` raises ``RuntimeError`` with the same text; ``"ignore"`` says nothing.
"""

from __future__ import annotations

import dataclasses
import math
import os
import re
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _core, parallel
from ._validate import flag

LOST_POLICIES = ("warn", "error", "ignore")
_IDS_SHOWN = 10  # global ids named in a lost-particle report


@dataclasses.dataclass(frozen=True)
class Guards:
    """Per-step checks of a run (see the module docstring).

    Args:
        max_step_displacement: largest move of a particle in one step, as a fraction of its
            radius (dimensionless, > 0; default 0.5; cf. LIGGGHTS' check/timestep/gran, which
            compares the distance travelled per step with the radius). The move in one step is
            ``time_step x |v|`` (m).
        max_overlap: largest contact overlap, as a fraction of the smaller radius of the pair
            (of the particle's radius for a wall; dimensionless, > 0; default 0.5).
        enabled: False switches every check off (the lost-particle policy is separate).
        emergency_checkpoint: path of an HDF5 checkpoint written (with ``Simulation.checkpoint``)
            when a guard trips, before the error is raised; None (default) writes none.

    Example:
        >>> import grainscale as gs
        >>> guards = gs.Guards(max_step_displacement=0.2, emergency_checkpoint="crash.h5")
    """

    max_step_displacement: float = 0.5
    max_overlap: float = 0.5
    enabled: bool = True
    emergency_checkpoint: str | os.PathLike[str] | None = None

    def __post_init__(self) -> None:
        for name in ("max_step_displacement", "max_overlap"):
            value = getattr(self, name)
            ok = isinstance(value, int | float) and not isinstance(value, bool)
            if not ok or not (value > 0 and math.isfinite(value)):
                raise ValueError(
                    f"Guards.{name} must be a positive, finite fraction of the radius, "
                    f"got {value!r}"
                )
            object.__setattr__(self, name, float(value))
        object.__setattr__(self, "enabled", flag("Guards", "enabled", self.enabled))
        path = self.emergency_checkpoint
        if path is not None and not isinstance(path, str | os.PathLike):
            raise ValueError(
                f"Guards.emergency_checkpoint must be a file path or None, got {path!r}"
            )


def resolve_guards(guards: Guards | bool | None) -> Guards:
    """``Simulation(guards=...)``: a Guards, True / None (the defaults) or False (off)."""
    if guards is None or guards is True:
        return Guards()
    if guards is False:
        return Guards(enabled=False)
    if not isinstance(guards, Guards):
        raise ValueError(
            f"Simulation.guards must be a grainscale.Guards, True, False or None, got {guards!r}"
        )
    return guards


class GuardMethods:
    """Guards and the lost-particle policy of a Simulation (a mixin; see the module
    docstring)."""

    _level: _core.Level
    _comm: Any
    _guards: Guards
    _lost_policy: str
    _run_rayleigh_time: float

    if TYPE_CHECKING:

        def checkpoint(self, path: str | os.PathLike[str]) -> None: ...  # CheckpointMethods

    def _init_guards(self, guards: Guards | bool | None, lost_particles: str) -> None:
        self.guards = resolve_guards(guards)
        self.lost_particles_policy = lost_particles

    @property
    def guards(self) -> Guards:
        """The run's checks (:class:`Guards`); assign a new Guards (or False) to change them."""
        return self._guards

    @guards.setter
    def guards(self, value: Guards | bool | None) -> None:
        g = resolve_guards(value)
        self._level.set_guards(g.enabled, g.max_step_displacement, g.max_overlap)
        self._guards = g

    @property
    def lost_particles_policy(self) -> str:
        """``"warn"``, ``"error"`` or ``"ignore"``: what a run does when particles leave
        through a closed side (see the module docstring)."""
        return self._lost_policy

    @lost_particles_policy.setter
    def lost_particles_policy(self, value: str) -> None:
        if value not in LOST_POLICIES:
            raise ValueError(
                f"Simulation.lost_particles must be one of 'warn', 'error', 'ignore', got {value!r}"
            )
        self._lost_policy = value

    def _run_chunk(self, steps: int, stats: bool) -> None:
        """One C++ run() of ``steps`` steps, with the guards' emergency checkpoint and the
        lost-particle report (collective)."""
        watch = self._lost_policy != "ignore"
        if watch:
            lost_before = int(self._level.lost_particles)
            log_start = int(self._level.lost_log_size)
        try:
            self._level.run(steps, stats)
        except RuntimeError as err:
            if not self._level.guard_tripped:
                raise
            message = self._with_rayleigh_time(str(err))
            raise RuntimeError(self._emergency_checkpoint(message)) from None
        if watch:
            lost = int(self._level.lost_particles) - lost_before
            if lost > 0:
                self._report_lost(lost, log_start)

    def _note_rayleigh_time(self) -> None:
        """Collective, at the start of a run: the smallest Rayleigh time (s) of the particles
        present and of those the streams may insert, for the remedy a guard's message gives.
        The core's message takes it from the particles left when the guard trips: the particle
        that tripped it may have left the domain by then (a sphere at 1e6 m/s), leaving none."""
        self._run_rayleigh_time = math.inf
        if self._guards.enabled:
            self._run_rayleigh_time = min(
                float(self._level.smallest_rayleigh_time()),
                float(self._level.smallest_insertion_rayleigh_time()),
            )

    def _with_rayleigh_time(self, message: str) -> str:
        """The guard's message with the smallest Rayleigh time of every particle of the run
        (see _note_rayleigh_time); the same on every rank."""

        def smallest(found: re.Match[str]) -> str:
            try:
                t_r = min(float(found.group(1)), getattr(self, "_run_rayleigh_time", math.inf))
            except ValueError:
                return found.group(0)
            if math.isinf(t_r):
                return "no particle left to give a Rayleigh time"
            return f"smallest Rayleigh time {t_r:.6g} s"

        return re.sub(r"smallest Rayleigh time (\S+) s", smallest, message, count=1)

    def _emergency_checkpoint(self, message: str) -> str:
        """Writes the emergency checkpoint if one was asked for; returns the error message."""
        path = self._guards.emergency_checkpoint
        if path is None:
            return message
        try:
            self.checkpoint(path)
        except Exception as err:  # e.g. non-finite positions: the lists cannot be rebuilt
            return f"{message}. The emergency checkpoint {os.fspath(path)!r} failed: {err}"
        return f"{message}. Emergency checkpoint of this step written to {os.fspath(path)!r}"

    def _report_lost(self, lost: int, log_start: int) -> None:
        # A hierarchy clears the log between runs, never inside one: the chunk's ids follow
        # log_start (on each rank; gathered under MPI).
        ids = np.asarray(self._level.lost_log(log_start), dtype=np.int64)
        if self._comm is not None:
            with parallel.waiting("Simulation.run (ids of lost particles)"):
                every = self._comm.allgather(ids)
            ids = np.concatenate([np.asarray(a, dtype=np.int64) for a in every])
        ids = np.sort(ids)
        shown = ", ".join(str(int(i)) for i in ids[:_IDS_SHOWN])
        more = ", ..." if len(ids) > _IDS_SHOWN else ""
        text = (
            f"{lost} particle(s) left the domain through a closed side by step "
            f"{int(self._level.step)} and were removed (global ids {shown}{more}; "
            f"{int(self._level.lost_particles)} lost in all). Close the box with walls or make "
            f"the axis periodic; Simulation(lost_particles='ignore') silences this report"
        )
        if self._lost_policy == "error":
            raise RuntimeError(text)
        warnings.warn(text, UserWarning, stacklevel=4)
