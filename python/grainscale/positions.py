"""Set-up helpers that only return particle positions (m), for ``Simulation.add_particles``:
:func:`lattice` (a simple cubic lattice in a box) and :func:`random_in_box` (random
non-overlapping centres). Also available as ``grainscale.insert.lattice`` and
``grainscale.insert.random_in_box``."""

from __future__ import annotations

import math

import numpy as np

from ._validate import is_real, positive, real_array
from .geometry import Box

_MAX_SITES = 1e8  # lattice sites: 2.4 GB of positions
_MAX_RANDOM = 10**7  # random_in_box places one sphere at a time in Python (minutes at this size)

__all__ = ["lattice", "random_in_box"]


def lattice(
    region: Box,
    spacing: float,
    count: int | None = None,
    jitter: float = 0.0,
    seed: int = 0,
    plane_z: float | None = None,
) -> np.ndarray:
    """Simple-cubic lattice sites inside ``region``, filled bottom-up (z, then y, then x).

    Args:
        region: box to fill; the first site is half a spacing inside each lower face.
        spacing: lattice spacing (m).
        count: number of sites (None: all that fit).
        jitter: uniform random displacement in [-jitter, jitter] added to x and y (m).
        seed: random seed for the jitter.
        plane_z: 2-D mode (``sim.plane_z``): a square lattice in the region's x-y rectangle,
            filled by rows (y, then x), with every z equal to ``plane_z``.

    Returns:
        (count, 3) positions.
    """
    spacing = positive("lattice", "spacing", spacing, " (m)")
    if not (is_real(jitter) and 0 <= jitter < 0.5 * spacing):
        raise ValueError(f"lattice.jitter must be in [0, spacing/2), got {jitter!r}")
    if count is not None and (isinstance(count, bool) or not isinstance(count, int | np.integer)):
        raise ValueError(f"lattice.count must be an integer or None, got {count!r}")
    with np.errstate(over="ignore"):
        sites = np.floor(np.asarray(region.length) / spacing + 1e-9)
        total = float(np.prod(sites))
    if total > _MAX_SITES:  # also keeps the int cast below exact
        raise ValueError(
            f"lattice.spacing must leave at most {_MAX_SITES:.0e} sites in the region, got "
            f"{spacing!r} m ({total:.3g} sites)"
        )
    n = sites.astype(int)
    if plane_z is not None:
        _check_plane("lattice", region, plane_z)
        n[2] = 1
    capacity = int(np.prod(n))
    if count is None:
        count = capacity
    if count < 0 or count > capacity:
        raise ValueError(
            f"lattice.count must be in [0, {capacity}] for this region and spacing, got {count}"
        )
    k = np.arange(count)
    ix = k % n[0]
    iy = (k // n[0]) % n[1]
    iz = k // (n[0] * n[1])
    pos = np.asarray(region.lo) + spacing * (np.stack([ix, iy, iz], axis=1) + 0.5)
    if jitter > 0:
        rng = np.random.default_rng(seed)
        pos[:, :2] += rng.uniform(-jitter, jitter, size=(count, 2))
    if plane_z is not None:
        pos[:, 2] = plane_z
    return pos


def _check_plane(owner: str, region: Box, plane_z: float) -> None:
    if not region.lo[2] <= plane_z <= region.hi[2]:
        raise ValueError(
            f"{owner}.plane_z must lie in the region's z range [{region.lo[2]}, "
            f"{region.hi[2]}], got {plane_z!r}"
        )


def _overlaps(
    grid: dict[tuple[int, int, int], list[int]],
    pos: np.ndarray,
    radii: np.ndarray,
    c: tuple[int, int, int],
    p: np.ndarray,
    r: float,
) -> bool:
    """Whether a sphere of radius r at p overlaps a placed one (grid: placed indices by cell)."""
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                for j in grid.get((c[0] + dx, c[1] + dy, c[2] + dz), ()):
                    if np.sum((pos[j] - p) ** 2) < (r + radii[j]) ** 2:
                        return True
    return False


def _too_full(region: Box, radii: np.ndarray, i: int, attempts: int, planar: bool) -> str:
    fraction = (
        np.sum(math.pi * radii**2) / (region.length[0] * region.length[1])
        if planar
        else np.sum(4 / 3 * math.pi * radii**3) / region.volume
    )
    return (
        f"random_in_box could not place particle {i} (radius {radii[i]}) after {attempts} "
        f"attempts; region too full (requested {'area' if planar else 'volume'} fraction "
        f"{fraction:.3f})"
    )


def random_in_box(
    region: Box,
    radius: float | np.ndarray,
    count: int | None = None,
    seed: int = 0,
    max_attempts: int = 200,
    plane_z: float | None = None,
) -> np.ndarray:
    """Random non-overlapping sphere centres inside ``region`` (spheres fully inside).

    Args:
        region: box to fill.
        radius: one radius, or an array of radii (one per particle, count taken from it).
        count: number of particles when ``radius`` is a scalar.
        seed: random seed.
        max_attempts: trials per particle before giving up.
        plane_z: 2-D mode (``sim.plane_z``): discs inside the region's x-y rectangle, centres
            at z = ``plane_z``.

    Returns:
        (N, 3) positions, in the order of ``radius``.

    Raises:
        RuntimeError: if a particle cannot be placed (the region is too full); nothing is
            silently dropped.
    """
    if np.ndim(radius) == 0:
        radii = np.atleast_1d(positive("random_in_box", "radius", radius, " (m)"))  # type: ignore[arg-type]
    else:
        radii = real_array("random_in_box", "radius", radius, (None,))
    if count is not None and radii.size == 1:
        if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 0:
            raise ValueError(f"random_in_box.count must be a non-negative integer, got {count!r}")
        if count > _MAX_RANDOM:
            raise ValueError(
                f"random_in_box.count must be at most {_MAX_RANDOM:.0e} (placement in Python; "
                f"insert.Pack places more), got {count}"
            )
        radii = np.full(int(count), float(radii[0]))
    if radii.size > _MAX_RANDOM:
        raise ValueError(
            f"random_in_box.radius must hold at most {_MAX_RANDOM:.0e} radii, got {radii.size}"
        )
    if np.any(~(radii > 0)):
        raise ValueError("random_in_box.radius must be positive (m)")
    rng = np.random.default_rng(seed)
    lo = np.asarray(region.lo, dtype=float)
    hi = np.asarray(region.hi, dtype=float)
    axes = 3
    if plane_z is not None:
        _check_plane("random_in_box", region, plane_z)
        axes = 2
    # Cells of at least the largest diameter (the neighbour search looks one cell around);
    # at least a millionth of the region so that tiny radii keep cell indices in range.
    cell = max(2.0 * float(radii.max()), 1e-6 * float(np.max(hi - lo)))
    grid: dict[tuple[int, int, int], list[int]] = {}
    pos = np.empty((radii.size, 3))
    for i in np.argsort(-radii, kind="stable"):
        r = radii[i]
        if np.any(0.5 * (hi - lo)[:axes] <= r):
            raise ValueError(f"random_in_box: region too small for radius {r}")
        for _ in range(max_attempts):
            p = rng.uniform(lo + r, hi - r)
            if plane_z is not None:
                p[2] = plane_z
            c = tuple(np.floor(p / cell).astype(int))
            if not _overlaps(grid, pos, radii, c, p, r):
                pos[i] = p
                grid.setdefault(c, []).append(int(i))
                break
        else:
            raise RuntimeError(_too_full(region, radii, i, max_attempts, plane_z is not None))
    return pos
