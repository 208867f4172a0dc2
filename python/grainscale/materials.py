"""Materials: elastic properties and density of a particle or wall species (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._validate import in_range, non_negative, positive


def _modulus(value: float) -> float:
    """Young's modulus: positive, finite or +inf (a rigid wall material)."""
    try:
        e = float(value)
    except (TypeError, ValueError):
        e = math.nan
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
