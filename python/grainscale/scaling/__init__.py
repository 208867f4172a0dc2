"""Scaling laws: the one place where a level's parameters are derived from a reference set.

The C++ core simulates whatever parameters it is given and knows nothing of coarse graining.
:func:`scale` maps a reference :class:`ParameterSet` and a size ratio h to the scaled set, by
one of the schemes of :mod:`grainscale.scaling.table` ("exact", "cg", "sakai", "spa"), and
reports the similarity numbers the scheme does not preserve::

    ref = gs.scaling.ParameterSet(domain=box, contact=law, time_step=1e-6, skin=2e-4, ...)
    coarse = gs.scaling.scale(ref, 4.0, scheme="cg")
    print([b.definition for b in coarse.broken])
    sim = gs.scaling.build_simulation(coarse.params)
"""

from __future__ import annotations

from .level import level_parameters
from .parameters import ParameterSet, Particles, build_simulation
from .table import DIMENSIONS, SCHEMES, Similarity, factors, similarity_exponents
from .transform import Scaled, scale

__all__ = [
    "DIMENSIONS",
    "SCHEMES",
    "ParameterSet",
    "Particles",
    "Scaled",
    "Similarity",
    "build_simulation",
    "factors",
    "level_parameters",
    "scale",
    "similarity_exponents",
]
