"""level_parameters(): the whole parameter set of one level of a multi-level hierarchy.

A hierarchy (grainscale.hierarchy) simulates one reference system at several resolutions. Every
level's parameters come from the reference by :func:`scale` with the level's size ratio; a finer
level, which covers only its region, then differs from a scaled copy of the whole system in its
box (the region plus a margin), in holding no particles and no insertions of its own (the
coarser level hands it its particles) and in the material of those particles. Its time step is
the hierarchy's to choose (the exchange interval is a whole number of steps of every level).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..geometry import Box
from ..materials import Material
from .parameters import ParameterSet
from .transform import scale

_Point = Sequence[float] | np.ndarray

# A region level's box reaches this many of its largest particle radii beyond the region, so
# that particles near the region's faces have their neighbours and the walls beyond.
REGION_MARGIN_RADII = 4.0
# The Verlet skin, when the reference sets none, in units of the level's largest radius.
SKIN_RADII = 0.2


def level_parameters(
    reference: ParameterSet,
    h: float,
    scheme: str = "cg",
    *,
    region: tuple[_Point, _Point] | None = None,
    region_material: Material | None = None,
    time_step: float | None = None,
) -> ParameterSet:
    """The parameter set of a hierarchy level of size ratio ``h`` (pure: nothing is built).

    Args:
        reference: the reference set; its ``size`` (radius, m) is the size distribution of the
            flowing particles, which every level resolves at its own scale.
        h: the level's size ratio to the reference (> 0; 1 is the reference).
        scheme: scaling scheme of :func:`scale` ("exact", "cg", "sakai", "spa").
        region: (lo, hi) bounds (m) of a finer level's region; None for the coarsest level,
            which covers the reference domain.
        region_material: the material of the particles a region level receives (registered
            after the scaled set's materials).
        time_step: the level's time step (s); None keeps the scaled reference's (possibly
            None). With a time step the skin defaults to 0.2 of the level's largest radius.

    Returns:
        The scaled set, with ``size`` the level's size distribution; for a region level its
        domain is the region grown by 4 largest radii and clipped to the reference domain
        (periodic along an axis only where the region spans the periodic reference domain),
        without particles or insertions.

    Example:
        >>> import grainscale as gs
        >>> glass = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
        >>> box = gs.Box(lo=(0, 0, 0), hi=(0.1, 0.1, 0.1))
        >>> ref = gs.scaling.ParameterSet(domain=box, size=gs.dist.Uniform(1e-3, 1e-3))
        >>> fine = level_parameters(ref, 1.0, region=((0, 0, 0), (0.02, 0.02, 0.02)),
        ...                         region_material=glass, time_step=1e-5)
        >>> fine.domain.hi, round(fine.skin, 6)
        ((0.024, 0.024, 0.024), 0.0002)
    """
    if reference.size is None:
        raise ValueError("level_parameters.reference.size must give the flowing particles' size")
    params = scale(reference, h, scheme).params
    size = params.size
    assert size is not None
    if region is not None:
        params = _region_level(params, reference.domain, region, size.max_radius, region_material)
    if time_step is not None:
        skin = params.skin if params.skin is not None else SKIN_RADII * size.max_radius
        params = dataclasses.replace(params, time_step=time_step, skin=skin)
    return params


def _region_level(
    params: ParameterSet,
    domain: Box,
    region: tuple[_Point, _Point],
    max_radius: float,
    material: Material | None,
) -> ParameterSet:
    dom_lo, dom_hi = np.asarray(domain.lo, float), np.asarray(domain.hi, float)
    lo, hi = np.asarray(region[0], float), np.asarray(region[1], float)
    tol = 1e-9 * float(np.max(dom_hi - dom_lo))
    margin = REGION_MARGIN_RADII * max_radius
    periodic = tuple(
        bool(domain.periodic[a]) and lo[a] <= dom_lo[a] + tol and hi[a] >= dom_hi[a] - tol
        for a in range(3)
    )
    materials = tuple(params.materials) + (() if material is None else (material,))
    return dataclasses.replace(
        params,
        domain=Box(
            lo=tuple(np.maximum(lo - margin, dom_lo)),
            hi=tuple(np.minimum(hi + margin, dom_hi)),
            periodic=periodic,  # type: ignore[arg-type]  # Box turns numpy bools into bools
        ),
        insertions=(),
        particles=(),
        materials=materials,
    )
