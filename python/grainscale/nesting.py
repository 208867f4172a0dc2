"""A chain of levels whose regions nest around a region of interest (:func:`nested_levels`).

The regions follow from the rules the hierarchy applies to them (grainscale.levels): every
level's exchange cell edge (``cell_size_range``), its cells across (``cells_across``) and the
clearance of a region from its parent's interface (``check_nesting``); nothing here sets a rule
of its own.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import scaling
from ._validate import span
from .geometry import Box
from .levels import NESTING_RADII, Exchange, Level, cell_size_range, flowing_size

__all__ = ["nested_levels"]

OWNER = "nested_levels"
# Relative tolerance of the whole-cell arithmetic (a length of n cells is n cells, not n + 1).
ROUNDING = 1e-9


@dataclass(frozen=True)
class _Step:
    """One finer level of the chain: its ratio, exchange cell edge (m), margin (cells) and the
    exchange its Level carries (None: the hierarchy's)."""

    cg: float
    parent: float
    cell: float
    margin: int
    exchange: Exchange | None


def nested_levels(
    base: scaling.ParameterSet,
    roi: Box,
    ratios: Sequence[float],
    exchange: Exchange | Sequence[Exchange] | None = None,
    scheme: str = "cg",
) -> list[Level]:
    """The levels of a chain h_0 > h_1 > ... > h_n whose regions nest around a region of
    interest: the coarsest everywhere (region None), the finest where the flow needs it.

    Args:
        base: the reference parameter set the :class:`~grainscale.Hierarchy` is built from: its
            ``domain`` bounds the regions, its particle size (``size``, else its first
            insertion's radius) with ``scheme`` fixes every level's largest diameter d_k (m) and
            so its exchange cells.
        roi: a gs.Box (m) inside the domain where the finest level must resolve the flow (its
            own, in its interior cells: around an orifice, see :class:`~grainscale.Level`).
        ratios: the coarse-graining ratios, coarsest first, strictly decreasing, the last at
            least 1 (e.g. ``(8, 4, 2, 1)``).
        exchange: the hierarchy's gs.Exchange (pass the same one to the Hierarchy; default
            gs.Exchange()), or one per finer level (``len(ratios) - 1``, set as their
            ``Level.exchange``). Its ``cell_size`` (else the package's default) and ``layer``
            enter the margins.
        scheme: scaling scheme of the levels, as for the Hierarchy.

    Returns:
        ``len(ratios)`` gs.Level, coarsest first; levels 1... with gs.Box regions.

    Level k (k >= 1) is coupled to its parent k - 1 by exchange cells of edge e_k (m): the
    hierarchy's own rule, ``Exchange.cell_size`` or by default 2 d_{k-1}, never below
    max(1.5 d_{k-1}, 2.5 d_k). Its region is the box it must hold (the ROI for the finest, the
    region of level k + 1 otherwise) grown on every side by m_k whole cells e_k, where m_k
    covers what happens on level k's side of its interface faces:

    * its boundary cells, one cell e_k deep, where level k is held to its parent's motion (the
      transition cells): the box it must hold starts behind them, in its interior cells;
    * its insertion band, at most min(2 d_k, e_k) deep (what its parent carries in is placed
      there), and its stress layer, ``Exchange.layer`` x d_k deep;
    * the clearance check_nesting asks of a finer region from level k's interface faces,
      NESTING_RADII (5) x d_k / 2 (level k's insertion shells).

    m_k = ceil(max(e_k, layer d_k, 2.5 d_k) / e_k) cells, which is 1 under the package's rules
    (e_k >= 2.5 d_k, layer 1.3 d_k), more only with a thicker layer (the clearance counts as
    met only strictly, so an edge of exactly 2.5 d_k takes 2). The region is then grown to a
    whole number of cells along each axis, at least 4 between opposite interface faces and 2
    where one face is on the domain's side (the cells the hierarchy's grid needs; the slack,
    less than a cell, split between the two sides), so that the grid's edge is e_k exactly and
    at least m_k whole cells lie between the box and every interface face. A face that would
    end less than one cell e_k from a closed side of the domain is put on it (a thinner sliver
    of the parent's material beside a wall is no flow; a face on the domain's side is no
    interface), and the other face is placed a whole number of cells from it. Along a periodic
    axis the regions must fit inside the domain.

    Raises:
        ValueError: naming the parameter and value: ratios not strictly decreasing or below 1,
            a ROI outside the domain, a cell size below the valid range, or margins that do not
            fit: a region that would cover the whole domain (its parent would hold nothing) or
            cross a periodic side, with the level and by how much.

    Example:
        >>> import grainscale as gs
        >>> import numpy as np
        >>> ref = gs.scaling.ParameterSet(domain=gs.Box(lo=(0, 0, 0), hi=(0.2, 0.2, 0.3)),
        ...                               size=gs.dist.Uniform(0.9e-3, 1e-3))
        >>> orifice = gs.Box(lo=(0.08, 0.08, 0), hi=(0.12, 0.12, 0.04))  # on the floor
        >>> for level in gs.nested_levels(ref, orifice, ratios=(8, 4, 2, 1)):
        ...     r = level.region
        ...     print(level.cg, r if r is None else np.round([r.lo, r.hi], 4).tolist())
        8 None
        4 [[0.0, 0.0, 0.0], [0.2, 0.2, 0.096]]
        2 [[0.052, 0.052, 0.0], [0.148, 0.148, 0.064]]
        1 [[0.072, 0.072, 0.0], [0.128, 0.128, 0.048]]

        The resolved level holds the orifice region with one cell (2 d_2 = 8 mm) around it, 7
        cells across and 6 high; the level at h = 2 holds that with one cell of 16 mm (96 mm
        = 6 cells across); the one at h = 4 with one cell of 32 mm would end 20 mm from the
        side walls, less than a cell, so its faces are on them.
    """
    if not isinstance(base, scaling.ParameterSet):
        raise ValueError(f"{OWNER}.base must be a gs.scaling.ParameterSet, got {base!r}")
    chain = _ratios(ratios)
    domain = base.domain
    lo, hi = _roi(roi, domain)
    steps = _steps(base, chain, exchange, scheme)
    regions: list[Box] = []
    for k in range(len(chain) - 1, 0, -1):  # finest first: each holds the next finer one
        lo, hi = _grow(lo, hi, domain, steps[k - 1], k)
        regions.insert(0, Box(lo=tuple(lo), hi=tuple(hi)))
    given = list(ratios)  # the ratios as given (8, not 8.0)
    levels = [Level(cg=given[0])]
    for h, step, region in zip(given[1:], steps, regions, strict=True):
        levels.append(Level(cg=h, region=region, exchange=step.exchange))
    return levels


def _ratios(ratios: Sequence[float]) -> list[float]:
    try:
        chain = [float(h) for h in ratios]
        if isinstance(ratios, str | bytes) or len(chain) != len(ratios):
            raise TypeError
    except (TypeError, ValueError):
        raise ValueError(
            f"{OWNER}.ratios must be a sequence of coarse-graining ratios, got {ratios!r}"
        ) from None
    if not chain or not all(math.isfinite(h) for h in chain):
        raise ValueError(f"{OWNER}.ratios must be finite ratios, coarsest first, got {ratios!r}")
    if any(b >= a for a, b in zip(chain, chain[1:], strict=False)):
        raise ValueError(
            f"{OWNER}.ratios must be strictly decreasing (coarsest first), got {tuple(ratios)!r}"
        )
    if chain[-1] < 1:
        raise ValueError(
            f"{OWNER}.ratios must end at least at 1 (the resolved reference), got {tuple(ratios)!r}"
        )
    return chain


def _roi(roi: Box, domain: Box) -> tuple[np.ndarray, np.ndarray]:
    if not isinstance(roi, Box):
        raise ValueError(f"{OWNER}.roi must be a gs.Box, got {roi!r}")
    lo, hi = np.asarray(roi.lo, float), np.asarray(roi.hi, float)
    dlo, dhi = np.asarray(domain.lo, float), np.asarray(domain.hi, float)
    tol = ROUNDING * float(np.max(dhi - dlo))
    if np.any(lo < dlo - tol) or np.any(hi > dhi + tol):
        raise ValueError(
            f"{OWNER}.roi must lie inside the domain {span(dlo, dhi)}, got {span(lo, hi)}"
        )
    return np.maximum(lo, dlo), np.minimum(hi, dhi)


def _steps(
    base: scaling.ParameterSet,
    chain: list[float],
    exchange: Exchange | Sequence[Exchange] | None,
    scheme: str,
) -> list[_Step]:
    """Cell edge and margin of every finer level (the hierarchy's rules, from the levels'
    largest diameters as the hierarchy scales them)."""
    size = flowing_size(base, OWNER)
    if size is None:
        raise ValueError(
            f"{OWNER}.base must give the particles' size (size, or an insertion's radius), got "
            "neither"
        )
    per_level = exchange is not None and not isinstance(exchange, Exchange)
    exchanges: list[Exchange]
    if exchange is None or isinstance(exchange, Exchange):
        exchanges = [exchange or Exchange()] * (len(chain) - 1)
    else:
        try:
            exchanges = list(exchange)
        except TypeError:
            exchanges = []
        if len(exchanges) != len(chain) - 1 or not all(isinstance(e, Exchange) for e in exchanges):
            got = f"{len(exchanges)} items" if exchanges else repr(exchange)
            raise ValueError(
                f"{OWNER}.exchange must be a gs.Exchange or one per finer level "
                f"({len(chain) - 1}), got {got}"
            )
    reference = scaling.ParameterSet(domain=base.domain, size=size)
    diameters = [
        2 * scaling.level_parameters(reference, h, scheme).size.max_radius  # type: ignore[union-attr]
        for h in chain
    ]
    steps = []
    for k in range(1, len(chain)):
        ex, d = exchanges[k - 1], diameters[k]
        lowest, cell = cell_size_range(diameters[k - 1], d)
        if ex.cell_size is not None:
            if ex.cell_size < lowest * (1 - ROUNDING):
                raise ValueError(
                    f"{OWNER}.exchange.cell_size of level {k} (cg={chain[k]:g}) must be at "
                    f"least {lowest:.4g} m (1.5 parent and 2.5 child diameters), got "
                    f"{ex.cell_size!r}"
                )
            cell = float(ex.cell_size)
        # Transition cells and insertion band: one cell; stress layer; check_nesting's clearance
        # (strictly, so that round-off in the check cannot refuse an exact fit).
        within = max(cell, ex.layer * d) / cell
        clear = NESTING_RADII * 0.5 * d * (1 + ROUNDING) / cell
        margin = max(math.ceil(within * (1 - ROUNDING)), math.ceil(clear))
        steps.append(_Step(chain[k], chain[k - 1], cell, margin, ex if per_level else None))
    return steps


def _grow(
    lo: np.ndarray, hi: np.ndarray, domain: Box, step: _Step, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Level k's region around the box [lo, hi] it must hold (m)."""
    dlo, dhi = np.asarray(domain.lo, float), np.asarray(domain.hi, float)
    reach = step.margin * step.cell
    axes = [
        _axis(lo[a] - reach, hi[a] + reach, dlo[a], dhi[a], step.cell, bool(domain.periodic[a]))
        for a in range(3)
    ]
    out_lo, out_hi = np.array([s[0] for s in axes]), np.array([s[1] for s in axes])
    spans = []
    for a in range(3):
        spans.append(out_lo[a] <= dlo[a] and out_hi[a] >= dhi[a])
        if domain.periodic[a] and (out_lo[a] < dlo[a] or out_hi[a] > dhi[a]):
            over = max(dlo[a] - out_lo[a], out_hi[a] - dhi[a])
            raise ValueError(
                f"{OWNER}: the region of level {k} (cg={step.cg:g}) must hold "
                f"{span(lo, hi)} with {step.margin} exchange cell(s) of {step.cell:.4g} m around "
                f"it; along the periodic axis {'xyz'[a]} it would cross the domain's side by "
                f"{over:.4g} m ({span(out_lo, out_hi)} in {span(dlo, dhi)})"
            )
    if all(spans):
        # How much longer the domain would have to be along the best axis for the parent to
        # keep one cell beside the region.
        short = min(
            min(dlo[a] + step.cell - (lo[a] - reach), hi[a] + reach - (dhi[a] - step.cell))
            for a in range(3)
        )
        raise ValueError(
            f"{OWNER}: the region of level {k} (cg={step.cg:g}) must hold {span(lo, hi)} with "
            f"{step.margin} exchange cell(s) of {step.cell:.4g} m around it, which covers the "
            f"whole domain {span(dlo, dhi)}: its parent (cg={step.parent:g}) would hold nothing. "
            f"The domain is {max(short, 0.0):.4g} m too short along its best axis to leave the "
            f"parent one cell beside the region; drop the coarser ratios, shrink the roi or "
            f"enlarge the domain"
        )
    return out_lo, out_hi


def _axis(
    lo: float, hi: float, dlo: float, dhi: float, cell: float, periodic: bool
) -> tuple[float, float]:
    """One axis of a region that must reach from ``lo`` to ``hi`` (m): whole cells, at least 4
    between two interface faces and 2 with one on a closed side of the domain, a face less than
    a cell from a closed side put on it."""

    def cells(length: float, least: int) -> int:
        return max(least, math.ceil(length / cell * (1 - ROUNDING)))

    on_lo = not periodic and lo < dlo + cell * (1 - ROUNDING)
    on_hi = not periodic and hi > dhi - cell * (1 - ROUNDING)
    while True:  # a face once on a side stays there: at most three passes
        if on_lo and on_hi:
            return dlo, dhi
        if on_lo:
            top = dlo + cells(hi - dlo, 2) * cell
            if top > dhi - cell * (1 - ROUNDING):
                on_hi = True
                continue
            return dlo, top
        if on_hi:
            bottom = dhi - cells(dhi - lo, 2) * cell
            if bottom < dlo + cell * (1 - ROUNDING):
                on_lo = True
                continue
            return bottom, dhi
        n = cells(hi - lo, 4)
        start = lo - 0.5 * (n * cell - (hi - lo))
        on_lo = not periodic and start < dlo + cell * (1 - ROUNDING)
        on_hi = not periodic and start + n * cell > dhi - cell * (1 - ROUNDING)
        if not (on_lo or on_hi):
            return start, start + n * cell
