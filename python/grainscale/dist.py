"""Particle size distributions (of the radius, by number; SI units: m).

Declarative, validated, frozen parameter sets. Sampling happens in the C++ core from a seeded
``std::mt19937_64`` (one uniform number per radius, by inversion of the cumulative
distribution), so every insertion is reproducible, identical on every platform, and its random
state can be checkpointed::

    gs.dist.Monodisperse(1e-3)
    gs.dist.Uniform(min=0.9e-3, max=1.1e-3)
    gs.dist.Normal(mean=1e-3, std=0.1e-3, min=0.8e-3, max=1.2e-3)      # truncated
    gs.dist.LogNormal(median=1e-3, sigma=0.2, min=0.5e-3, max=2e-3)    # truncated
    gs.dist.Discrete(radii=(1e-3, 2e-3), weights=(0.5, 0.5), fractions="mass")

All distributions are *number* distributions of the radius: ``sample`` draws radii with the
given probability per particle. ``Discrete`` also accepts mass fractions and converts them
(number weight proportional to mass fraction / r^3). ``mean_radius`` and ``std_radius`` are the
exact moments of the (truncated) number distribution.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, cast

import numpy as np

from . import _core
from ._validate import non_negative, positive

__all__ = [
    "Discrete",
    "Distribution",
    "LogNormal",
    "Monodisperse",
    "Normal",
    "Uniform",
    "as_distribution",
]


def _phi(x: float) -> float:
    """Standard normal density."""
    return math.exp(-0.5 * x * x) / math.sqrt(2.0 * math.pi)


def _cdf(x: float) -> float:
    """Standard normal cumulative distribution."""
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def _bounds(owner: str, lo: float, hi: float) -> tuple[float, float]:
    lo = positive(owner, "min", lo, " (m)")
    hi = positive(owner, "max", hi, " (m)")
    if not hi >= lo:
        raise ValueError(f"{owner}.max must be >= {owner}.min = {lo!r} (m), got {hi!r}")
    return lo, hi


class _Base:
    """Shared behaviour: the C++ parameter struct, sampling and the support."""

    def _to_core(self) -> _core.SizeDistribution:
        raise NotImplementedError

    @property
    def min_radius(self) -> float:
        """Smallest radius that can be drawn (m)."""
        return float(self._to_core().min_radius)

    @property
    def max_radius(self) -> float:
        """Largest radius that can be drawn (m)."""
        return float(self._to_core().max_radius)

    def sample(self, n: int, seed: int = 0) -> np.ndarray:
        """``n`` radii (m) drawn by the core's seeded engine (the same ones insertion draws).

        Args:
            n: number of radii.
            seed: seed of the std::mt19937_64 engine (non-negative integer).
        """
        if int(n) != n or n < 0:
            raise ValueError(f"sample.n must be a non-negative integer, got {n!r}")
        return np.asarray(self._to_core().sample(int(n), _seed("sample", seed)))


def _seed(owner: str, seed: int) -> int:
    if isinstance(seed, bool) or int(seed) != seed or not 0 <= int(seed) < 2**64:
        raise ValueError(f"{owner}.seed must be an integer in [0, 2^64), got {seed!r}")
    return int(seed)


@dataclass(frozen=True)
class Monodisperse(_Base):
    """All particles of one radius.

    Args:
        radius: m.

    Example:
        >>> Monodisperse(1e-3).mean_radius
        0.001
    """

    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive("Monodisperse", "radius", self.radius, " (m)"))

    def _to_core(self) -> _core.SizeDistribution:
        return _core.SizeDistribution.monodisperse(self.radius)

    @property
    def mean_radius(self) -> float:
        """Mean radius by number (m)."""
        return self.radius

    @property
    def std_radius(self) -> float:
        """Standard deviation of the radius by number (m)."""
        return 0.0


@dataclass(frozen=True)
class Uniform(_Base):
    """Radius uniformly distributed in [min, max].

    Args:
        min: smallest radius (m), positive.
        max: largest radius (m), >= min.

    Example:
        >>> round(Uniform(1e-3, 3e-3).mean_radius, 6)
        0.002
    """

    min: float
    max: float

    def __post_init__(self) -> None:
        lo, hi = _bounds("Uniform", self.min, self.max)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)

    def _to_core(self) -> _core.SizeDistribution:
        return _core.SizeDistribution.uniform(self.min, self.max)

    @property
    def mean_radius(self) -> float:
        """Mean radius by number (m)."""
        return 0.5 * (self.min + self.max)

    @property
    def std_radius(self) -> float:
        """Standard deviation of the radius by number (m)."""
        return (self.max - self.min) / math.sqrt(12.0)


@dataclass(frozen=True)
class Normal(_Base):
    """Normal (Gaussian) radius distribution truncated to [min, max].

    Args:
        mean: mean of the untruncated normal (m), positive.
        std: its standard deviation (m), >= 0.
        min: lower truncation (m); default mean - 3 std, which must then be positive.
        max: upper truncation (m); default mean + 3 std.

    ``mean_radius`` / ``std_radius`` are the moments after truncation.
    """

    mean: float
    std: float
    min: float | None = None
    max: float | None = None

    def __post_init__(self) -> None:
        mean = positive("Normal", "mean", self.mean, " (m)")
        std = non_negative("Normal", "std", self.std)
        lo = mean - 3.0 * std if self.min is None else self.min
        hi = mean + 3.0 * std if self.max is None else self.max
        if self.min is None and not lo > 0:
            raise ValueError(
                f"Normal.min must be positive (m), got {lo!r} (the default mean - 3 std); "
                "give min explicitly"
            )
        lo, hi = _bounds("Normal", lo, hi)
        if std == 0 and not lo <= mean <= hi:
            raise ValueError(f"Normal.mean must be in [min, max] when std = 0, got {mean!r}")
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "std", std)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)
        self._to_core()  # the core checks that [min, max] holds probability

    def _range(self) -> tuple[float, float]:
        return cast(float, self.min), cast(float, self.max)  # resolved in __post_init__

    def _to_core(self) -> _core.SizeDistribution:
        return _core.SizeDistribution.normal(self.mean, self.std, *self._range())

    def _standard_bounds(self) -> tuple[float, float, float]:
        lo, hi = self._range()
        a = (lo - self.mean) / self.std
        b = (hi - self.mean) / self.std
        return a, b, _cdf(b) - _cdf(a)

    @property
    def mean_radius(self) -> float:
        """Mean radius by number after truncation (m)."""
        if self.std == 0:
            return self.mean
        a, b, z = self._standard_bounds()
        return self.mean + self.std * (_phi(a) - _phi(b)) / z

    @property
    def std_radius(self) -> float:
        """Standard deviation of the radius by number after truncation (m)."""
        if self.std == 0:
            return 0.0
        a, b, z = self._standard_bounds()
        shift = (_phi(a) - _phi(b)) / z
        var = 1.0 + (a * _phi(a) - b * _phi(b)) / z - shift * shift
        return self.std * math.sqrt(max(var, 0.0))


@dataclass(frozen=True)
class LogNormal(_Base):
    """Log-normal radius distribution: ln r ~ N(ln median, sigma^2), truncated to [min, max].

    Args:
        median: median of the untruncated distribution (m), positive.
        sigma: standard deviation of ln r (dimensionless), >= 0.
        min: lower truncation (m); default median exp(-3 sigma).
        max: upper truncation (m); default median exp(3 sigma).
    """

    median: float
    sigma: float
    min: float | None = None
    max: float | None = None

    def __post_init__(self) -> None:
        median = positive("LogNormal", "median", self.median, " (m)")
        sigma = non_negative("LogNormal", "sigma", self.sigma)
        if sigma > 10:  # exp(3 sigma) spans 13 decades: no radius distribution is that wide
            raise ValueError(f"LogNormal.sigma must be at most 10, got {self.sigma!r}")
        lo = median * math.exp(-3.0 * sigma) if self.min is None else self.min
        hi = median * math.exp(3.0 * sigma) if self.max is None else self.max
        lo, hi = _bounds("LogNormal", lo, hi)
        if sigma == 0 and not lo <= median <= hi:
            raise ValueError(
                f"LogNormal.median must be in [min, max] when sigma = 0, got {median!r}"
            )
        object.__setattr__(self, "median", median)
        object.__setattr__(self, "sigma", sigma)
        object.__setattr__(self, "min", lo)
        object.__setattr__(self, "max", hi)
        self._to_core()

    def _range(self) -> tuple[float, float]:
        return cast(float, self.min), cast(float, self.max)  # resolved in __post_init__

    def _to_core(self) -> _core.SizeDistribution:
        return _core.SizeDistribution.lognormal(self.median, self.sigma, *self._range())

    def moment(self, k: int) -> float:
        """E[r^k] by number after truncation (m^k)."""
        mu, s = math.log(self.median), self.sigma
        if s == 0:
            return float(self.median**k)
        lo, hi = self._range()
        a = (math.log(lo) - mu) / s
        b = (math.log(hi) - mu) / s
        z = _cdf(b) - _cdf(a)
        return math.exp(k * mu + 0.5 * (k * s) ** 2) * (_cdf(b - k * s) - _cdf(a - k * s)) / z

    @property
    def mean_radius(self) -> float:
        """Mean radius by number after truncation (m)."""
        return self.moment(1)

    @property
    def std_radius(self) -> float:
        """Standard deviation of the radius by number after truncation (m)."""
        m1 = self.moment(1)
        return math.sqrt(max(self.moment(2) - m1 * m1, 0.0))


@dataclass(frozen=True)
class Discrete(_Base):
    """A finite set of radii with weights.

    Args:
        radii: the radii (m), positive.
        weights: one non-negative weight per radius (normalised internally, not all zero).
        fractions: ``"number"`` if the weights are number fractions (probability per particle),
            ``"mass"`` if they are mass fractions (the share of the total mass; converted to
            number weights proportional to weight / r^3, exact for one material).

    Example:
        >>> d = Discrete(radii=(1e-3, 2e-3), weights=(1, 8), fractions="mass")
        >>> d.number_fractions()
        (0.5, 0.5)
    """

    radii: Sequence[float]
    weights: Sequence[float]
    fractions: Literal["number", "mass"] = "number"

    def __post_init__(self) -> None:
        try:
            r = tuple(float(v) for v in self.radii)
            w = tuple(float(v) for v in self.weights)
        except (TypeError, ValueError):
            raise ValueError(
                f"Discrete.radii and Discrete.weights must be sequences of numbers, got "
                f"{self.radii!r}, {self.weights!r}"
            ) from None
        if not r:
            raise ValueError("Discrete.radii must be non-empty, got ()")
        for v in r:
            positive("Discrete", "radii", v, " (m)")
        if len(w) != len(r):
            raise ValueError(
                f"Discrete.weights must have one weight per radius ({len(r)}), got {len(w)}"
            )
        for v in w:
            non_negative("Discrete", "weights", v)
        if not sum(w) > 0:
            raise ValueError(f"Discrete.weights must not all be zero, got {w!r}")
        if self.fractions not in ("number", "mass"):
            raise ValueError(
                f"Discrete.fractions must be 'number' or 'mass', got {self.fractions!r}"
            )
        object.__setattr__(self, "radii", r)
        object.__setattr__(self, "weights", w)

    def _to_core(self) -> _core.SizeDistribution:
        return _core.SizeDistribution.discrete(
            list(self.radii), list(self.weights), self.fractions == "mass"
        )

    def number_fractions(self) -> tuple[float, ...]:
        """Probability per particle of each radius."""
        w = np.asarray(self.weights, dtype=float)
        if self.fractions == "mass":
            w = w / np.asarray(self.radii, dtype=float) ** 3
        return tuple(float(v) for v in w / w.sum())

    @property
    def mean_radius(self) -> float:
        """Mean radius by number (m)."""
        return float(np.dot(self.number_fractions(), self.radii))

    @property
    def std_radius(self) -> float:
        """Standard deviation of the radius by number (m)."""
        p = np.asarray(self.number_fractions())
        r = np.asarray(self.radii)
        m = float(p @ r)
        return math.sqrt(max(float(p @ (r - m) ** 2), 0.0))


Distribution = Monodisperse | Uniform | Normal | LogNormal | Discrete


def as_distribution(value: Distribution | float, owner: str, name: str = "radius") -> Distribution:
    """A distribution, or a positive number (m) turned into ``Monodisperse``."""
    if isinstance(value, Monodisperse | Uniform | Normal | LogNormal | Discrete):
        return value
    if isinstance(value, int | float) and not isinstance(value, bool):
        return Monodisperse(positive(owner, name, value, " (m)"))
    raise ValueError(
        f"{owner}.{name} must be a grainscale.dist distribution or a radius in m, got {value!r}"
    )
