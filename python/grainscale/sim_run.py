"""The arguments of ``Simulation.run`` and the step a run ends at.

``steps`` must be a whole number (an int, a numpy integer or an integral float such as 1e4), not
a bool; ``until`` a finite real number (s), not a string; ``progress`` True, False or None. A
run whose last step would lie beyond ``MAX_STEP`` (2**62, half the range of the core's int64
step counter) is refused: it could never end (``steps=2**63``, ``until=1e300``).
"""

from __future__ import annotations

import math
from typing import Any

from . import parallel
from ._validate import finite, flag, whole

MAX_STEP = 2**62
OWNER = "Simulation.run"


def check_run_arguments(steps: object, until: object, progress: object) -> None:
    """ValueError naming the argument unless each given one has the documented type."""
    if steps is not None:
        whole(OWNER, "steps", steps, 0)
    if until is not None:
        finite(OWNER, "until", until, " (s)")
    if progress is not None:
        flag(OWNER, "progress", progress)


def target_step(step: int, time: float, steps: object, until: object, dt: float) -> int:
    """The step a run from ``step`` (at ``time``, s) of ``steps`` steps or up to time ``until``
    (s) with time step ``dt`` (s) ends at; ValueError beyond MAX_STEP."""
    if steps is not None:
        target = step + whole(OWNER, "steps", steps, 0)
        if target > MAX_STEP:
            raise ValueError(
                f"{OWNER}.steps must end the run at step 2**62 at most (the step counter is an "
                f"int64), got {steps!r} from step {step}"
            )
        return target
    u = finite(OWNER, "until", until, " (s)")
    if u < time - dt:  # up to a step short of now: rounding of a time the caller computed
        raise ValueError(
            f"{OWNER}.until must not lie before the current time t = {time:.9g} s (a run goes "
            f"forward), got {until!r} s"
        )
    n = (u - time) / dt * (1 - 1e-12)
    if n > MAX_STEP - step:
        raise ValueError(
            f"{OWNER}.until must be reachable within 2**62 steps (the step counter is an int64), "
            f"got {until!r} s: {n:.3g} steps of {dt:.6g} s from t = {time:.6g} s"
        )
    return step + max(0, math.ceil(n))


def next_chunk(chunk: int, n: int, elapsed: float, comm: Any) -> int:
    """Steps per C++ call after a chunk of ``n`` steps took ``elapsed`` s: chunks of 0.25-1 s
    (the size carries over to the next run) keep Ctrl-C and the bar responsive and spread the
    cost of a chunk boundary (statistics, a separate closing kick) over many steps. Under MPI
    every rank must take the same chunks: rank 0's timing decides."""
    if comm is not None:
        with parallel.waiting("Simulation.run (chunk size from rank 0)"):
            elapsed = comm.bcast(elapsed, root=0)
    if elapsed < 0.25 and n == chunk:
        return min(2 * chunk, 100000)
    if elapsed > 1.0 and chunk > 1:
        return chunk // 2
    return chunk
