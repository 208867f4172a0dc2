"""The exchange cells of a hierarchy's interface as VTK points (ParaView): one point per region
cell at its centre, with the boundary flag and both levels' cell averages."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from .vtk import PVDSeries, write_vtp


def write_exchange_cells(
    path: str | os.PathLike[str],
    grid: dict[str, Any],
    parent: dict[str, Any],
    child: dict[str, Any],
) -> None:
    """Writes the region cells of ``grid`` (an Interface's grid()) with the ``coarse_*`` fields
    of ``parent`` and the ``fine_*`` fields of ``child`` (mass kg, solid fraction, Favre velocity
    m/s, stress Pa as 9 components) to the .vtp file ``path``."""
    cells = np.flatnonzero(grid["inside"] > 0)
    dims, origin, edge = np.array(grid["dims"]), np.array(grid["origin"]), np.array(grid["edge"])
    ijk = np.stack([cells % dims[0], (cells // dims[0]) % dims[1], cells // (dims[0] * dims[1])], 1)
    centres = origin + (ijk + 0.5) * edge
    data = {"boundary": grid["boundary"][cells].astype(np.int32)}
    for name, fields in (("coarse", parent), ("fine", child)):
        data[f"{name}_mass"] = fields["mass"][cells]
        data[f"{name}_solid_fraction"] = fields["solid_fraction"][cells]
        data[f"{name}_velocity"] = fields["velocity"][cells]
        data[f"{name}_stress"] = fields["stress"][cells].reshape(-1, 9)
    write_vtp(path, centres, data)


class ExchangeCellSeries:
    """Every interface's exchange cells written every ``every`` s of simulated time from
    ``start`` on: ``<directory>/cells<k>_<interval>.vtp``, listed in ``cells<k>.pvd``."""

    def __init__(self, directory: Path, every: float, start: float, interfaces: int) -> None:
        self.directory, self.every, self.next = directory, every, start
        self.series = [PVDSeries(directory / f"cells{k}.pvd") for k in range(interfaces)]

    def write(
        self, time: float, interval: int, couplings: list[Any], rank: int, tol: float
    ) -> None:
        """Writes the couplings' last fields if ``time`` (s) has reached the next output time
        (within ``tol`` s); only rank 0 writes."""
        if time < self.next - tol:
            return
        self.next += self.every * max(1, math.ceil((time - self.next) / self.every))
        if rank != 0:
            return
        self.directory.mkdir(parents=True, exist_ok=True)
        for k, c in enumerate(couplings):
            assert c.parent_fields is not None and c.child_fields is not None
            name = f"cells{k}_{interval:08d}.vtp"
            write_exchange_cells(self.directory / name, c.grid, c.parent_fields, c.child_fields)
            self.series[k].add(time, name)
