"""When a periodic output writes: every ``every`` seconds of simulated time or every
``every_steps`` steps. Shared by the output operations of :mod:`grainscale.io` (VTK, Dump,
ContactNetwork, Checkpoints).

A schedule follows the protocol of ``Simulation.output()``: ``next_step(step, time,
time_step)`` returns the next step at which the output is due; after writing, the output calls
``done(step, time)``.
"""

from __future__ import annotations

import math
import numbers


def check_every(owner: str, every: object, every_steps: object) -> tuple[float | None, int | None]:
    """``(every, every_steps)`` validated: exactly one given, a positive finite time in s or a
    positive integer; ValueError naming ``owner`` otherwise."""
    if (every is None) == (every_steps is None):
        raise ValueError(
            f"{owner} needs exactly one of every (s) or every_steps, "
            f"got every={every!r}, every_steps={every_steps!r}"
        )
    if every is not None:
        if (
            isinstance(every, bool)
            or not isinstance(every, numbers.Real)
            or not math.isfinite(every)
            or every <= 0
        ):
            raise ValueError(f"{owner}.every must be a positive finite time in s, got {every!r}")
        return float(every), None
    if (
        isinstance(every_steps, bool)
        or not isinstance(every_steps, numbers.Integral)
        or every_steps <= 0
    ):
        raise ValueError(f"{owner}.every_steps must be a positive integer, got {every_steps!r}")
    return None, int(every_steps)


class Schedule:
    """The steps at which a periodic output writes.

    Args:
        owner: the output's name, for error messages (e.g. ``"VTK"``).
        every: simulated-time interval, s: the first step whose time reaches each multiple of
            ``every`` (t = 0, every, 2 every, ...).
        every_steps: step interval: the steps that are multiples of ``every_steps``.
        at_start: the first call of ``next_step`` is due at once (the step the output is
            attached at); False: the first multiple after it (a checkpoint is not rewritten at
            the step a run was restarted from).
    """

    def __init__(
        self,
        owner: str,
        every: float | None = None,
        every_steps: int | None = None,
        at_start: bool = True,
    ) -> None:
        self.every, self.every_steps = check_every(owner, every, every_steps)
        self.at_start = bool(at_start)
        self.last_step: int | None = None  # step of the last write
        self._next_index = 0  # index n of the next output time n * every not yet covered
        self.time_step: float | None = None  # last time step seen by next_step, s

    def describe(self) -> str:
        """``every=...`` or ``every_steps=...`` (for reprs)."""
        if self.every is not None:
            return f"every={self.every!r}"
        return f"every_steps={self.every_steps}"

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step >= ``step`` at which to write.

        Args:
            step: current step number.
            time: simulated time at ``step``, s.
            time_step: integration time step, s (assumed constant until the returned step).
        """
        step = int(step)
        self.time_step = float(time_step)
        if self.last_step is None:
            if self.at_start:
                return step  # never written yet: write now
            self.done(step, time)  # the attachment step counts as written
        assert self.last_step is not None
        earliest = max(step, self.last_step + 1)
        if self.every_steps is not None:
            k = self.every_steps
            return -(-earliest // k) * k  # ceil to a multiple of k
        assert self.every is not None
        target = self._next_index * self.every
        # first step whose time reaches the target (tolerance 1e-6 step for round-off)
        steps_ahead = math.ceil((target - float(time)) / float(time_step) - 1e-6)
        return max(step + steps_ahead, earliest)

    def done(self, step: int, time: float, time_step: float | None = None) -> None:
        """Record a write at ``step`` (time ``time``, s): the output times up to ``time`` are
        covered."""
        self.last_step = int(step)
        if self.every is not None:
            dt = time_step if time_step is not None else self.time_step
            # output times up to time (+ 1e-3 step for round-off) are covered by this snapshot
            covered = math.floor((float(time) + 1e-3 * float(dt or 0.0)) / self.every)
            self._next_index = max(self._next_index, covered + 1)
