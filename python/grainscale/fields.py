"""Eulerian cell averages of a simulation (DESIGN.md 2.7): mass, Favre velocity, solid fraction,
stress tensor (kinetic + contact virial, compression positive), velocity range and velocity
spread (standard deviation about the Favre velocity, m/s per component) on a grid of hexahedral
cells; the averaging is done in C++ (cpp/field/cell_average.hpp, which gives the
definitions). The hierarchy's exchange uses the same averages::

    avg = gs.fields.CellAverages(sim, gs.Box(lo=(0, 0, 0), hi=(0.1, 0.1, 0.05)), cell_size=0.01)
    for _ in range(10):
        sim.run(steps=100)
        avg.sample()            # the contacts of the last step: needs record_contacts=True
    f = avg.finish()            # dict of numpy arrays, cell c = ix + nx (iy + ny iz)
    f["solid_fraction"], f["velocity"], f["stress"]   # (n,), (n, 3), (n, 3, 3)
    f["velocity_min"], f["velocity_max"], f["velocity_spread"]   # (n, 3) each

Under MPI ``sample`` is local and ``finish`` is collective (sums over the ranks).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import _core
from ._validate import positive
from .geometry import Box
from .simulation import Simulation


class CellAverages:
    """Cell averages of ``sim`` over the box ``region`` cut into cells of about ``cell_size``
    (m, one value or one per axis; the edges are adjusted so that a whole number of cells fills
    the box)."""

    def __init__(
        self, sim: Simulation, region: Box, cell_size: float | tuple[float, float, float]
    ) -> None:
        if not isinstance(sim, Simulation):
            raise ValueError(f"CellAverages.sim must be a grainscale.Simulation, got {sim!r}")
        if not isinstance(region, Box):
            raise ValueError(f"CellAverages.region must be a grainscale.Box, got {region!r}")
        sizes = np.broadcast_to(np.asarray(cell_size, dtype=object), (3,))
        if np.ndim(cell_size) not in (0, 1) or np.size(cell_size) not in (1, 3):
            raise ValueError(
                f"CellAverages.cell_size must be a number or 3 numbers (m), got {cell_size!r}"
            )
        edges = [positive("CellAverages", "cell_size", v, " (m)") for v in sizes]
        if not sim.record_contacts:
            raise ValueError(
                "CellAverages needs Simulation(record_contacts=True) for the contact stress, got "
                "record_contacts=False"
            )
        length = np.asarray(region.hi, float) - np.asarray(region.lo, float)
        self.dims = tuple(
            max(1, int(round(float(L) / e))) for L, e in zip(length, edges, strict=True)
        )
        self.edge = tuple(float(L) / n for L, n in zip(length, self.dims, strict=True))
        self.origin = tuple(float(v) for v in region.lo)
        self.sim = sim
        self._avg = _core.CellAverager(self.origin, self.edge, self.dims, sim.dimension)

    @property
    def cells(self) -> int:
        return math.prod(self.dims)

    def centres(self) -> np.ndarray:
        """(n, 3) cell centres, m."""
        c = np.arange(self.cells)
        nx, ny, _ = self.dims
        ijk = np.stack([c % nx, (c // nx) % ny, c // (nx * ny)], axis=1)
        centres: np.ndarray = np.asarray(self.origin) + (ijk + 0.5) * np.asarray(self.edge)
        return centres

    def sample(self) -> None:
        """Adds one sample: the particles now and the contacts of the last step."""
        self._avg.sample(self.sim.engine.core)

    def finish(self) -> dict[str, Any]:
        """The averages over the samples since the last finish (collective); starts anew."""
        return dict(self._avg.finish(self.sim.engine.core))
