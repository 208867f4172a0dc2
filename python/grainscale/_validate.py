"""Small validators shared by the parameter classes.

Every message has the shape ``Owner.parameter must be <constraint>, got <value>``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def positive(owner: str, name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float if it is positive and finite, else raise ValueError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a positive number{unit}, got {value!r}") from None
    if not (v > 0 and math.isfinite(v)):
        raise ValueError(f"{owner}.{name} must be positive and finite{unit}, got {value!r}")
    return v


def in_range(
    owner: str, name: str, value: float, lo: float, hi: float, closed_hi: bool = True
) -> float:
    """Return ``value`` as float if it lies in [lo, hi] (or [lo, hi)), else raise ValueError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a number, got {value!r}") from None
    ok = lo <= v <= hi if closed_hi else lo <= v < hi
    if not ok or math.isnan(v):
        bracket = "]" if closed_hi else ")"
        raise ValueError(f"{owner}.{name} must be in [{lo:g}, {hi:g}{bracket}, got {value!r}")
    return v


def non_negative(owner: str, name: str, value: float) -> float:
    """Return ``value`` as float if it is >= 0 and finite, else raise ValueError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a number, got {value!r}") from None
    if not (v >= 0 and math.isfinite(v)):
        raise ValueError(f"{owner}.{name} must be non-negative and finite, got {value!r}")
    return v


def vector3(owner: str, name: str, value: Sequence[float]) -> tuple[float, float, float]:
    """Return a finite 3-vector as a tuple of floats, else raise ValueError."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{owner}.{name} must be a 3-vector of numbers, got {value!r}") from None
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ValueError(f"{owner}.{name} must be a finite 3-vector, got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))
