"""The industrial silo of issue 28: a flat-bottomed cylinder whose bed, fully resolved, would hold
about 10^7 spheres, and the narrow resolved silos and pure coarse graining it is compared with.

Everything here is geometry and parameters (SI units); the runs are in
:mod:`studies.silo_industrial.silo_runs`.

* :func:`reference_parameters` is the resolved system (h = 1) of a cylinder of any diameter:
  the side wall and the floor with its central circular orifice as one triangle mesh, a shutter
  (a rectangle just below the orifice) that slides away, a pour stream through a disc face at
  the top and an outlet below the floor.
* :func:`hierarchy_levels` nests the chain of levels (``SiloCase.ratios``) around the orifice
  with :func:`grainscale.nested_levels`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

import grainscale as gs

SHUTTER = 1  # index of the shutter among the walls of reference_parameters()
SHUTTER_SPEED = 2.0  # m/s; the shutter slides for SHUTTER_TIME when the silo opens
SHUTTER_TIME = 0.03  # s


@dataclass(frozen=True)
class SiloCase:
    """The silo, its particles, its phases and the hierarchy (SI units). The defaults are the
    case of issue 28: 0.40 m across, about 104 kg poured (about 10^7 spheres of 2 mm)."""

    diameter: float = 0.40  # silo diameter (m)
    orifice: float = 0.02  # D0: central circular orifice (m)
    height: float = 0.62  # the pour face is at this height, the domain's top 10 mm above (m)
    below: float = 0.02  # the domain reaches this far below the floor (m)
    particle: float = 2e-3  # resolved particle diameter d (m)
    spread: float = 0.05  # diameters uniform in d (1 +/- spread)
    density: float = 2500.0  # kg/m^3
    youngs_modulus: float = 1e7  # Pa
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    fill_mass: float = 104.0  # kg poured (a bed about 0.55 m high)
    fill_rate: float = 80.0  # kg/s
    pour_speed: float = 2.0  # m/s downwards through the pour face
    settle: float = 0.4  # s between the end of the pour and the opening
    discharge: float = 10.0  # s after the shutter starts to open
    transient: float = 0.5  # s after opening before W is measured
    ratios: tuple[float, ...] = (8.0, 4.0, 2.0, 1.0)  # the hierarchy's chain, coarsest first
    roi_width: float = 2.0  # the finest level resolves a box roi_width x D0 wide
    roi_top: float = 1.25  # from below the floor to roi_top x D0 above it
    exchange_every: float = 5e-4  # s between exchanges of the hierarchy
    velocity_gain: float = 0.1
    stress_gain: float = 0.5
    boundary_velocity_gain: float = 1.0
    advance: float = 1.0
    seed: int = 1
    # The resolved references: silos reference_widths x D0 across, a bed reference_bed x D0
    # deep poured in reference_fill_time (s), settled and discharged for reference_discharge.
    reference_widths: tuple[float, ...] = (4.0, 6.0)
    reference_bed: float = 5.0
    reference_fill_time: float = 0.4
    reference_discharge: float = 1.0
    reference_transient: float = 0.3

    def __post_init__(self) -> None:
        for name in ("diameter", "orifice", "height", "particle", "fill_mass", "discharge"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"SiloCase.{name} must be positive, got {value!r}")
        if self.orifice >= 0.5 * self.diameter:
            raise ValueError(
                f"SiloCase.orifice must be below half the diameter, got {self.orifice!r}"
            )
        if not 0 <= self.transient < self.discharge:
            raise ValueError(
                f"SiloCase.transient must be in [0, discharge), got {self.transient!r}"
            )

    @property
    def open_time(self) -> float:
        """When the shutter starts to slide away (s)."""
        return self.fill_mass / self.fill_rate + self.settle

    @property
    def end_time(self) -> float:
        """End of the run (s)."""
        return self.open_time + self.discharge

    @property
    def material(self) -> gs.Material:
        """The spheres' (and the walls') material."""
        return gs.Material(
            density=self.density,
            youngs_modulus=self.youngs_modulus,
            poisson_ratio=self.poisson_ratio,
            name="glass",
        )

    @property
    def size(self) -> gs.dist.Uniform:
        """Resolved radii (m), uniform in d/2 (1 +/- spread)."""
        r = 0.5 * self.particle
        return gs.dist.Uniform(r * (1 - self.spread), r * (1 + self.spread))

    @property
    def particle_mass(self) -> float:
        """Mean mass of one resolved sphere (kg): rho 4/3 pi <r^3>, radii uniform in [a, b]."""
        a, b = self.size.min, self.size.max
        mean_r3 = (b**4 - a**4) / (4 * (b - a))
        return self.density * 4.0 / 3.0 * math.pi * mean_r3

    def resolved_equivalent(self, mass: float) -> float:
        """How many resolved spheres ``mass`` (kg) of the material is."""
        return mass / self.particle_mass

    def references(self) -> list[SiloCase]:
        """The narrow resolved silos: the same orifice, particles and material, a bed
        reference_bed x D0 deep (at solid fraction 0.6), the pour face 3 D0 above it."""
        bed = self.reference_bed * self.orifice
        out = []
        for w in self.reference_widths:
            diameter = w * self.orifice
            mass = 0.6 * self.density * math.pi * (0.5 * diameter) ** 2 * bed
            out.append(
                dataclasses.replace(
                    self,
                    diameter=diameter,
                    height=bed + 3 * self.orifice,
                    fill_mass=mass,
                    fill_rate=mass / self.reference_fill_time,
                    settle=0.3,
                    discharge=self.reference_discharge,
                    transient=self.reference_transient,
                )
            )
        return out


# A small silo for the reduced test: 4 mm spheres, D0 / d = 6, three levels 4 -> 2 -> 1, a
# shallow bed and a 0.25 s discharge.
QUICK = SiloCase(
    diameter=0.24,
    orifice=0.024,
    particle=4e-3,
    height=0.16,
    fill_mass=6.0,
    fill_rate=20.0,
    settle=0.1,
    discharge=0.25,
    transient=0.08,
    ratios=(4.0, 2.0, 1.0),
    reference_widths=(3.75,),
    reference_bed=3.0,
    reference_discharge=0.3,
    reference_transient=0.1,
)


def segments(radius: float, tolerance: float) -> int:
    """Sides (a multiple of 8) of a polygon inscribed in a circle of ``radius`` whose sides stay
    within ``tolerance`` of the circle (m): the sagitta r (1 - cos(pi / n)) <= tolerance."""
    n = math.pi / math.acos(max(-1.0, 1.0 - tolerance / radius))
    return max(32, 8 * math.ceil(n / 8))


def _square_ring(count: int, half: float) -> np.ndarray:
    """``count`` points (a multiple of 8) evenly spaced around a square of half-side ``half``
    centred on the origin, counter-clockwise from (half, 0): the corners are points count / 8,
    3 count / 8, ..."""
    s = 8 * half * np.arange(count) / count  # distance along the perimeter from (half, 0)
    side = np.minimum(((s + half) // (2 * half)).astype(int), 4)  # 0 right, 1 top, 2 left, 3 bottom
    u = s + half - 2 * half * side  # along that side, from its first corner
    x = np.select(
        [side == 0, side == 1, side == 2, side == 3], [half, half - u, -half, -half + u], half
    )
    y = np.select(
        [side == 0, side == 1, side == 2, side == 3], [-half + u, half, half - u, -half], u - half
    )
    return np.stack([x, y], axis=1)


def silo_mesh(case: SiloCase, material: gs.Material) -> gs.geometry.Mesh:
    """The side wall (0 <= z <= height) and the floor (z = 0) with its central circular orifice
    as one two-sided mesh of triangles about a cell e ~ 10 mm across (the mesh walls' bins take
    their size from the median triangle):

    * the orifice: a polygon within 0.02 d of the circle (its area within 0.1 %), joined by a
      strip of triangles to a square plate a whole number of cells e across around it;
    * the floor beyond: a grid of squares e across over the domain's square (the part outside
      the cylinder is never reached);
    * the side wall: a polygon within 0.02 d of the cylinder, in rows about e high.
    """
    R, r0, d = 0.5 * case.diameter, 0.5 * case.orifice, case.particle
    cells = max(4, round(R / 0.01))
    e = R / cells  # the grid lines pass through the centre
    plate = min(cells - 1, math.ceil(1.5 * case.orifice / e))  # plate half-side in cells
    n0 = segments(r0, 0.02 * d)
    a0 = 2 * math.pi * np.arange(n0) / n0
    hole = R + r0 * np.stack([np.cos(a0), np.sin(a0)], axis=1)
    ring = R + _square_ring(n0, plate * e)
    grid = e * np.arange(2 * cells + 1)
    gx, gy = np.meshgrid(grid, grid, indexing="ij")
    flat = np.concatenate([hole, ring, np.stack([gx.ravel(), gy.ravel()], axis=1)])
    tri: list[tuple[int, int, int]] = []
    for i in range(n0):  # hole -> plate edge
        j = (i + 1) % n0
        tri += [(i, j, n0 + j), (i, n0 + j, n0 + i)]
    g0, m = 2 * n0, 2 * cells + 1
    for i in range(2 * cells):  # the grid's squares outside the plate
        for j in range(2 * cells):
            if max(abs(i + 0.5 - cells), abs(j + 0.5 - cells)) < plate:
                continue
            k = g0 + i * m + j
            tri += [(k, k + m, k + m + 1), (k, k + m + 1, k + 1)]
    n = segments(R, 0.02 * d)
    a = 2 * math.pi * np.arange(n) / n
    side = R + R * np.stack([np.cos(a), np.sin(a)], axis=1)
    rows = max(1, round(case.height / e))
    levels = case.height * np.arange(rows + 1) / rows
    wall = np.concatenate([np.column_stack([side, np.full(n, z)]) for z in levels])
    base = len(flat)
    for r in range(rows):
        for i in range(n):
            p, q = base + r * n + i, base + r * n + (i + 1) % n
            tri += [(p, q, q + n), (p, q + n, p + n)]
    v = np.concatenate([np.column_stack([flat, np.zeros(len(flat))]), wall])
    return gs.geometry.Mesh(vertices=v, triangles=np.array(tri), material=material)


def reference_parameters(case: SiloCase) -> gs.scaling.ParameterSet:
    """The resolved system (h = 1): the silo mesh (wall 0), the shutter just below the orifice
    (wall SHUTTER), the pour stream through a disc at the top and an outlet below the floor."""
    glass = case.material
    R, d0, d = 0.5 * case.diameter, case.orifice, case.particle
    shutter = gs.Rectangle(  # 0.05 d below the floor, overlapping the orifice by 2 d each side
        corner=(R - 0.5 * d0 - 2 * d, R - 0.5 * d0 - 2 * d, -0.05 * d),
        edge1=(d0 + 4 * d, 0, 0),
        edge2=(0, d0 + 4 * d, 0),
        material=glass,
    )
    # The pour disc keeps a coarsest parcel's diameter from the wall.
    margin = case.ratios[0] * d
    stream = gs.insert.Stream(
        gs.insert.DiscFace(centre=(R, R, case.height), normal=(0, 0, -1), radius=R - margin),
        mass_rate=case.fill_rate,
        radius=case.size,
        material=glass,
        velocity=(0, 0, -case.pour_speed),
        seed=case.seed,
        stop=case.fill_mass / case.fill_rate,
    )
    w = case.diameter
    outlet = gs.insert.Outlet(region=gs.Box(lo=(0, 0, -case.below), hi=(w, w, -0.5 * case.below)))
    return gs.scaling.ParameterSet(
        domain=gs.Box(lo=(0, 0, -case.below), hi=(w, w, case.height + 0.01)),
        contact=gs.contact.HertzMindlin(restitution=case.restitution, friction=case.friction),
        walls=(silo_mesh(case, glass), shutter),
        insertions=(stream,),
        outlets=(outlet,),
        size=case.size,
    )


def region_of_interest(case: SiloCase) -> gs.Box:
    """Where the resolved level must resolve the flow: roi_width x D0 across the orifice, from
    the bottom of the domain to roi_top x D0 above the floor (m)."""
    R, half = 0.5 * case.diameter, 0.5 * case.roi_width * case.orifice
    return gs.Box(
        lo=(R - half, R - half, -case.below), hi=(R + half, R + half, case.roi_top * case.orifice)
    )


def exchange(case: SiloCase) -> gs.Exchange:
    """The hierarchy's coupling settings (every interface)."""
    return gs.Exchange(
        every=case.exchange_every,
        velocity_gain=case.velocity_gain,
        stress_gain=case.stress_gain,
        boundary_velocity_gain=case.boundary_velocity_gain,
        advance=case.advance,
    )


def hierarchy_levels(case: SiloCase) -> list[gs.Level]:
    """The chain of levels nested around the orifice (:func:`grainscale.nested_levels`)."""
    return gs.nested_levels(
        reference_parameters(case), region_of_interest(case), case.ratios, exchange(case)
    )


def describe(case: SiloCase) -> dict[str, Any]:
    """The case as plain data, with the resolved-equivalent count of the poured mass."""
    out = dataclasses.asdict(case)
    out["particle_mass"] = case.particle_mass
    out["resolved_equivalent_poured"] = case.resolved_equivalent(case.fill_mass)
    return out
