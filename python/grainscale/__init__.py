"""grainscale: discrete element method for granular materials.

A C++17 core driven from Python. Start with :class:`Simulation`, :class:`Material` and the
laws in :mod:`grainscale.contact`.
"""

from __future__ import annotations

from . import contact, dist, fields, geometry, insert, io, parallel, scaling, timestep
from .geometry import Box, Plane, Rectangle
from .guards import Guards
from .hierarchy import Exchange, Hierarchy, Level
from .materials import Material
from .nesting import nested_levels
from .particle_view import ParticleView
from .sim_walls import WallHandle, WallMotion
from .simulation import Simulation

__version__ = "0.1.0"

__all__ = [
    "Box",
    "Exchange",
    "Guards",
    "Hierarchy",
    "Level",
    "Material",
    "ParticleView",
    "Plane",
    "Rectangle",
    "Simulation",
    "WallHandle",
    "WallMotion",
    "contact",
    "dist",
    "fields",
    "geometry",
    "insert",
    "io",
    "nested_levels",
    "parallel",
    "scaling",
    "timestep",
]
