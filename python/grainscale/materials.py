"""Materials: elastic properties and density of a particle or wall species (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._validate import in_range, is_real, non_negative, positive


def _modulus(value: float) -> float:
    """Young's modulus: positive, finite or +inf (a rigid wall material)."""
    e = float(value) if is_real(value) else math.nan  # no strings, bools or complex numbers
    if not e > 0:  # also NaN
        raise ValueError(
            "Material.youngs_modulus must be positive (Pa; inf for a rigid wall material), "
            f"got {value!r}"
        )
    return e


@dataclass(frozen=True)
class Material:
    """A solid material.

    Args:
        density: kg/m^3.
        youngs_modulus: Young's modulus E in Pa; ``math.inf`` makes a rigid wall material: E*
            and G* of a contact with it are the particle's alone, as for a wall without a
            material, but the wall keeps its own name, interaction values and pair entries
            (e.g. a frictionless die next to rough platens). Particles need a finite E.
        poisson_ratio: Poisson's ratio nu, in [0, 0.5).
        name: label used in output and messages.
        restitution, friction, rolling_friction, rolling_damping: optional per-material
            interaction values; a pair of materials uses their mean (see grainscale.contact for
            the mixing rules). None leaves the value to the contact law.

    Example:
        >>> glass = Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> round(glass.shear_modulus)
        19230769
    """

    density: float
    youngs_modulus: float
    poisson_ratio: float
    name: str = "material"
    restitution: float | None = None
    friction: float | None = None
    rolling_friction: float | None = None
    rolling_damping: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "density", positive("Material", "density", self.density))
        object.__setattr__(self, "youngs_modulus", _modulus(self.youngs_modulus))
        object.__setattr__(
            self,
            "poisson_ratio",
            in_range("Material", "poisson_ratio", self.poisson_ratio, 0.0, 0.5, closed_hi=False),
        )
        if self.restitution is not None:
            in_range("Material", "restitution", self.restitution, 0.0, 1.0)
        for name in ("friction", "rolling_friction", "rolling_damping"):
            if getattr(self, name) is not None:
                non_negative("Material", name, getattr(self, name))

    @property
    def rigid(self) -> bool:
        """True for a rigid wall material (youngs_modulus = inf)."""
        return math.isinf(self.youngs_modulus)

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)), Pa."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))


def check_masses(owner: str, radius: np.ndarray, material: object, dimension: int) -> None:
    """ValueError naming the first radius whose particle's mass or moment of inertia float64
    cannot hold as a normal number (a radius of 1e-200 m gives a mass of 0 kg: the engine would
    divide by it). Mass m = rho 4/3 pi r^3, I = 2/5 m r^2 (3-D); m = rho pi r^2 x 1 m,
    I = m r^2 / 2 (2-D). Anything above is the user's choice: the engine copes with small
    particles, and the placement checks refuse coordinates too coarse for the radius."""
    if not isinstance(material, Material) or material.rigid:
        return  # refused by the caller with its own message
    r = np.asarray(radius, dtype=float)
    with np.errstate(over="ignore", under="ignore"):
        if dimension == 2:
            mass = material.density * math.pi * r**2
            inertia = 0.5 * mass * r**2
        else:
            mass = material.density * (4.0 / 3.0) * math.pi * r**3
            inertia = 0.4 * mass * r**2
    tiny = np.finfo(float).tiny
    bad = ~((mass >= tiny) & (inertia >= tiny) & np.isfinite(mass) & np.isfinite(inertia))
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(
            f"{owner}.radius must give a mass and moment of inertia that float64 holds as normal "
            f"numbers (between {tiny:.3g} and {np.finfo(float).max:.3g}), got {float(r[i])!r} m at "
            f"index {i}: mass {float(mass[i]):.3g} kg, moment of inertia "
            f"{float(inertia[i]):.3g} kg m^2 with density {material.density:g} kg/m^3"
        )
