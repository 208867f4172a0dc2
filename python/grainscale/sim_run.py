"""The arguments of ``Simulation.run`` and the step a run ends at.

``steps`` must be a whole number (an int, a numpy integer or an integral float such as 1e4), not
a bool; ``until`` a finite real number (s), not a string; ``progress`` True, False or None. A
run whose last step would lie beyond ``MAX_STEP`` (2**62, half the range of the core's int64
step counter) is refused: it could never end (``steps=2**63``, ``until=1e300``).
"""

from __future__ import annotations

import math

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
    n = (u - time) / dt * (1 - 1e-12)
    if n > MAX_STEP - step:
        raise ValueError(
            f"{OWNER}.until must be reachable within 2**62 steps (the step counter is an int64), "
            f"got {until!r} s: {n:.3g} steps of {dt:.6g} s from t = {time:.6g} s"
        )
    return step + max(0, math.ceil(n))
