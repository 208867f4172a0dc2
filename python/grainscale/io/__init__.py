"""Output: VTK XML files for ParaView (no VTK library needed), the walls as surfaces, and HDF5
checkpoints."""

from . import checkpoint, wall_surfaces
from .vtk import VTK, PVDSeries, write_vtp, write_vtp_mesh

__all__ = ["VTK", "PVDSeries", "checkpoint", "wall_surfaces", "write_vtp", "write_vtp_mesh"]
