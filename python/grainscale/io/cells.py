"""The exchange cells of a hierarchy's interface as VTK points (ParaView): one point per region
cell at its centre, with the boundary flag and both levels' cell averages."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from .vtk import write_vtp


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
