"""Time-step helpers: Rayleigh time and elastic Hertz contact time (SI units)."""

from __future__ import annotations

from . import _core
from .materials import Material


def rayleigh_time(material: Material, radius: float) -> float:
    """Rayleigh time t_R = pi r sqrt(rho/G) / (0.1631 nu + 0.8766), s.

    Example:
        >>> from grainscale import Material
        >>> glass = Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> f"{rayleigh_time(glass, 1e-3):.3e}"  # G = E / (2 (1 + nu)) = 19.2 MPa
        '3.870e-05'
    """
    if material.rigid:
        raise ValueError(
            "rayleigh_time.material must be deformable (finite youngs_modulus), got the rigid "
            f"wall material {material.name!r}"
        )
    return _core.rayleigh_time(
        radius, material.density, material.youngs_modulus, material.poisson_ratio
    )


def hertz_contact_time(
    material: Material,
    radius: float,
    impact_velocity: float,
    other: tuple[Material, float] | None = None,
) -> float:
    """Elastic Hertz contact duration (CASES.md A1), s.

    Args:
        material, radius: the impacting sphere.
        impact_velocity: relative normal approach speed, m/s.
        other: (material, radius) of the second sphere, or None for a rigid wall.
    """
    import math

    m1 = material.density * 4.0 / 3.0 * math.pi * radius**3
    c1 = (1 - material.poisson_ratio**2) / material.youngs_modulus
    if other is None:
        r_eff, m_eff, e_eff = radius, m1, 1.0 / c1
    else:
        mat2, r2 = other
        m2 = mat2.density * 4.0 / 3.0 * math.pi * r2**3
        c2 = (1 - mat2.poisson_ratio**2) / mat2.youngs_modulus
        r_eff, m_eff, e_eff = radius * r2 / (radius + r2), m1 * m2 / (m1 + m2), 1.0 / (c1 + c2)
    return _core.hertz_contact_time(r_eff, m_eff, e_eff, impact_velocity)
