"""Silo discharge study (CASES D1): Beverloo's correlation and its fits.

    W = C rho_b sqrt(g) (D0 - k d)^n    (Beverloo, Leniger & van de Velde 1961)

``fit_beverloo`` fits C, k and optionally n in log W; ``exponent_interval`` gives the
profile-likelihood range of the free exponent, ``seed_scatter`` the scatter between seeds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

# ------------------------------------------------------------------------------------------
# Beverloo
# ------------------------------------------------------------------------------------------


G = 9.81  # m/s^2, standard gravity
#: Beverloo's reference constants (CASES.md D1)
BEVERLOO_C = 0.58
BEVERLOO_K = 1.5


def beverloo_rate(
    orifice: float | np.ndarray,
    diameter: float,
    bulk_density: float,
    c: float = BEVERLOO_C,
    k: float = BEVERLOO_K,
    exponent: float = 2.5,
) -> Any:
    """Beverloo's discharge rate C rho_b sqrt(g) (D0 - k d)^n (kg/s; 0 when D0 <= k d)."""
    gap = np.clip(np.asarray(orifice, dtype=float) - k * diameter, 0.0, None)
    return c * bulk_density * math.sqrt(G) * gap**exponent


@dataclass(frozen=True)
class BeverlooFit:
    """Fitted W = C rho_b sqrt(g) (D0 - k d)^exponent (least squares in log W)."""

    c: float
    k: float
    exponent: float
    free_exponent: bool
    free_k: bool
    rms_log_residual: float
    points: int
    at_bound: bool  # a fitted k or exponent lies on the edge of its search range

    def rate(self, orifice: Any, diameter: float, bulk_density: float) -> Any:
        return beverloo_rate(orifice, diameter, bulk_density, self.c, self.k, self.exponent)


def fit_beverloo(
    orifice: Sequence[float],
    rate: Sequence[float],
    diameter: float,
    bulk_density: float | Sequence[float],
    exponent: float | None = 2.5,
    k: float | None = None,
) -> BeverlooFit:
    """Fit W = C rho_b sqrt(g) (D0 - k d)^n to measured rates (least squares in log W).

    C is always fitted (in closed form); ``exponent`` None fits the exponent (search in [1, 4],
    step 1e-3 after a 1e-2 scan), ``k`` None fits k (search in [0, min D0/d), step 1e-3).
    ``bulk_density`` is one value or one per orifice (kg/m^3). Needs at least as many valid
    rates as free parameters (then the fit is exact).
    """
    d0 = np.asarray(orifice, dtype=float)
    w = np.asarray(rate, dtype=float)
    rho = np.broadcast_to(np.asarray(bulk_density, dtype=float), d0.shape)
    ok = np.isfinite(w) & (w > 0)
    d0, w, rho = d0[ok], w[ok], rho[ok]
    need = 1 + (exponent is None) + (k is None)
    if len(d0) < need:
        raise ValueError(f"fit_beverloo needs at least {need} valid rates, got {len(d0)}")
    k_max = d0.min() / diameter
    if k is not None and not 0 <= k < k_max:
        raise ValueError(f"fit_beverloo.k must be in [0, min D0/d = {k_max:g}), got {k!r}")
    ly = np.log(w / (rho * math.sqrt(G)))
    ks = np.arange(0.0, k_max - 1e-3, 1e-3) if k is None else np.array([float(k)])
    x = np.log(d0[None, :] - ks[:, None] * diameter)

    def best(n: float) -> tuple[float, float, float]:
        logc = np.mean(ly[None, :] - n * x, axis=1)
        ss = np.sum((ly[None, :] - n * x - logc[:, None]) ** 2, axis=1)
        i = int(np.argmin(ss))
        return float(ss[i]), float(ks[i]), float(math.exp(logc[i]))

    if exponent is not None:
        n = float(exponent)
    else:
        coarse = np.arange(1.0, 4.0 + 1e-9, 0.01)
        n0 = float(coarse[int(np.argmin([best(v)[0] for v in coarse]))])
        fine = np.arange(max(1.0, n0 - 0.01), min(4.0, n0 + 0.01) + 1e-9, 1e-3)
        n = float(fine[int(np.argmin([best(v)[0] for v in fine]))])
    ss, k_fit, c = best(n)
    at_bound = (k is None and k_fit in (ks[0], ks[-1])) or (
        exponent is None and (n <= 1.0 or n >= 4.0)
    )
    return BeverlooFit(
        c=c,
        k=k_fit,
        exponent=n,
        free_exponent=exponent is None,
        free_k=k is None,
        rms_log_residual=math.sqrt(ss / len(d0)),
        points=len(d0),
        at_bound=bool(at_bound),
    )


def exponent_interval(
    orifice: Sequence[float],
    rate: Sequence[float],
    diameter: float,
    bulk_density: float | Sequence[float],
    sigma_log: float,
) -> tuple[float, float]:
    """Exponents n in [1, 4] (step 0.01) whose best (C, k) fit is within one standard error of
    the free fit: sum of squared log residuals <= its minimum + sigma_log^2 (Delta chi^2 = 1
    for log residuals with standard deviation ``sigma_log``, the profile-likelihood interval).
    """
    if not (math.isfinite(sigma_log) and sigma_log > 0):
        raise ValueError(f"exponent_interval.sigma_log must be positive, got {sigma_log!r}")
    grid = np.arange(1.0, 4.0 + 1e-9, 0.01)
    ss = np.empty_like(grid)
    for i, n in enumerate(grid):
        fit = fit_beverloo(orifice, rate, diameter, bulk_density, exponent=float(n))
        ss[i] = fit.rms_log_residual**2 * fit.points
    inside = grid[ss <= ss.min() + sigma_log**2]
    return float(inside.min()), float(inside.max())


def fit_all(
    orifices: Sequence[float], rate: Sequence[float], rho: Sequence[float], diameter: float
) -> tuple[BeverlooFit | None, BeverlooFit | None, BeverlooFit | None]:
    """The three Beverloo fits of a study: (n = 2.5; C, k), (C, k, n), (k = 1.5; C, n); None
    where there are too few valid rates."""
    valid = [(a, w, b) for a, w, b in zip(orifices, rate, rho, strict=True) if math.isfinite(w)]
    if len(valid) < 2:
        return None, None, None
    d0, w, b = zip(*valid, strict=True)
    return (
        fit_beverloo(d0, w, diameter, b, exponent=2.5),
        fit_beverloo(d0, w, diameter, b, exponent=None) if len(valid) >= 3 else None,
        fit_beverloo(d0, w, diameter, b, exponent=None, k=BEVERLOO_K),
    )
