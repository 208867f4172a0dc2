"""Measurements on the platen records of a uniaxial EEPA test (see eepa_uniaxial).

Strains are engineering strains of the platen travel. The confined loading strain is counted
from the seating height, where the axial stress first reaches a small seating stress (as a
laboratory test counts from a seating load): before it the platen only meets the few highest
particles of a rough top surface (a poured sample) or closes the small gap a compacted sample
opens as cohesion and gravity set in; both are properties of the boundary layer, not of the
bulk, and grow with d/D. The strain from the start of the loading is measured too. The unconfined
stress is corrected for the growing cross-section, sigma = F (1 - eps) / A0 (ASTM D2166); the
unconfined strength is the maximum up to the strain cap (ASTM D2166 takes the stress at 15 %
strain when there is no peak) of its running mean over STRENGTH_WINDOW.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

SEATING_FRACTION = 0.02  # seating stress / sigma_pre
LOADING_BIN = 0.002  # strain bin of the loading curve
UNCONFINED_BIN = 0.005  # strain bin over which the unconfined stress is averaged
# Window (strain) of the running mean whose maximum is the strength: the platen force of a
# plastically flowing sample fluctuates by particle-scale rearrangements whose amplitude grows
# with d/D, so the maximum of 0.005 bins is biased upwards the more, the coarser the particles.
STRENGTH_WINDOW = 0.02
UNLOADING_FRACTION = 0.25  # secant over the first 25 % of the stress drop (CASES.md E3)


@dataclass(frozen=True)
class Metrics:
    """Bulk results of one run (SI units)."""

    seating_height: float  # m
    loading_strain: list[float]  # bin centres
    loading_stress: list[float]  # Pa, bin means
    start_strain: list[float]  # loading strain from the height where the loading started
    start_stress: list[float]  # Pa, bin means on start_strain
    pre_strain: float  # strain at sigma_pre
    unloading_stiffness: float  # Pa, secant
    unconfined_strain: list[float]
    unconfined_stress: list[float]  # Pa, area-corrected bin means
    strength: float  # Pa, sigma_c: maximum of the STRENGTH_WINDOW running mean
    strength_strain: float  # strain at sigma_c (centre of the window)
    strength_bin: float  # Pa, maximum of the UNCONFINED_BIN means (first version of the study)
    peaked: bool  # the windowed stress fell clearly after sigma_c (else: a plateau, ASTM cap)


def binned(x: np.ndarray, y: np.ndarray, width: float) -> tuple[np.ndarray, np.ndarray]:
    """Means of y over consecutive bins of x of the given width, starting at x = 0 (empty bins
    dropped); returns bin centres and means."""
    k = np.floor(np.asarray(x) / width).astype(int)
    keep = k >= 0
    k, y = k[keep], np.asarray(y)[keep]
    if k.size == 0:
        return np.zeros(0), np.zeros(0)
    sums = np.bincount(k, weights=y)
    counts = np.bincount(k)
    full = counts > 0
    centres = (np.arange(len(counts)) + 0.5) * width
    return centres[full], sums[full] / counts[full]


def seating_index(stress: Sequence[float], seat: float, window: int = 5) -> int:
    """First record from which the running mean over ``window`` records reaches ``seat``."""
    s = np.asarray(stress, dtype=float)
    if len(s) < window:
        raise ValueError(f"seating_index needs at least {window} records, got {len(s)}")
    mean = np.convolve(s, np.ones(window) / window, mode="valid")
    above = np.nonzero(mean >= seat)[0]
    if above.size == 0:
        raise ValueError(f"seating_index: the stress never reached the seating stress {seat} Pa")
    return int(above[0])


def secant_unloading(height: Sequence[float], stress: Sequence[float], h_ref: float) -> float:
    """Secant stiffness (Pa) over the first UNLOADING_FRACTION of the stress drop of an
    unloading record that starts at its peak; strain measured against ``h_ref``."""
    z, s = np.asarray(height), np.asarray(stress)
    target = (1 - UNLOADING_FRACTION) * s[0]
    below = np.nonzero(s <= target)[0]
    if below.size == 0:
        raise ValueError("secant_unloading: the stress never fell by the required fraction")
    k = int(below[0])
    # linear interpolation of the platen height at the target stress
    w = (s[k - 1] - target) / (s[k - 1] - s[k]) if k > 0 else 1.0
    z_t = z[k - 1] + w * (z[k] - z[k - 1]) if k > 0 else z[k]
    return float((s[0] - target) / ((z_t - z[0]) / h_ref))


def measure(
    loading: tuple[Sequence[float], Sequence[float]],
    unloading: tuple[Sequence[float], Sequence[float]],
    unconfined: tuple[Sequence[float], Sequence[float]],
    unconfined_start: float,
    pre_stress: float,
) -> Metrics:
    """Metrics from the (height, stress) records of the three stages."""
    hl, sl = np.asarray(loading[0]), np.asarray(loading[1])
    k = seating_index(sl, SEATING_FRACTION * pre_stress)
    h_seat = float(hl[k])
    eps = (h_seat - hl[k:]) / h_seat
    e_bins, s_bins = binned(eps, sl[k:], LOADING_BIN)
    e0_bins, s0_bins = binned((hl[0] - hl) / hl[0], sl, LOADING_BIN)
    # running mean over 5 records (0.01 % strain) against the platen-force noise
    smooth = np.ones(5) / 5
    stiffness = secant_unloading(
        np.convolve(unloading[0], smooth, mode="valid"),
        np.convolve(unloading[1], smooth, mode="valid"),
        h_seat,
    )
    hu, su = np.asarray(unconfined[0]), np.asarray(unconfined[1])
    eps_u = (unconfined_start - hu) / unconfined_start
    u_bins, c_bins = binned(eps_u, su * (1 - eps_u), UNCONFINED_BIN)
    j = int(np.argmax(c_bins))
    w = max(1, round(STRENGTH_WINDOW / UNCONFINED_BIN))
    window = np.convolve(c_bins, np.ones(w) / w, mode="valid") if len(c_bins) >= w else c_bins
    jw = int(np.argmax(window))
    peaked = bool(np.any(window[jw:] < 0.8 * window[jw]))
    return Metrics(
        seating_height=h_seat,
        loading_strain=e_bins.tolist(),
        loading_stress=s_bins.tolist(),
        start_strain=e0_bins.tolist(),
        start_stress=s0_bins.tolist(),
        pre_strain=float(eps[-1]),
        unloading_stiffness=stiffness,
        unconfined_strain=u_bins.tolist(),
        unconfined_stress=c_bins.tolist(),
        strength=float(window[jw]),
        strength_strain=float(np.mean(u_bins[jw : jw + w])),
        strength_bin=float(c_bins[j]),
        peaked=peaked,
    )


def l1_relative(
    x_ref: Sequence[float], y_ref: Sequence[float], x: Sequence[float], y: Sequence[float]
) -> float:
    """CASES.md section 0 curve metric sum|y(x_ref) - y_ref| / sum|y_ref|, over the reference
    abscissae inside the range of x (the other curve is interpolated, not the reference)."""
    xr, yr = np.asarray(x_ref), np.asarray(y_ref)
    inside = (xr >= np.min(x)) & (xr <= np.max(x))
    if not np.any(inside):
        raise ValueError("l1_relative: the curves share no abscissae")
    yi = np.interp(xr[inside], x, y)
    return float(np.sum(np.abs(yi - yr[inside])) / np.sum(np.abs(yr[inside])))


def relative_difference(value: float, reference: float) -> float:
    """(value - reference) / reference."""
    return (value - reference) / reference


def inertial_number(strain_rate: float, diameter: float, density: float, stress: float) -> float:
    """I = eps_dot d sqrt(rho / p) (GDR MiDi 2004, Eur. Phys. J. E 14:341); quasi-static for
    I below about 1e-3."""
    return strain_rate * diameter * math.sqrt(density / stress)


def strain_at_stress(
    strain: Sequence[float], stress: Sequence[float], levels: Sequence[float]
) -> np.ndarray:
    """Strain at which a loading curve first reaches each stress level (the curve's running
    maximum, interpolated), so that curves of several seeds can be averaged at equal stress."""
    s = np.maximum.accumulate(np.asarray(stress, dtype=float))
    e = np.asarray(strain, dtype=float)
    # on a flat stretch of the running maximum keep its first strain
    keep = np.concatenate(([True], np.diff(s) > 0))
    return np.interp(levels, s[keep], e[keep])
