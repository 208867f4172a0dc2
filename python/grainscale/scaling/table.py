"""Scale factors of every dimensional quantity, per scheme and dimension, as data.

Each entry is the exponent p of the factor h**p by which a quantity of the reference system is
multiplied in the scaled one (h = particle size ratio). Schemes:

``exact``  Feng & Owen (2014, Comp. Part. Mech. 1:159, doi:10.1007/s40571-014-0010-y), as
           tabulated by Zhang, Huang & Zhao (2021, CMES, doi:10.32604/cmes.2021.016018, Tab. 1):
           length x h, time x h, density x 1; everything else follows from its dimensions
           [L^a M^b T^c] as h**(a + 3b + c). The whole system (domain, walls, gravity) scales:
           the scaled system reproduces the reference trajectory exactly.
``cg``     energy-density consistent coarse graining: particles x h, domain, walls, gravity
           and process time unchanged; materials, restitution, friction and rolling
           parameters unchanged, linear stiffness x h, dashpot x h^2, pull-off force x h^2,
           surface energy x h (Thakur, Ooi & Ahmadian 2016, Powder Technol. 293:130: stiffness
           linear and adhesive force quadratic in particle size); time step x h.
``sakai``  the coarse grain model of Sakai & Koshizuka (2009) as analysed by Zhang et al. 2021,
           sec. 3.1.2: a particle of size h represents h^3 originals (h^2 in 2-D), contact force
           x h^3 at the same overlap (k_CGM = h^3 k_O, their Eq. 16, so the time step is kept),
           van der Waals (pull-off) force x h^2 (Eq. 15), same velocity and angular velocity
           (Fig. 3), gravity and domain unchanged.
``spa``    the similar particle assembly of Kuwagi et al. (Zhang et al. 2021, sec. 3.1.1): every
           force x h^3 (Eq. 9), cohesion included; otherwise as ``sakai``.

2-D tables are per unit thickness (discs): a quantity that grows with the thickness (mass,
inertia, force, torque, stiffness, damping, energy, pull-off force, mass rate, area) loses one
power of h against 3-D (the servo gains, inverse forces, gain one); intensive quantities (stress,
moduli, density, surface energy) keep their 3-D factor. Zhang et al. 2021, Eq. 34-35: the mean
contact force scales as h^2 in 3-D and h in 2-D.
"""

from __future__ import annotations

from dataclasses import dataclass

SCHEMES = ("exact", "cg", "sakai", "spa")
DIMENSIONS = (3, 2)

# quantity: exponents (exact 3-D, exact 2-D, cg 3-D, cg 2-D, sakai 3-D, sakai 2-D, spa 3-D,
# spa 2-D). "radius" and "overlap" are particle-scale lengths; "domain_length" covers the
# domain, wall geometry and positions; "time" is process time (wall motion, run length).
_TABLE: dict[str, tuple[float, ...]] = {
    "radius": (1, 1, 1, 1, 1, 1, 1, 1),
    "overlap": (1, 1, 1, 1, 0, 0, 0, 0),
    "domain_length": (1, 1, 0, 0, 0, 0, 0, 0),
    "area": (2, 1, 0, 0, 0, 0, 0, 0),
    "skin": (1, 1, 1, 1, 1, 1, 1, 1),
    "time": (1, 1, 0, 0, 0, 0, 0, 0),
    "time_step": (1, 1, 1, 1, 0, 0, 0, 0),
    "density": (0, 0, 0, 0, 0, 0, 0, 0),
    "mass": (3, 2, 3, 2, 3, 2, 3, 2),
    "inertia": (5, 4, 5, 4, 5, 4, 5, 4),
    "velocity": (0, 0, 0, 0, 0, 0, 0, 0),
    "angular_velocity": (-1, -1, -1, -1, 0, 0, 0, 0),
    "wall_angular_velocity": (-1, -1, 0, 0, 0, 0, 0, 0),
    "gravity": (-1, -1, 0, 0, 0, 0, 0, 0),
    "force": (2, 1, 2, 1, 3, 2, 3, 2),
    "wall_force": (2, 1, 0, 0, 0, 0, 0, 0),
    "torque": (3, 2, 3, 2, 4, 3, 4, 3),
    "stress": (0, 0, 0, 0, 0, 0, 0, 0),
    "normal_stiffness": (1, 0, 1, 0, 3, 2, 3, 2),
    "tangential_stiffness": (1, 0, 1, 0, 3, 2, 3, 2),
    "damping_coefficient": (2, 1, 2, 1, 3, 2, 3, 2),
    "rolling_stiffness": (3, 2, 3, 2, 5, 4, 5, 4),
    "energy": (3, 2, 3, 2, 3, 2, 3, 2),
    "surface_energy": (1, 1, 1, 1, 1, 1, 2, 2),
    "cohesion_energy_density": (0, 0, 0, 0, 0, 0, 1, 1),
    "pull_off_force": (2, 1, 2, 1, 2, 1, 3, 2),
    "mass_rate": (2, 1, 0, 0, 0, 0, 0, 0),
    "particle_count": (0, 0, -3, -2, -3, -2, -3, -2),
    "servo_gain": (-2, -1, 0, 0, 0, 0, 0, 0),
    "servo_integral_gain": (-3, -2, 0, 0, 0, 0, 0, 0),
    "characteristic_velocity": (0, 0, 0, 0, 0, 0, 0, 0),
    "restitution": (0, 0, 0, 0, 0, 0, 0, 0),
    "friction": (0, 0, 0, 0, 0, 0, 0, 0),
    "rolling_friction": (0, 0, 0, 0, 0, 0, 0, 0),
    "rolling_damping": (0, 0, 0, 0, 0, 0, 0, 0),
    "poisson_ratio": (0, 0, 0, 0, 0, 0, 0, 0),
}


@dataclass(frozen=True)
class Similarity:
    """A dimensionless number the scaled system does not preserve.

    Attributes:
        name: short identifier (e.g. ``"froude"``).
        definition: the number in symbols and words.
        exponent: the scaled value is the reference value times h**exponent.
        factor: h**exponent for the h of the scaling.
    """

    name: str
    definition: str
    exponent: float
    factor: float


@dataclass(frozen=True)
class _Number:
    """A tracked dimensionless number: powers of table quantities (2-D: where they differ)."""

    name: str
    definition: str
    powers: dict[str, float]
    needs: str = ""  # "gravity" / "cohesion": only reported for sets that have it
    powers_2d: dict[str, float] | None = None


# The exponent of a number is sum(power * table exponent): zero for every number under exact
# scaling (checked by the tests).
_NUMBERS = (
    _Number(
        "froude",
        "Froude number v^2 / (g d) on the particle size",
        {"velocity": 2, "gravity": -1, "radius": -1},
        needs="gravity",
    ),
    _Number(
        "size_ratio",
        "container-, orifice- and wall-gap-to-particle size ratio D / d",
        {"domain_length": 1, "radius": -1},
    ),
    _Number(
        "bond",
        "cohesion-to-weight ratio (granular Bond number) f0 / (m g)",
        {"pull_off_force": 1, "mass": -1, "gravity": -1},
        needs="cohesion",
    ),
    _Number(
        "inertial_number",
        "inertial number I = (d / T) sqrt(rho / p) at a given process time T and stress p",
        {"radius": 1, "time": -1, "density": 0.5, "stress": -0.5},
    ),
    _Number(
        "time_ratio",
        "time step (contact duration) to process time dt / T",
        {"time_step": 1, "time": -1},
    ),
    _Number("relative_overlap", "overlap to particle size delta / d", {"overlap": 1, "radius": -1}),
    _Number(
        "contact_stress",
        "contact force to bulk stress F / (sigma d^2) (F / (sigma d) in 2-D)",
        {"force": 1, "stress": -1, "radius": -2},
        powers_2d={"force": 1, "stress": -1, "radius": -1},
    ),
)


def _column(scheme: str, dimension: int) -> int:
    if scheme not in SCHEMES:
        raise ValueError(f"scaling.scheme must be one of {', '.join(SCHEMES)}, got {scheme!r}")
    if dimension not in DIMENSIONS:
        raise ValueError(f"scaling.dimension must be 3 or 2, got {dimension!r}")
    return 2 * SCHEMES.index(scheme) + (0 if dimension == 3 else 1)


def factors(scheme: str = "exact", dimension: int = 3) -> dict[str, float]:
    """The factor table of ``scheme``: quantity name -> exponent p (the factor is h**p).

    Example:
        >>> factors("exact")["force"], factors("exact", dimension=2)["force"]
        (2, 1)
    """
    col = _column(scheme, dimension)
    return {name: row[col] for name, row in _TABLE.items()}


def similarity_exponents(scheme: str, dimension: int = 3) -> dict[str, float]:
    """Exponent of every tracked similarity number under ``scheme`` (0: preserved)."""
    table = factors(scheme, dimension)
    out = {}
    for n in _NUMBERS:
        powers = n.powers_2d if dimension == 2 and n.powers_2d is not None else n.powers
        out[n.name] = sum(p * table[q] for q, p in powers.items())
    return out


def broken_similarities(
    scheme: str, h: float, dimension: int = 3, gravity: bool = True, cohesion: bool = False
) -> list[Similarity]:
    """The similarity numbers ``scheme`` changes, for a system with/without gravity, cohesion."""
    present = {"": True, "gravity": gravity, "cohesion": cohesion}
    exponents = similarity_exponents(scheme, dimension)
    return [
        Similarity(n.name, n.definition, exponents[n.name], float(h) ** exponents[n.name])
        for n in _NUMBERS
        if present[n.needs] and exponents[n.name] != 0
    ]
