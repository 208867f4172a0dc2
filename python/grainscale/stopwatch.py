"""Wall-clock accumulated per named part of a loop: where a run's time goes."""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager


class Stopwatch:
    """Seconds of wall-clock (this rank) per part, summed over every timed stretch.

    Example:
        >>> watch = Stopwatch(("insert", "sample"))
        >>> with watch.part("insert"):
        ...     pass
        >>> sorted(watch.seconds)
        ['insert', 'sample']
        >>> watch.seconds["insert"] >= 0.0
        True
    """

    def __init__(self, parts: tuple[str, ...]) -> None:
        self.seconds: dict[str, float] = dict.fromkeys(parts, 0.0)

    @contextmanager
    def part(self, name: str) -> Iterator[None]:
        """Adds the wall-clock of the ``with`` block to ``seconds[name]`` (a known part)."""
        if name not in self.seconds:
            raise KeyError(f"Stopwatch.part: unknown part {name!r}, known {sorted(self.seconds)}")
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] += time.perf_counter() - t0
