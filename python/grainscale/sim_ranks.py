"""Simulation's collective queries across MPI ranks: gathered particle arrays, sums over ranks,
the decomposition and load balancing. A mixin of :class:`grainscale.simulation.Simulation`,
which holds the state (``_level``, ``_comm``)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _core, parallel
from ._validate import real
from .particle_view import SCALAR_FIELDS, VECTOR_FIELDS

if TYPE_CHECKING:
    from .particle_view import ParticleView


class RankMethods:
    """The collective methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _comm: Any
    engine: Any

    if TYPE_CHECKING:

        def particles(self, writable: bool = True) -> AbstractContextManager[ParticleView]: ...

        def _resolve_defaults(self) -> None: ...

    def gather(
        self, fields: Sequence[str] = ("position", "velocity", "angular_velocity", "radius", "id")
    ) -> dict[str, np.ndarray]:
        """Collective: copies of the particle arrays of every rank, sorted by id, on every rank.

        Args:
            fields: names of ``particles()`` arrays (``id`` is always included).
        """
        names = list(dict.fromkeys([*fields, "id"]))
        for name in names:
            if name not in VECTOR_FIELDS + SCALAR_FIELDS:
                raise ValueError(
                    f"Simulation.gather.fields must name particle arrays "
                    f"{VECTOR_FIELDS + SCALAR_FIELDS}, got {name!r}"
                )
        with self.particles(writable=False) as p:
            local = {name: np.array(getattr(p, name)) for name in names}
        if self._comm is not None:
            with parallel.waiting("Simulation.gather"):
                parts = self._comm.allgather(local)
            local = {name: np.concatenate([q[name] for q in parts]) for name in names}
        order = np.argsort(local["id"], kind="stable")
        return {name: a[order] for name, a in local.items()}

    def sum_over_ranks(self, value: Any) -> Any:
        """Collective: ``value`` (a number or numpy array, e.g. a sum over this rank's
        ``particles()``) summed over the ranks, on every rank; ``value`` itself when serial."""
        if self._comm is None:
            return value
        with parallel.waiting("Simulation.sum_over_ranks"):
            parts = self._comm.allgather(value)
        total = parts[0]
        for part in parts[1:]:  # in rank order: every rank gets the same bits
            total = total + part
        return total

    def decomposition(self) -> dict[str, Any]:
        """Collective: processor grid, this rank's grid coordinates, the cut positions per axis
        (m) and the particle count of every rank."""
        d = dict(self._level.decomposition())
        d["counts"] = list(self._level.rank_counts())
        return d

    def balance(self, every: int | None = None, threshold: float = 1.05) -> dict[str, float]:
        """Collective: move the subdomain cuts so that every rank holds the same estimated work
        (along each split axis; the particles move at the next step). A particle's work is
        1 + 0.8 per neighbour-list entry + 2 per touching contact: deterministic, so balanced
        runs stay reproducible.

        Args:
            every: also rebalance automatically at neighbour-list builds at least this many
                steps apart, when the imbalance exceeds ``threshold`` (0 switches it off;
                parallel runs start with every = 500, threshold = 1.05).
            threshold: largest rank's work / mean work that automatic balancing accepts.

        Returns: ``{"before": ..., "after": ...}``, the imbalance (largest rank's work / mean).
        """
        self.engine.check_unseen_writes()
        if every is not None:
            if isinstance(every, bool) or not isinstance(every, int | np.integer) or every < 0:
                raise ValueError(
                    f"Simulation.balance.every must be a non-negative integer, got {every!r}"
                )
            limit = real("Simulation.balance", "threshold", threshold)
            if not 1.0 <= limit < math.inf:
                raise ValueError(
                    f"Simulation.balance.threshold must be >= 1 and finite (largest / mean work), "
                    f"got {threshold!r}"
                )
            self._level.set_auto_balance(int(every), limit)
        self._resolve_defaults()
        before, after = self._level.balance()
        return {"before": float(before), "after": float(after)}
