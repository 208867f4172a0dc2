"""Silo discharge study (CASES D1): the silos, their material and their walls.

``SiloCase`` holds every parameter of a silo (SI units) and derives the silo, bed and measuring
window for an orifice; ``annulus_mesh`` and ``cylinder_surface`` build the floor and the wall.
The study itself is ``studies.silo_discharge.silo_discharge``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import grainscale as gs
from studies.silo_discharge.silo_beverloo import beverloo_rate

WINDOW = (0.2, 0.7)  # fractions of the inventory between which W is measured
DEFAULT_ORIFICES_MM = (24.0, 32.0, 40.0, 52.0, 64.0)
QUICK_ORIFICES_MM = (24.0, 28.0)
#: one small constant-head silo (the reduced test in tests/physics uses the same)
QUICK_CASE = {
    "silo_diameter": 0.06,
    "fill_height": 0.05,
    "transient": 0.3,
    "measure_time": 0.4,
    "measure_count": 400.0,
}
DEFAULT_ORIFICES = tuple(1e-3 * v for v in DEFAULT_ORIFICES_MM)  # m


@dataclass(frozen=True)
class SiloCase:
    """Parameters of the silos (SI units).

    By default every orifice gets the smallest silo whose diameter does not affect the rate,
    D_s = max(silo_ratio D0, D0 + wall_gap d), with a bed max(height_ratio D_s, head_ratio D0)
    deep, kept at that depth by re-pouring (``constant_head``). ``silo_diameter`` fixes the silo
    instead, ``fill_height`` or ``particles`` the fill (give at most one of these two).

    Args:
        silo_ratio: least silo diameter / D0 (Beverloo needs >= 2.5).
        wall_gap: least (silo diameter - D0) / d.
        height_ratio: settled bed height / silo diameter ...
        head_ratio: ... or / D0, whichever is larger (CASES D1: H / D0 > 2).
        constant_head: re-pour what the outlet removes (else the bed drains).
        silo_diameter: fixed inner diameter of the cylinder (m), or None.
        fill_height: fixed target height of the settled bed (m), or None; the poured mass is
            packing_guess x rho_p x silo cross-section x height.
        particles: fixed number of particles instead (the poured mass is that many mean
            particles; exact to about one particle), or None.
        diameter: mean particle diameter (m); diameters uniform in diameter (1 +/- spread).
        packing_guess: solid fraction used to turn a height into a mass.
        pour_speed: speed of the poured particles through the top face (m/s).
        pour_fraction: solid fraction of the poured stream (sets the mass rate).
        settle_speed: the bed is settled when the rms speed sqrt(2 KE / M) drops below it
            (m/s), at the earliest ``min_settle`` s after the pour ends, at the latest
            ``max_settle`` s after it.
        shutter_speed: speed (m/s) at which the shutter under the orifice drops 4 d away.
        transient: s after opening before the steady window (constant head).
        measure_time, measure_count: the window lasts at least this long (s) and about this
            many particles at Beverloo's rate.
        refill_every: s between re-pourings; refill_speed: their downward speed (m/s).
        stop_fraction: a draining discharge stops when this fraction of the inventory has left.
        clog_time: a discharge with no particle out for this long (s) counts as clogged.
        max_discharge: longest discharge simulated (s).
        outlet_every: steps between outlet checks.
        time_step: s; None: 0.2 x the Rayleigh time of the smallest sphere.
        vtk_every: particle snapshot interval (s) or None for no VTK output.
        cg: coarse-graining ratio h >= 1: the particles (parcels h d across), time step, skin
            and contact parameters come from ``grainscale.scaling.scale(..., "cg")`` of the
            resolved set; the silo, bed, fill mass and measuring window stay those of the
            resolved case (d), the outlet depth, shutter gap and pour/refill margins follow
            the parcel size h d.
    """

    silo_ratio: float = 2.5
    wall_gap: float = 20.0
    height_ratio: float = 0.5
    head_ratio: float = 2.0
    constant_head: bool = True
    silo_diameter: float | None = None
    fill_height: float | None = None
    particles: int | None = None
    diameter: float = 4e-3
    diameter_spread: float = 0.05
    density: float = 2500.0
    youngs_modulus: float = 1e7
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    rolling_friction: float = 0.05
    rolling_damping: float = 0.3
    packing_guess: float = 0.57
    pour_speed: float = 1.5
    pour_fraction: float = 0.15
    settle_speed: float = 0.01
    min_settle: float = 0.05
    max_settle: float = 1.0
    shutter_speed: float = 4.0
    transient: float = 0.4
    measure_time: float = 0.3
    measure_count: float = 1000.0
    refill_every: float = 0.02
    refill_speed: float = 1.0
    stop_fraction: float = 0.75
    clog_time: float = 0.5
    max_discharge: float = 30.0
    outlet_every: int = 10
    time_step: float | None = None
    vtk_every: float | None = None
    cg: float = 1.0

    def __post_init__(self) -> None:
        if not (isinstance(self.cg, int | float) and math.isfinite(self.cg) and self.cg >= 1):
            raise ValueError(f"SiloCase.cg must be >= 1, got {self.cg!r}")
        if self.fill_height is not None and self.particles is not None:
            raise ValueError(
                "SiloCase takes at most one of fill_height and particles, got "
                f"fill_height={self.fill_height!r}, particles={self.particles!r}"
            )
        if self.particles is not None and (
            isinstance(self.particles, bool) or int(self.particles) != self.particles
        ):
            raise ValueError(f"SiloCase.particles must be an integer, got {self.particles!r}")
        if self.particles is not None and self.particles < 50:
            raise ValueError(f"SiloCase.particles must be at least 50, got {self.particles}")
        for name in (
            "silo_ratio",
            "height_ratio",
            "head_ratio",
            "diameter",
            "density",
            "youngs_modulus",
            "packing_guess",
            "pour_speed",
            "pour_fraction",
            "settle_speed",
            "max_settle",
            "shutter_speed",
            "clog_time",
            "max_discharge",
            "transient",
            "measure_time",
            "measure_count",
            "refill_every",
            "refill_speed",
        ):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise ValueError(f"SiloCase.{name} must be positive, got {value!r}")
        for name in ("silo_diameter", "fill_height"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 2 * self.diameter):
                raise ValueError(
                    f"SiloCase.{name} must exceed two particle diameters (m), got {value!r}"
                )
        if not (math.isfinite(self.wall_gap) and self.wall_gap >= 0):
            raise ValueError(f"SiloCase.wall_gap must be >= 0, got {self.wall_gap!r}")
        if not 0 <= self.diameter_spread < 1:
            raise ValueError(
                f"SiloCase.diameter_spread must be in [0, 1), got {self.diameter_spread!r}"
            )
        if not WINDOW[1] < self.stop_fraction <= 1:
            raise ValueError(
                f"SiloCase.stop_fraction must be in ({WINDOW[1]}, 1], got {self.stop_fraction!r}"
            )

    # ----- derived quantities
    @property
    def radius_distribution(self) -> gs.dist.Uniform:
        r = 0.5 * self.diameter
        return gs.dist.Uniform(r * (1 - self.diameter_spread), r * (1 + self.diameter_spread))

    @property
    def mean_particle_mass(self) -> float:
        """Mean particle mass by number (kg): rho 4/3 pi E[r^3] for the uniform radius."""
        a, b = self.radius_distribution.min, self.radius_distribution.max
        r3 = (b**4 - a**4) / (4 * (b - a)) if b > a else a**3
        return self.density * 4.0 / 3.0 * math.pi * r3

    def silo_for(self, orifice: float) -> float:
        """Silo diameter (m) for the orifice D0 (m): the fixed one, else the smallest with
        D_s >= silo_ratio D0 (Beverloo et al. 1961) and D_s - D0 >= wall_gap d (Nedderman et
        al. 1982: the rate is independent of the silo diameter when D_s - D0 > 30 d)."""
        if self.silo_diameter is not None:
            return self.silo_diameter
        return max(self.silo_ratio * orifice, orifice + self.wall_gap * self.diameter)

    def target_mass(self, orifice: float) -> float:
        """Mass poured into the silo of the orifice D0 (kg)."""
        if self.particles is not None:
            return self.particles * self.mean_particle_mass
        silo = self.silo_for(orifice)
        height = self.fill_height
        if height is None:
            height = max(self.height_ratio * silo, self.head_ratio * orifice)
        area = math.pi * (0.5 * silo) ** 2
        return self.packing_guess * self.density * area * height

    def nominal_height(self, orifice: float) -> float:
        """Expected bed height (m) at the packing guess."""
        area = math.pi * (0.5 * self.silo_for(orifice)) ** 2
        return self.target_mass(orifice) / (self.packing_guess * self.density * area)

    def measure_window(self, orifice: float) -> tuple[float, float]:
        """Steady window (s after opening) of a constant-head run: from ``transient`` for at
        least ``measure_time`` s and about ``measure_count`` particles at Beverloo's rate
        (C = 0.58, k = 1.5, rho_b = 0.6 rho_p)."""
        w = beverloo_rate(orifice, self.diameter, 0.6 * self.density)
        length = self.measure_time
        if w > 0:
            length = max(length, self.measure_count * self.mean_particle_mass / float(w))
        return self.transient, self.transient + length

    def describe(self) -> str:
        """The silo and fill rule in words."""
        if self.silo_diameter is not None:
            silo = f"silo D_s = {self.silo_diameter * 1e3:g} mm"
        else:
            silo = f"silo D_s = max({self.silo_ratio:g} D0, D0 + {self.wall_gap:g} d)"
        if self.particles is not None:
            fill = f"{self.particles} particles"
        elif self.fill_height is not None:
            fill = f"fill height {self.fill_height * 1e3:g} mm"
        else:
            fill = f"bed max({self.height_ratio:g} D_s, {self.head_ratio:g} D0) deep"
        head = "constant head (outflow re-poured on top)" if self.constant_head else "draining"
        cg = f", coarse-grained h = {self.cg:g}" if self.cg != 1 else ""
        return f"{silo}, {fill}, {head}{cg}"

    def material(self) -> gs.Material:
        return gs.Material(
            density=self.density,
            youngs_modulus=self.youngs_modulus,
            poisson_ratio=self.poisson_ratio,
            name="glass",
        )

    def contact_law(self) -> gs.contact.HertzMindlin:
        return gs.contact.HertzMindlin(
            restitution=self.restitution,
            friction=self.friction,
            rolling=gs.contact.EPSD(self.rolling_friction, self.rolling_damping),
        )


# ------------------------------------------------------------------------------------------
# geometry
# ------------------------------------------------------------------------------------------


def annulus_mesh(
    inner_radius: float,
    outer_radius: float,
    segments: int = 72,
    z: float = 0.0,
    material: gs.Material | None = None,
) -> gs.geometry.Mesh:
    """A flat annulus in the plane z (m) with a central circular hole: a silo floor.

    The hole is a regular polygon of ``segments`` sides with the area of the circle of radius
    ``inner_radius`` (its vertices sit slightly outside the circle); rings of quads, each split
    into two triangles, with a radial spacing about equal to the outer arc length.
    """
    if not 0 < inner_radius < outer_radius:
        raise ValueError(
            f"annulus_mesh.outer_radius must exceed inner_radius = {inner_radius!r} (m), got "
            f"{outer_radius!r}"
        )
    if segments < 8:
        raise ValueError(f"annulus_mesh.segments must be at least 8, got {segments!r}")
    step = 2 * math.pi / segments
    r_hole = inner_radius * math.sqrt(step / math.sin(step))  # equal-area polygon
    rings = max(1, math.ceil((outer_radius - r_hole) / (outer_radius * step)))
    radii = np.linspace(r_hole, outer_radius, rings + 1)
    theta = np.arange(segments) * step
    vertices = np.array([(r * math.cos(t), r * math.sin(t), z) for r in radii for t in theta])
    triangles = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            triangles += [(a, b, b + segments), (a, b + segments, a + segments)]
    return gs.geometry.Mesh(vertices, np.array(triangles), material=material)


def cylinder_surface(radius: float, z0: float, z1: float, segments: int = 72) -> tuple:
    """Vertices and triangles of an open cylinder surface (for ParaView only)."""
    theta = np.arange(segments) * 2 * math.pi / segments
    ring = np.column_stack([radius * np.cos(theta), radius * np.sin(theta)])
    vertices = np.vstack([np.column_stack([ring, np.full(segments, z)]) for z in (z0, z1)])
    tris = []
    for j in range(segments):
        a, b = j, (j + 1) % segments
        tris += [(a, b, b + segments), (a, b + segments, a + segments)]
    return vertices, np.array(tris, dtype=np.int64)
