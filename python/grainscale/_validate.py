"""Small validators shared by the parameter classes.

Every message has the shape ``Owner.parameter must be <constraint>, got <value>``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number: int, float or a numpy integer/float scalar; not a
    bool, a string, a complex number or an array (no silent coercion)."""
    if isinstance(value, bool | np.bool_):
        return False
    if isinstance(value, int | float | np.integer | np.floating):
        return True
    return isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"


def real(owner: str, name: str, value: object, what: str = "a number") -> float:
    """``value`` as a float if it is a real number (see is_real), else ValueError."""
    if not is_real(value):
        raise ValueError(f"{owner}.{name} must be {what}, got {value!r}")
    return float(value)  # type: ignore[arg-type]


def flag(owner: str, name: str, value: object) -> bool:
    """``value`` as a bool if it is one (a Python or numpy bool), else ValueError: a string such
    as ``'no'`` or a number is not taken for its truth value."""
    if not isinstance(value, bool | np.bool_):
        raise ValueError(f"{owner}.{name} must be True or False, got {value!r}")
    return bool(value)


def finite(owner: str, name: str, value: object, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number (see is_real), else ValueError."""
    v = real(owner, name, value, f"a finite number{unit}")
    if not math.isfinite(v):
        raise ValueError(f"{owner}.{name} must be finite{unit}, got {value!r}")
    return v


def at_least(owner: str, name: str, value: object, lo: float, what: str = "") -> float:
    """``value`` as a float if it is a finite real number >= ``lo``, else ValueError."""
    v = real(owner, name, value, f"a number >= {lo:g}{what}")
    if not (v >= lo and math.isfinite(v)):
        raise ValueError(f"{owner}.{name} must be >= {lo:g}{what} and finite, got {value!r}")
    return v


def whole(owner: str, name: str, value: object, lo: int = 0) -> int:
    """``value`` as an int if it is a whole number >= ``lo`` (an int, a numpy integer or a float
    with an integral value, e.g. 1e4); bools, strings and fractions are refused."""
    what = {0: "a non-negative integer", 1: "a positive integer"}.get(lo, f"an integer >= {lo}")
    if not is_real(value):
        raise ValueError(f"{owner}.{name} must be {what}, got {value!r}")
    v = value if isinstance(value, int | np.integer) else float(value)  # type: ignore[arg-type]
    if isinstance(v, float) and not (math.isfinite(v) and v == int(v)):
        raise ValueError(f"{owner}.{name} must be {what}, got {value!r}")
    if int(v) < lo:
        raise ValueError(f"{owner}.{name} must be {what}, got {value!r}")
    return int(v)


def _holds_bool(value: object) -> bool:
    if isinstance(value, bool | np.bool_):
        return True
    return isinstance(value, list | tuple) and any(_holds_bool(v) for v in value)


def real_array(owner: str, name: str, value: object, *shapes: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a C-contiguous float64 array of one of ``shapes`` (None: any length),
    refusing strings, bools, complex numbers, objects, ragged or other shapes and non-finite
    values."""
    try:
        a = np.asarray(value)
    except Exception:
        a = np.asarray(None)
    if a.dtype.kind not in "iuf" or _holds_bool(value):
        kind = "bool" if _holds_bool(value) else a.dtype
        raise ValueError(
            f"{owner}.{name} must be an array of real numbers, got dtype {kind} ({str(value)[:60]})"
        )

    def fits(shape: tuple[int | None, ...]) -> bool:
        return a.ndim == len(shape) and all(
            n is None or n == m for n, m in zip(shape, a.shape, strict=True)
        )

    if not any(fits(shape) for shape in shapes):
        want = " or ".join(
            "("
            + ", ".join("N" if n is None else str(n) for n in sh)
            + ("," if len(sh) == 1 else "")
            + ")"
            for sh in shapes
        )
        raise ValueError(f"{owner}.{name} must have shape {want}, got {a.shape}")
    a = np.ascontiguousarray(a, dtype=float)
    if not np.all(np.isfinite(a)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise ValueError(f"{owner}.{name} must be finite, got {float(a[bad])} at index {bad}")
    return a


def id_array(owner: str, name: str, value: object) -> np.ndarray:
    """``value`` (a sequence or array of particle ids, any shape) as a flat int64 array,
    refusing floats, bools, strings and ids outside int64."""
    try:
        a = np.asarray(value)
    except Exception:
        a = np.asarray(None)
    if a.size == 0 and a.dtype.kind == "f":  # [] and np.array([])
        return np.zeros(0, dtype=np.int64)
    if a.dtype.kind not in "iu" or _holds_bool(value):
        raise ValueError(
            f"{owner}.{name} must be integer particle ids, got dtype {a.dtype} ({str(value)[:60]})"
        )
    if a.dtype.kind == "u" and a.size and a.max() > np.iinfo(np.int64).max:
        raise ValueError(f"{owner}.{name} must be ids below 2**63, got {a.max()}")
    return a.astype(np.int64).reshape(-1)


def positive(owner: str, name: str, value: float, unit: str = "") -> float:
    """Return ``value`` as float if it is positive and finite, else raise ValueError."""
    v = real(owner, name, value, f"a positive number{unit}")
    if not (v > 0 and math.isfinite(v)):
        raise ValueError(f"{owner}.{name} must be positive and finite{unit}, got {value!r}")
    return v


def in_range(
    owner: str, name: str, value: float, lo: float, hi: float, closed_hi: bool = True
) -> float:
    """Return ``value`` as float if it lies in [lo, hi] (or [lo, hi)), else raise ValueError."""
    v = real(owner, name, value)
    ok = lo <= v <= hi if closed_hi else lo <= v < hi
    if not ok or math.isnan(v):
        bracket = "]" if closed_hi else ")"
        raise ValueError(f"{owner}.{name} must be in [{lo:g}, {hi:g}{bracket}, got {value!r}")
    return v


def non_negative(owner: str, name: str, value: float) -> float:
    """Return ``value`` as float if it is >= 0 and finite, else raise ValueError."""
    v = real(owner, name, value)
    if not (v >= 0 and math.isfinite(v)):
        raise ValueError(f"{owner}.{name} must be non-negative and finite, got {value!r}")
    return v


def direction(owner: str, name: str, value: Sequence[float]) -> tuple[float, float, float]:
    """A finite, non-zero 3-vector (a normal, an axis). One so long or short that its squared
    length would overflow or underflow is brought to a largest component in [0.5, 1) by a
    power of two: exact, so the unit vector the core derives keeps its bits."""
    v = np.asarray(vector3(owner, name, value))
    largest = float(np.max(np.abs(v)))
    if largest == 0:
        raise ValueError(f"{owner}.{name} must be a non-zero vector, got {value}")
    if not 2.0**-500 < largest < 2.0**500:
        v = np.ldexp(v, -math.frexp(largest)[1])
    return (float(v[0]), float(v[1]), float(v[2]))


def vector3(owner: str, name: str, value: object) -> tuple[float, float, float]:
    """Return a finite 3-vector of real numbers as a tuple of floats, else raise ValueError."""
    try:
        a = np.asarray(value)
    except Exception:
        a = np.asarray(None)
    bad = a.dtype.kind not in "iuf" or a.shape != (3,) or _holds_bool(value)
    if bad or not np.all(np.isfinite(a)):
        raise ValueError(f"{owner}.{name} must be a finite 3-vector of numbers, got {value!r}")
    return (float(a[0]), float(a[1]), float(a[2]))


def span(lo: Sequence[float] | np.ndarray, hi: Sequence[float] | np.ndarray) -> str:
    """A box's bounds for a message: ``[(x, y, z), (x, y, z)] m``."""

    def point(p: Sequence[float] | np.ndarray) -> str:
        return "(" + ", ".join(f"{float(x):.6g}" for x in p) + ")"

    return f"[{point(lo)}, {point(hi)}] m"
