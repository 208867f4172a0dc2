"""Output: VTK XML files for ParaView (no VTK library needed: particles with a choice of fields
and user arrays, the walls as surfaces, the contact network as lines), HDF5 particle dumps and
contact tables with their readers, checkpoints and periodic checkpoints."""

from . import checkpoint, wall_surfaces
from .auto_checkpoint import Checkpoints, latest_checkpoint
from .contact_network import ContactNetwork, read_contacts
from .dump import Dump, DumpSnapshot, read_dump
from .vtk import PVDSeries, write_vtp, write_vtp_lines, write_vtp_mesh
from .vtk_output import VTK

__all__ = [
    "VTK",
    "Checkpoints",
    "ContactNetwork",
    "Dump",
    "DumpSnapshot",
    "PVDSeries",
    "checkpoint",
    "latest_checkpoint",
    "read_contacts",
    "read_dump",
    "wall_surfaces",
    "write_vtp",
    "write_vtp_lines",
    "write_vtp_mesh",
]
