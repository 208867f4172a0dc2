"""Output for visualisation: VTK XML files for ParaView (no VTK library needed)."""

from .vtk import VTK, PVDSeries, write_vtp, write_vtp_mesh

__all__ = ["VTK", "PVDSeries", "write_vtp", "write_vtp_mesh"]
