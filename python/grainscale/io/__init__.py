"""Output: VTK XML files for ParaView (no VTK library needed) and HDF5 checkpoints."""

from . import checkpoint
from .vtk import VTK, PVDSeries, write_vtp, write_vtp_mesh

__all__ = ["VTK", "PVDSeries", "checkpoint", "write_vtp", "write_vtp_mesh"]
