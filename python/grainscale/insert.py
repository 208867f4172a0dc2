"""Insertion and removal of particles.

Operations executed by the C++ core (cpp/insert/), declared here as validated, frozen
parameter sets (SI units):

* :class:`Pack` - random non-overlapping placement of a count or a volume fraction of particles
  in a region (``gs.Box``, a finite ``gs.geometry.Cylinder`` or the interior of a closed
  ``gs.geometry.Mesh``), avoiding the particles already present and the walls;
  ``sim.insert(Pack(...))`` inserts at once and returns the ids.
* :class:`Stream` - particles entering through a face (:class:`RectangleFace`,
  :class:`DiscFace`) at a mass rate with an initial velocity, in batches, without overlaps
  (with particles or walls);
  ``sim.insert(Stream(...))`` registers it (it runs inside ``sim.run``) and returns a
  :class:`StreamHandle` with the mass bookkeeping.
* :class:`Outlet` - particles whose centre enters a region are deleted and counted;
  ``sim.add_outlet(Outlet(...))`` returns an :class:`OutletHandle` with the removed mass and its
  history (for discharge rates).

Radii come from a size distribution (:mod:`grainscale.dist`) sampled in C++ with a seeded
engine: the same seed gives the same particles. Nothing is ever dropped silently: a packing
that cannot reach its target raises ``RuntimeError`` and inserts nothing; stream particles that
find no room stay pending and are retried at the next batch.

The set-up helpers that only return positions (:func:`lattice`, :func:`random_in_box`, for
``Simulation.add_particles``) live in ``grainscale.positions`` and are re-exported here.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import KW_ONLY, dataclass
from typing import TYPE_CHECKING, Any, NamedTuple, cast

import numpy as np

from . import _core
from ._validate import direction, non_negative, positive, span, vector3
from .dist import Distribution, as_distribution
from .geometry import Box, Cylinder, Mesh
from .materials import Material
from .positions import lattice, random_in_box

if TYPE_CHECKING:
    from .engine import Engine
    from .simulation import Simulation

__all__ = [
    "DiscFace",
    "Outlet",
    "OutletHandle",
    "OutletHistory",
    "Pack",
    "RectangleFace",
    "Region",
    "Stream",
    "StreamHandle",
    "lattice",
    "random_in_box",
]

Region = Box | Cylinder


# --------------------------------------------------------------------------- regions and faces


def _core_region(region: Any, owner: str, allow_mesh: bool = False) -> _core.Region:
    """The core's region for a gs.Box, a finite gs.geometry.Cylinder or (allow_mesh) the
    interior of a closed gs.geometry.Mesh; anything else is refused naming ``owner``."""
    if isinstance(region, Box | Cylinder) or (allow_mesh and isinstance(region, Mesh)):
        return region._to_core(owner)
    kinds = (
        "grainscale.Box, grainscale.geometry.Cylinder or a closed grainscale.geometry.Mesh"
        if allow_mesh
        else "grainscale.Box or grainscale.geometry.Cylinder"
    )
    raise ValueError(f"{owner}.region must be a {kinds}, got {region!r}")


def _material(owner: str, material: Any) -> Material:
    if not isinstance(material, Material):
        raise ValueError(f"{owner}.material must be a grainscale.Material, got {material!r}")
    return material


def _seed(owner: str, seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed < 2**64:
        raise ValueError(f"{owner}.seed must be an integer in [0, 2^64), got {seed!r}")
    return int(seed)


def _positive_int(owner: str, name: str, value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{owner}.{name} must be a positive integer, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class RectangleFace:
    """A parallelogram inlet face: corner + a edge1 + b edge2, a, b in [0, 1] (m).

    Its normal is edge1 x edge2 (normalised). Stream particles are placed on the side of the
    face the stream velocity points to (the normal decides when the velocity is parallel to the
    face).
    """

    corner: tuple[float, float, float]
    edge1: tuple[float, float, float]
    edge2: tuple[float, float, float]

    def __post_init__(self) -> None:
        object.__setattr__(self, "corner", vector3("RectangleFace", "corner", self.corner))
        e1 = vector3("RectangleFace", "edge1", self.edge1)
        e2 = vector3("RectangleFace", "edge2", self.edge2)
        with np.errstate(over="ignore", invalid="ignore"):
            area = float(np.linalg.norm(np.cross(e1, e2)))
        if not 0 < area < 1e300:  # 0: degenerate; beyond: the normal would overflow
            raise ValueError(
                f"RectangleFace.edge2 must be non-zero, not parallel to edge1 and span an area "
                f"below 1e300 m^2 with it, got {self.edge2}"
            )
        object.__setattr__(self, "edge1", e1)
        object.__setattr__(self, "edge2", e2)

    def _to_core(self) -> _core.Face:
        return _core.Face.rectangle(self.corner, self.edge1, self.edge2)


@dataclass(frozen=True)
class DiscFace:
    """A circular inlet face (m): centre, normal (normalised internally), radius."""

    centre: tuple[float, float, float]
    normal: tuple[float, float, float]
    radius: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "centre", vector3("DiscFace", "centre", self.centre))
        object.__setattr__(self, "normal", direction("DiscFace", "normal", self.normal))
        object.__setattr__(self, "radius", positive("DiscFace", "radius", self.radius, " (m)"))

    def _to_core(self) -> _core.Face:
        return _core.Face.disc(self.centre, self.normal, self.radius)


Face = RectangleFace | DiscFace

# --------------------------------------------------------------------------- packing


@dataclass(frozen=True)
class Pack:
    """Random non-overlapping packing of a region (random sequential addition, largest first).

    The spheres lie entirely inside the region and overlap neither each other, nor the particles
    already in the simulation, nor any wall (plane, rectangle, cylinder, mesh, where it is at
    insertion time): a sphere touching a wall, as the contact code sees it, is not a valid
    position (mesh walls are two-sided: a sphere may sit inside a closed mesh wall if it fits
    there). Give exactly one of ``count`` and ``volume_fraction`` (a fraction of the region's
    volume, including any part walls take up). If a particle finds no free position in
    ``max_attempts`` trials, ``sim.insert`` raises ``RuntimeError`` saying how many were placed
    and inserts nothing. Random sequential addition jams near a volume fraction of 0.38 for
    equal spheres; denser beds come from letting a looser packing settle.

    A closed ``gs.geometry.Mesh`` (e.g. ``Mesh.from_stl``) as region packs its interior: a sphere
    is inside when its centre is (parity of the crossings of a ray along +x) and it does not
    cross the surface. The surface must be closed and consistently oriented (every edge shared
    by exactly two triangles, traversed in opposite directions; identical vertices are merged),
    else ``ValueError``; the mesh's material and motion are ignored, and it is not added as a
    wall (pass it to ``sim.add_wall`` too to keep the particles in).

    Args:
        region: ``gs.Box``, a finite ``gs.geometry.Cylinder`` or a closed
            ``gs.geometry.Mesh``, inside the domain. In 2-D mode a ``gs.Box`` whose z range
            contains ``sim.plane_z``: discs are placed in its x-y rectangle, in the plane.
        radius: a ``gs.dist`` distribution, or one radius (m).
        material: the particles' material.
        count: number of particles.
        volume_fraction: particle volume / region volume in [0, 1] (2-D: disc area / rectangle
            area); radii are drawn until the total is closest to the target.
        velocity: initial velocity of every particle (m/s).
        seed: random seed (radii and positions).
        max_attempts: trial positions per particle.

    Example:
        >>> import grainscale as gs
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02))
        >>> sim = gs.Simulation(domain=box)
        >>> ids = sim.insert(gs.insert.Pack(box, radius=1e-3, material=glass, count=50, seed=1))
        >>> len(ids)
        50
    """

    region: Region | Mesh
    _: KW_ONLY
    radius: Distribution | float
    material: Material
    count: int | None = None
    volume_fraction: float | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    seed: int = 0
    max_attempts: int = 1000

    def __post_init__(self) -> None:
        _core_region(self.region, "Pack", allow_mesh=True)
        object.__setattr__(self, "radius", as_distribution(self.radius, "Pack"))
        _material("Pack", self.material)
        if (self.count is None) == (self.volume_fraction is None):
            raise ValueError(
                "Pack needs exactly one of count and volume_fraction, got "
                f"count={self.count!r}, volume_fraction={self.volume_fraction!r}"
            )
        if self.count is not None and (
            isinstance(self.count, bool)
            or not isinstance(self.count, int | np.integer)
            or self.count < 0
        ):
            raise ValueError(f"Pack.count must be a non-negative integer, got {self.count!r}")
        if self.volume_fraction is not None:
            vf = non_negative("Pack", "volume_fraction", self.volume_fraction)
            if vf > 1:
                raise ValueError(f"Pack.volume_fraction must be in [0, 1], got {vf!r}")
            object.__setattr__(self, "volume_fraction", vf)
        object.__setattr__(self, "velocity", vector3("Pack", "velocity", self.velocity))
        object.__setattr__(self, "seed", _seed("Pack", self.seed))
        object.__setattr__(
            self, "max_attempts", _positive_int("Pack", "max_attempts", self.max_attempts)
        )

    def _insert(self, sim: Simulation) -> np.ndarray:
        if sim.dimension == 2 and not isinstance(self.region, Box):
            raise ValueError(f"Pack.region must be a gs.Box in 2-D mode, got {self.region!r}")
        first, n = sim.engine.pack(
            _core_region(self.region, "Pack", allow_mesh=True),
            cast(Distribution, self.radius)._to_core(),
            -1 if self.count is None else int(self.count),
            -1.0 if self.volume_fraction is None else float(self.volume_fraction),
            sim.particle_material_index(self.material, "Pack"),
            self.velocity,
            self.seed,
            self.max_attempts,
        )
        return np.arange(first, first + n, dtype=np.int64)


# --------------------------------------------------------------------------- streams


@dataclass(frozen=True)
class Stream:
    """Particles entering through a face at a mass rate, in batches, without overlaps.

    Batch k is due at t_k = start + k every and brings the mass of [t_k, t_k + every) (up to
    ``stop``); it runs inside ``sim.run`` at the first step with t >= t_k, so results do not
    depend on how ``run`` is chunked. Its particles are drawn from ``radius`` and placed at
    random in a slab on the face's downstream side (the side ``velocity`` points to), of
    thickness max(2 largest diameters, normal speed x every), avoiding each other, every
    particle present and every wall (where it is at the batch time). Particles that find no
    room (also when a wall takes part of the slab) stay pending and are retried at the next
    batch time (also after ``stop``) - never dropped. Keep the stream's volume fraction,
    mass_rate / (density x face area x normal speed), well below ~0.3, or pending mass
    accumulates.

    Args:
        face: :class:`RectangleFace` or :class:`DiscFace` (inside the domain with its slab).
        mass_rate: kg/s.
        radius: a ``gs.dist`` distribution, or one radius (m).
        material: the particles' material.
        velocity: initial velocity (m/s).
        seed: random seed (radii and positions).
        start: simulated time of the first batch (s); None: when the stream is registered.
        stop: simulated time after which no more mass is requested (s); None: never.
        every: batch interval (s); None: the time to travel one largest diameter at the normal
            insertion speed (then the velocity must cross the face).
        max_attempts: trial positions per pending particle and batch.
    """

    face: Face
    _: KW_ONLY
    mass_rate: float
    radius: Distribution | float
    material: Material
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    seed: int = 0
    start: float | None = None
    stop: float | None = None
    every: float | None = None
    max_attempts: int = 50

    def __post_init__(self) -> None:
        if not isinstance(self.face, RectangleFace | DiscFace):
            raise ValueError(
                f"Stream.face must be a grainscale.insert.RectangleFace or DiscFace, "
                f"got {self.face!r}"
            )
        object.__setattr__(
            self, "mass_rate", positive("Stream", "mass_rate", self.mass_rate, " (kg/s)")
        )
        object.__setattr__(self, "radius", as_distribution(self.radius, "Stream"))
        _material("Stream", self.material)
        object.__setattr__(self, "velocity", vector3("Stream", "velocity", self.velocity))
        object.__setattr__(self, "seed", _seed("Stream", self.seed))
        if self.start is not None:
            object.__setattr__(self, "start", non_negative("Stream", "start", self.start))
        if self.stop is not None:
            stop = positive("Stream", "stop", self.stop, " (s)")
            if self.start is not None and not stop > self.start:
                raise ValueError(
                    f"Stream.stop must be greater than start = {self.start!r} s, got {stop!r}"
                )
            object.__setattr__(self, "stop", stop)
        if self.every is not None:
            object.__setattr__(self, "every", positive("Stream", "every", self.every, " (s)"))
        elif float(np.dot(self.velocity, self._normal())) == 0:
            raise ValueError(
                "Stream.every must be given when the velocity has no component across the face "
                f"(s), got None (velocity {self.velocity})"
            )
        object.__setattr__(
            self, "max_attempts", _positive_int("Stream", "max_attempts", self.max_attempts)
        )

    def _normal(self) -> np.ndarray:
        if isinstance(self.face, DiscFace):
            n = np.asarray(self.face.normal)
        else:
            n = np.cross(self.face.edge1, self.face.edge2)
        unit: np.ndarray = n / np.linalg.norm(n)
        return unit

    @property
    def volume_fraction(self) -> float:
        """Solid fraction of the stream crossing the face, rate / (density area normal speed)."""
        speed = abs(float(np.dot(self.velocity, self._normal())))
        if isinstance(self.face, DiscFace):
            area = math.pi * self.face.radius**2
        else:
            area = float(np.linalg.norm(np.cross(self.face.edge1, self.face.edge2)))
        if speed == 0:
            return math.inf
        return self.mass_rate / (self.material.density * area * speed)

    def _insert(self, sim: Simulation) -> StreamHandle:
        index = sim.engine.add_stream(
            self.face._to_core(),
            cast(Distribution, self.radius)._to_core(),
            mass_rate=self.mass_rate,
            material=sim.particle_material_index(self.material, "Stream"),
            velocity=self.velocity,
            seed=self.seed,
            start=sim.time if self.start is None else self.start,
            stop=self.stop,
            every=self.every,
            max_attempts=self.max_attempts,
        )
        phi = self.volume_fraction
        if math.isfinite(phi) and phi > 0.3:
            warnings.warn(
                f"Stream volume fraction {phi:.2f} (mass_rate / (density x face area x normal "
                "speed)) is high: insertion may not keep up and pending mass may grow; use a "
                "larger face or a higher speed",
                stacklevel=3,
            )
        return StreamHandle(sim.engine, index, self)


class StreamHandle:
    """Bookkeeping of a registered stream (all masses in kg, counts of particles).

    requested = mass_rate x elapsed time in [start, stop]; inserted + pending = mass scheduled
    by the batches so far (it leads the requested mass by at most one batch and one particle).
    """

    def __init__(self, engine: Engine, index: int, stream: Stream) -> None:
        self._engine = engine
        self.index = index
        self.stream = stream

    def status(self) -> dict[str, Any]:
        """All bookkeeping values at once (see the properties), plus ``batches`` (batch times
        passed), ``interval`` (s), ``thickness`` (m) and ``direction`` (unit, into the slab)."""
        return self._engine.stream_status(self.index)

    @property
    def requested_mass(self) -> float:
        """mass_rate x time elapsed since start (up to stop), kg."""
        return float(self._engine.stream_status(self.index)["requested_mass"])

    @property
    def inserted_mass(self) -> float:
        """Mass of the particles inserted so far, kg."""
        return float(self._engine.stream_status(self.index)["inserted_mass"])

    @property
    def pending_mass(self) -> float:
        """Mass of the particles due but not placed yet (retried at the next batch), kg."""
        return float(self._engine.stream_status(self.index)["pending_mass"])

    @property
    def scheduled_mass(self) -> float:
        """What the batches so far asked for (inserted_mass + pending_mass), kg."""
        return float(self._engine.stream_status(self.index)["scheduled_mass"])

    @property
    def inserted_count(self) -> int:
        """Number of particles inserted so far."""
        return int(self._engine.stream_status(self.index)["inserted_count"])

    @property
    def pending_count(self) -> int:
        """Number of particles due but not placed yet."""
        return int(self._engine.stream_status(self.index)["pending_count"])

    @property
    def max_radius(self) -> float:
        """Largest radius the stream inserts (m)."""
        return cast(Distribution, self.stream.radius).max_radius

    @property
    def interval(self) -> float:
        """Batch interval (s)."""
        return float(self._engine.stream_status(self.index)["interval"])

    def slab(self) -> _core.Region:
        """The insertion slab (core Region; ``contains(points, radius)`` tests points)."""
        return self._engine.stream_slab(self.index)

    def __repr__(self) -> str:
        s = self.status()
        return (
            f"StreamHandle(index={self.index}, requested_mass={s['requested_mass']:.6g}, "
            f"inserted_mass={s['inserted_mass']:.6g}, pending_mass={s['pending_mass']:.6g}, "
            f"inserted_count={s['inserted_count']})"
        )


# --------------------------------------------------------------------------- outlets


@dataclass(frozen=True)
class Outlet:
    """Deletes the particles whose centre lies inside a region, and counts them.

    The test runs inside ``sim.run`` every ``every`` steps (default: every step). It costs a
    few ns per particle, small next to the contact forces, and makes the removal time exact to
    one step; each removal triggers a neighbour-list rebuild, so with very high discharge
    rates ``every`` > 1 bounds the extra rebuilds. The schedule depends on the step counter
    only, never on how ``run`` is chunked.

    Args:
        region: ``gs.Box`` or a finite ``gs.geometry.Cylinder`` (may extend beyond the domain).
        every: steps between checks.
    """

    region: Region
    every: int = 1

    def __post_init__(self) -> None:
        _core_region(self.region, "Outlet")
        object.__setattr__(self, "every", _positive_int("Outlet", "every", self.every))

    def _add(self, sim: Simulation) -> OutletHandle:
        region = _core_region(self.region, "Outlet")
        lo, hi = (np.asarray(b, float) for b in region.bounds())
        domain = sim.domain
        if not (np.all(hi >= domain.lo) and np.all(lo <= domain.hi)):
            raise ValueError(
                f"Outlet.region must meet the simulation domain {span(domain.lo, domain.hi)}, "
                f"got a {type(self.region).__name__} with bounds {span(lo, hi)}, entirely "
                "outside it: the outlet could never remove a particle"
            )
        index = sim.engine.add_outlet(region, self.every)
        return OutletHandle(sim.engine, index, self)


class OutletHistory(NamedTuple):
    """Cumulative removal history: one entry at registration and one per removing check."""

    time: np.ndarray  # s
    mass: np.ndarray  # kg, cumulative
    number: np.ndarray  # cumulative number of particles


class OutletHandle:
    """Removal bookkeeping of a registered outlet."""

    def __init__(self, engine: Engine, index: int, outlet: Outlet) -> None:
        self._engine = engine
        self.index = index
        self.outlet = outlet

    @property
    def removed_count(self) -> int:
        """Number of particles removed so far."""
        return int(self._engine.outlet_status(self.index)["removed_count"])

    @property
    def removed_mass(self) -> float:
        """Mass removed so far (kg)."""
        return float(self._engine.outlet_status(self.index)["removed_mass"])

    @property
    def removed_moment(self) -> np.ndarray:
        """Sum of m x over the particles removed so far (kg m); their centre of mass is
        ``removed_moment / removed_mass``."""
        return np.asarray(self._engine.outlet_status(self.index)["removed_moment"], float)

    def history(self) -> OutletHistory:
        """(time s, cumulative mass kg, cumulative number) arrays; the discharge rate is the
        slope of mass over time (e.g. ``np.polyfit(time, mass, 1)[0]`` in kg/s)."""
        t, m, c = self._engine.outlet_history(self.index)
        return OutletHistory(np.asarray(t), np.asarray(m), np.asarray(c))

    def __repr__(self) -> str:
        return (
            f"OutletHandle(index={self.index}, removed_count={self.removed_count}, "
            f"removed_mass={self.removed_mass:.6g})"
        )
