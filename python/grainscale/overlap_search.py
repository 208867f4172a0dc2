"""The searches behind the set-up checks (:mod:`grainscale.placement`), vectorised in numpy:
pairs of particles that overlap (cell lists, periodic axes wrapped to the nearest image) and
particles that overlap a triangle mesh (closest point on a triangle, candidates from a grid).

Pairs: the particles are split into radius classes (radii within a factor 2), and each pair of
classes is searched on a grid of cells at least as wide as the largest contact distance between
them, so a few large particles among many small ones do not fill every cell with hundreds of
candidates. A grid holds one set; the other set's particles look up their own cell and the
neighbouring ones (a particle against its own set: half of the neighbours, each pair once).
Cost: O(N) per class pair, in chunks of a bounded number of candidate pairs. A heap of far more
candidates than any packing holds (particles stacked on one point) ends the search early: the
count is then a lower bound (``Found.complete`` False).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

CAP = 1 << 20  # cells per axis at most: a cell key of three axes fits in an int64
CHUNK = 1 << 21  # candidate pairs examined at once (bounded memory)
DENSE = 16  # a table of every cell when there are at most this many cells per point
BUDGET = 200  # candidate pairs per particle examined before the search stops, overlaps found
KEEP = 1000  # offending pairs kept (the smallest indices), for the message


@dataclass(frozen=True)
class Space:
    """The domain as the search sees it: lower corner, edge lengths, periodic axes, and the
    axes measured (3; 2 for discs, whose z is ignored)."""

    lo: np.ndarray
    length: np.ndarray
    periodic: np.ndarray
    axes: int = 3

    def __post_init__(self) -> None:  # a box too long for float64 does not wrap
        object.__setattr__(self, "periodic", self.periodic & np.isfinite(self.length))

    def wrap(self, x: np.ndarray) -> np.ndarray:
        """Coordinates on periodic axes brought into [lo, lo + length)."""
        x = np.array(x, dtype=float)
        for a in np.flatnonzero(self.periodic):
            x[:, a] = self.lo[a] + np.mod(x[:, a] - self.lo[a], self.length[a])
        return x

    def columns(self, x: np.ndarray) -> list[np.ndarray]:
        """The measured coordinates of the points ``x``, one contiguous array per axis (faster
        to gather from)."""
        return [np.ascontiguousarray(x[:, a]) for a in range(self.axes)]

    def distance2(
        self, x: list[np.ndarray], i: np.ndarray, y: list[np.ndarray], j: np.ndarray
    ) -> np.ndarray:
        """Squared distances between points x[i] and y[j] (columns), nearest periodic image."""
        total = np.zeros(len(i))
        for a in range(self.axes):
            d = x[a].take(i) - y[a].take(j)
            if self.periodic[a]:
                d -= self.length[a] * np.round(d / self.length[a])
            total += d * d
        return total


class Grid:
    """Points binned in cells at least ``size`` wide; ``lo``/``hi`` bound, on closed axes,
    every point that is binned or looked up."""

    def __init__(
        self, points: np.ndarray, size: float, space: Space, lo: np.ndarray, hi: np.ndarray
    ) -> None:
        self.shape = np.ones(3, dtype=np.int64)
        self.width = np.full(3, np.inf)
        self.origin = np.zeros(3)
        self.periodic = np.zeros(3, bool)
        for a in range(space.axes):
            if space.periodic[a]:
                cells = space.length[a] / size  # inf for a tiny size: capped
                self.shape[a] = int(min(max(cells, 1.0), CAP)) if cells == cells else 1
                self.width[a] = space.length[a] / self.shape[a]
                self.origin[a] = space.lo[a]
                self.periodic[a] = True
            else:
                extent = float(hi[a] - lo[a])
                self.origin[a] = lo[a]
                self.width[a] = max(size, extent / (CAP - 1))
                if np.isfinite(self.width[a]):  # else one cell (coordinates near overflow)
                    self.shape[a] = int(extent // self.width[a]) + 1
        self.stride = np.array([self.shape[1] * self.shape[2], self.shape[2], 1])
        cells = int(np.prod(self.shape))
        key = self.key(self.cells(points))
        self.order = np.argsort(key, kind="stable")
        self.dense = cells <= DENSE * (len(points) + 256)
        self.empty = cells  # the key of an empty cell, for neighbours beyond a closed side
        if self.dense:  # where every cell's run starts in ``order``
            self.start = np.zeros(cells + 2, dtype=np.int64)
            np.cumsum(np.bincount(key, minlength=cells + 1), out=self.start[1:])
        else:  # only the occupied cells, found by binary search
            self.keys, self.first, counts = np.unique(
                key[self.order], return_index=True, return_counts=True
            )
            self.counts = counts.astype(np.int64)

    def cells(self, x: np.ndarray) -> np.ndarray:
        """(m, 3) cell indices of the points ``x``."""
        with np.errstate(invalid="ignore", over="ignore"):
            i = np.floor((x - self.origin) / self.width)  # 0 on the axes not binned (width inf)
        cells: np.ndarray = np.clip(np.nan_to_num(i), 0, self.shape - 1).astype(np.int64)
        return cells

    def key(self, i: np.ndarray) -> np.ndarray:
        keys: np.ndarray = i @ self.stride
        return keys

    def lookup(self, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(start in ``order``, count) of the points in the cells of keys ``k``."""
        if self.dense:
            start = self.start[k]
            return start, self.start[k + 1] - start
        at = np.minimum(np.searchsorted(self.keys, k), len(self.keys) - 1)
        return self.first[at], np.where(self.keys[at] == k, self.counts[at], 0)

    def neighbours(self, cells: np.ndarray) -> Callable[[tuple[int, ...]], tuple[np.ndarray, ...]]:
        """A function of an offset: ``lookup`` of the cells ``cells + offset`` (periodic axes
        wrap, closed ones end)."""
        base = self.key(cells)
        edges = [(cells[:, a] == 0, cells[:, a] == self.shape[a] - 1) for a in range(3)]

        def at(offset: tuple[int, ...]) -> tuple[np.ndarray, ...]:
            k = base + int(np.dot(offset, self.stride))
            beyond = None  # past a closed side
            for a in range(3):
                if offset[a]:
                    edge = edges[a][offset[a] > 0]
                    if self.periodic[a]:
                        np.subtract(k, offset[a] * self.shape[a] * self.stride[a], k, where=edge)
                    else:
                        beyond = edge if beyond is None else beyond | edge
            if beyond is not None:
                k[beyond] = self.empty
            return self.lookup(k)

        return at

    def stencil(self, half: bool) -> list[tuple[tuple[int, ...], bool]]:
        """Offsets to the distinct neighbouring cells, with whether a pair found through the
        offset must be kept only once (point index below partner's). ``half``: one of each
        offset and its opposite, for a set against itself."""
        steps: list[tuple[int, ...]] = []
        for a in range(3):
            if self.shape[a] == 1:
                steps.append((0,))
            elif self.periodic[a] and self.shape[a] == 2:  # +1 and -1 are the same cell
                steps.append((0, 1))
            else:
                steps.append((-1, 0, 1))
        out = []
        for o in itertools.product(*steps):
            back = tuple(o[a] if steps[a] == (0, 1) else -o[a] for a in range(3))
            if not half:
                out.append((o, False))
            elif back == o:  # the pair is met from both sides through this offset
                out.append((o, True))
            elif o > back:
                out.append((o, False))
        return out


def expand(start: np.ndarray, count: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Pairs (k, start[k] + m) for m < count[k], in chunks of about CHUNK pairs."""
    end = np.cumsum(count)
    k0 = 0
    while k0 < len(count):
        before = int(end[k0 - 1]) if k0 else 0
        k1 = max(int(np.searchsorted(end, before + CHUNK, side="right")), k0 + 1)
        c = count[k0:k1]
        total = int(end[k1 - 1]) - before
        shift = np.repeat(start[k0:k1] - (end[k0:k1] - c - before), c)
        yield np.repeat(np.arange(k0, k1), c), shift + np.arange(total)
        k0 = k1


class Found(NamedTuple):
    """Offending pairs: their number, the first ones (at most KEEP, (i, j) sorted) and whether
    the number is exact."""

    total: int
    pairs: np.ndarray
    complete: bool


class _Sink:
    def __init__(self, particles: int) -> None:
        self.budget = BUDGET * particles + 1_000_000
        self.count = 0
        self.examined = 0
        self.kept = np.zeros((0, 2), dtype=np.int64)

    def add(self, i: np.ndarray, j: np.ndarray, examined: int) -> None:
        self.examined += examined
        self.count += len(i)
        if len(i):
            self.kept = np.concatenate([self.kept, np.stack([i, j], axis=1)])
            if len(self.kept) > 2 * KEEP:
                self.kept = _sorted(self.kept)[:KEEP]

    @property
    def exhausted(self) -> bool:
        return self.examined > self.budget and self.count > 0

    def found(self) -> Found:
        return Found(self.count, _sorted(self.kept)[:KEEP], not self.exhausted)


def _sorted(pairs: np.ndarray) -> np.ndarray:
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def _search(
    q: np.ndarray,
    g: np.ndarray,
    pos: np.ndarray,
    rad: np.ndarray,
    space: Space,
    tolerance: float,
    sink: _Sink,
    within: bool,
) -> None:
    """Offending pairs between the points ``q`` and ``g`` (indices into pos/rad) into ``sink``:
    as (q index, g index); ``within`` (one set of particles), as (smaller, larger) index, and
    when ``q`` is ``g`` each pair once."""
    if sink.exhausted:
        return
    same = q is g
    swap = not same and len(q) > len(g)  # look up from the smaller set: fewer lookups
    if swap:
        q, g = g, q
    both = q if same else np.concatenate([q, g])
    size = float(rad[q].max() + rad[g].max())  # the largest contact distance
    lo, hi = pos[both].min(axis=0), pos[both].max(axis=0)
    grid = Grid(pos[g], size, space, lo, hi)
    # both sets in the grid's order: the gathers below stay in cache
    g = g[grid.order]
    gpos, grad = pos[g], rad[g]
    q = g if same else q
    qpos, qrad = (gpos, grad) if same else (pos[q], rad[q])
    at = grid.neighbours(grid.cells(qpos))
    gcol, qcol = space.columns(gpos), space.columns(qpos)
    uniform = grad.min() == grad.max() == qrad.min() == qrad.max()
    reach = (2.0 - tolerance) * float(grad[0])  # the limit when every radius is the same
    for offset, once in grid.stencil(half=same):
        for a, b in expand(*at(offset)):
            if once:
                keep = a < b
                a, b = a[keep], b[keep]
            d2 = space.distance2(gcol, b, qcol, a)
            if uniform:
                bad = d2 < reach * reach
            else:
                ra, rb = qrad[a], grad[b]
                r = ra + rb - tolerance * np.minimum(ra, rb)
                bad = d2 < r * r
            a, b = q[a[bad]], g[b[bad]]
            if swap:
                a, b = b, a
            if within:
                a, b = np.minimum(a, b), np.maximum(a, b)
            sink.add(a, b, len(bad))
            if sink.exhausted:
                return


def _present(classes: np.ndarray) -> np.ndarray:
    """The classes present, in increasing order (a count per class: no sort)."""
    return np.flatnonzero(np.bincount(classes)) if len(classes) else classes


def _classes(radius: np.ndarray, largest: float) -> np.ndarray:
    """Radius classes: k where radius is in (largest / 2^(k+1), largest / 2^k]."""
    return np.clip(np.floor(np.log2(largest / radius)), 0, 62).astype(np.int64)


def _quiet() -> np.errstate:
    """Extreme inputs (coordinates near the float64 limit, subnormal radii) overflow to infinite
    distances and limits, which compare the safe way; the set-up checks report them otherwise."""
    return np.errstate(over="ignore", invalid="ignore", divide="ignore")


@_quiet()
def overlapping_pairs(
    position: np.ndarray,
    radius: np.ndarray,
    space: Space,
    tolerance: float,
    other: tuple[np.ndarray, np.ndarray] | None = None,
) -> Found:
    """Pairs that overlap by more than ``tolerance`` x the smaller radius (identical centres
    included): among the particles (i < j) when ``other`` is None, else between particle i and
    particle j of ``other`` (positions, radii)."""
    n = len(radius)
    sink = _Sink(n + (0 if other is None else len(other[1])))
    if n == 0 or (other is not None and len(other[1]) == 0):
        return sink.found()
    if other is None:
        pos, rad, split = space.wrap(position), radius, n
    else:
        near = _near(space.wrap(position), radius, space.wrap(other[0]), other[1], space)
        if len(near) == 0:
            return sink.found()
        pos = np.concatenate([space.wrap(position), space.wrap(other[0][near])])
        rad = np.concatenate([radius, other[1][near]])
        split = n
    cls = _classes(rad, float(rad.max()))
    mine, theirs = cls[:split], cls[split:]
    index = np.arange(len(rad))
    for c in _present(mine):
        a = index[:split][mine == c]
        if other is None:
            _search(a, a, pos, rad, space, tolerance, sink, True)
            for d in _present(mine[mine > c]):  # the smaller classes look up this one
                b = index[:split][mine == d]
                _search(b, a, pos, rad, space, tolerance, sink, True)
        else:
            for d in _present(theirs):
                b = split + np.flatnonzero(theirs == d)
                _search(a, b, pos, rad, space, tolerance, sink, False)
        if sink.exhausted:
            break
    found = sink.found()
    pairs = found.pairs.copy()
    if other is not None and len(pairs):
        pairs[:, 1] = near[pairs[:, 1] - split]
    return Found(found.total, pairs, found.complete)  # ``near`` is increasing: still sorted


def _near(
    position: np.ndarray,
    radius: np.ndarray,
    other: np.ndarray,
    other_radius: np.ndarray,
    space: Space,
) -> np.ndarray:
    """Indices of ``other`` within contact reach of the box around ``position`` (wrapped)."""
    reach = float(radius.max() + other_radius.max())
    keep = np.ones(len(other), bool)
    for a in range(space.axes):
        start = position[:, a].min() - reach
        span = position[:, a].max() + reach - start
        if space.periodic[a]:
            if span < space.length[a]:
                keep &= np.mod(other[:, a] - start, space.length[a]) <= span
        else:
            keep &= (other[:, a] >= start) & (other[:, a] <= start + span)
    return np.flatnonzero(keep)


@_quiet()
def mesh_overlaps(
    vertices: np.ndarray, triangles: np.ndarray, position: np.ndarray, reach: np.ndarray
) -> np.ndarray:
    """Indices of the points nearer than their ``reach`` to a triangle of the mesh.

    The points near the mesh are binned in about one cell per point; each triangle visits the
    cells its box (grown by the largest reach) covers, and the exact distance (closest point on
    the triangle) is computed only for the points inside that box."""
    if len(position) == 0:
        return np.zeros(0, dtype=np.int64)
    corners = vertices[triangles]
    big = float(reach.max())
    tlo, thi = corners.min(axis=1) - big, corners.max(axis=1) + big
    near = np.flatnonzero(np.all((position >= tlo.min(0)) & (position <= thi.max(0)), axis=1))
    if len(near) == 0:
        return np.zeros(0, dtype=np.int64)
    p, r = position[near], reach[near]
    lo, hi = p.min(axis=0), p.max(axis=0)
    touched = np.flatnonzero(np.all((thi >= lo) & (tlo <= hi), axis=1))
    extent = np.maximum(hi - lo, big)
    size = max(big, float(np.prod(extent) / len(p)) ** (1 / 3))
    grid = Grid(p, size, Space(lo, hi - lo, np.zeros(3, bool)), lo, hi)
    first, last = grid.cells(tlo[touched]), grid.cells(thi[touched])
    span = last - first + 1
    bad = np.zeros(len(p), bool)
    a, ab, ac = corners[:, 0], corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    normal = np.cross(ab, ac)
    norm = np.linalg.norm(normal, axis=1, keepdims=True)
    unit = np.divide(normal, norm, out=np.zeros_like(normal), where=norm > 0)  # 0: no area
    for k, m in expand(np.zeros(len(touched), dtype=np.int64), np.prod(span, axis=1)):
        # the m-th cell of triangle k's block of cells
        ey, ez = span[k, 1], span[k, 2]
        cell = first[k] + np.stack([m // (ey * ez), (m // ez) % ey, m % ez], axis=1)
        for j, s in expand(*grid.lookup(grid.key(cell))):
            t, i = touched[k[j]], grid.order[s]
            # cheap filters first: near the triangle's plane, inside its grown box
            keep = np.abs(_dot(p[i] - a[t], unit[t])) < r[i]
            t, i = t[keep], i[keep]
            keep = np.all((p[i] >= tlo[t]) & (p[i] <= thi[t]), axis=1)
            t, i = t[keep], i[keep]
            close = _distance2(p[i], a[t], ab[t], ac[t]) < r[i] * r[i]
            bad[i[close]] = True
    return near[np.flatnonzero(bad)]


def _dot(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    dots: np.ndarray = np.einsum("ij,ij->i", u, v)
    return dots


def _distance2(p: np.ndarray, a: np.ndarray, ab: np.ndarray, ac: np.ndarray) -> np.ndarray:
    """Squared distance from the points p to the triangles (a, a + ab, a + ac), by the regions
    of the closest point (vertex, edge or face; Ericson, Real-Time Collision Detection 5.1.5)."""
    ap, bp, cp = p - a, p - a - ab, p - a - ac
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        on_ab = d1 / (d1 - d3)
        on_ac = d2 / (d2 - d6)
        on_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        v, w = vb / (va + vb + vc), vc / (va + vb + vc)
    regions = [
        (d1 <= 0) & (d2 <= 0),  # vertex a
        (d3 >= 0) & (d4 <= d3),  # vertex b
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),  # edge ab
        (d6 >= 0) & (d5 <= d6),  # vertex c
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),  # edge ac
        (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0),  # edge bc
    ]
    s = np.select(regions, [0.0, 1.0, on_ab, 0.0, 0.0, 1.0 - on_bc], v)
    u = np.select(regions, [0.0, 0.0, 0.0, 1.0, on_ac, on_bc], w)
    d = ap - s[:, None] * ab - u[:, None] * ac
    out = _dot(d, d)
    flat = ~np.isfinite(out)  # a degenerate triangle (no area): its three edges
    if np.any(flat):
        pf, af, bf, cf = p[flat], a[flat], a[flat] + ab[flat], a[flat] + ac[flat]
        out[flat] = np.min([_segment2(pf, x, y) for x, y in ((af, bf), (af, cf), (bf, cf))], 0)
    return out


def _segment2(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distance from the points p to the segments [a, b]."""
    ab = b - a
    t = np.clip(_dot(p - a, ab) / np.maximum(_dot(ab, ab), np.finfo(float).tiny), 0.0, 1.0)
    d = p - a - t[:, None] * ab
    return _dot(d, d)
