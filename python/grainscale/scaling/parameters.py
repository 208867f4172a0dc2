"""The parameter set of one system (reference or scaled), and a Simulation built from it."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._validate import positive, vector3
from ..contact import EEPA, ContactLaw, HertzMindlin, Linear
from ..dist import Distribution, as_distribution
from ..geometry import Box, Cylinder, Mesh, Plane, Rectangle, Servo, Wall
from ..insert import Outlet, Pack, Stream
from ..materials import Material
from ..simulation import Simulation


@dataclass(frozen=True)
class Particles:
    """A group of particles of one material (SI units).

    Args:
        position: (N, 3) centres, m.
        radius: (N,) radii or one radius, m.
        material: their material.
        velocity: (N, 3) m/s or None (at rest).
        angular_velocity: (N, 3) rad/s or None.
    """

    position: np.ndarray
    radius: np.ndarray | float
    material: Material
    velocity: np.ndarray | None = None
    angular_velocity: np.ndarray | None = None

    def __post_init__(self) -> None:
        x = np.asarray(self.position, dtype=float).reshape(-1, 3)
        n = len(x)
        r = np.broadcast_to(np.asarray(self.radius, dtype=float), (n,)).copy()
        if not np.all(np.isfinite(x)):
            raise ValueError("Particles.position must be finite (m), got a non-finite value")
        if n and not (np.all(r > 0) and np.all(np.isfinite(r))):
            raise ValueError(
                f"Particles.radius must be positive and finite (m), got {float(r.min())!r}"
            )
        if not isinstance(self.material, Material):
            raise ValueError(f"Particles.material must be a Material, got {self.material!r}")
        object.__setattr__(self, "position", _frozen(x))
        object.__setattr__(self, "radius", _frozen(r))
        for name in ("velocity", "angular_velocity"):
            v = getattr(self, name)
            if v is not None:
                v = np.broadcast_to(np.asarray(v, dtype=float), (n, 3)).copy()
                if not np.all(np.isfinite(v)):
                    raise ValueError(f"Particles.{name} must be finite, got a non-finite value")
                object.__setattr__(self, name, _frozen(v))

    def __len__(self) -> int:
        return len(self.position)


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class ParameterSet:
    """Everything dimensional that defines a DEM system, in one frozen value (SI units).

    A reference set is mapped to a level's set by :func:`grainscale.scaling.scale`; nothing
    else changes parameters for coarse graining (the C++ core knows nothing of it).

    Args:
        domain: the simulation box.
        contact: contact law (HertzMindlin, Linear, EEPA, with rolling and per-pair entries).
        gravity: m/s^2.
        time_step: s, or None for the Simulation default (0.2 x the smallest Rayleigh time).
        skin: Verlet skin (m), or None for the default (0.1 x the largest diameter).
        walls: walls, in the order Simulation.add_wall indexes them.
        servos: wall index -> Servo for the walls under force/stress control.
        particles: particle groups with positions (only an exact scaling can map them).
        size: size distribution of particles still to insert (radius, m), or None.
        insertions: Pack and Stream operations, inserted / registered in order.
        outlets: Outlet operations.
        materials: further materials to register, in order.
    """

    domain: Box
    contact: ContactLaw = field(default_factory=HertzMindlin)
    gravity: tuple[float, float, float] = (0.0, 0.0, -9.81)
    time_step: float | None = None
    skin: float | None = None
    walls: Sequence[Wall] = ()
    servos: Mapping[int, Servo] = field(default_factory=dict)
    particles: Sequence[Particles] = ()
    size: Distribution | None = None
    insertions: Sequence[Pack | Stream] = ()
    outlets: Sequence[Outlet] = ()
    materials: Sequence[Material] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.domain, Box):
            raise ValueError(f"ParameterSet.domain must be a grainscale.Box, got {self.domain!r}")
        if not isinstance(self.contact, HertzMindlin | Linear | EEPA):
            raise ValueError(
                "ParameterSet.contact must be HertzMindlin, Linear or EEPA, "
                f"got {type(self.contact).__name__}"
            )
        object.__setattr__(self, "gravity", vector3("ParameterSet", "gravity", self.gravity))
        for name in ("time_step", "skin"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, positive("ParameterSet", name, getattr(self, name)))
        walls = tuple(self.walls)
        for w in walls:
            if not isinstance(w, Plane | Rectangle | Cylinder | Mesh):
                raise ValueError(
                    f"ParameterSet.walls must hold Plane, Rectangle, Cylinder or Mesh, got {w!r}"
                )
        servos = dict(self.servos)
        for k, s in servos.items():
            if not (isinstance(k, int) and 0 <= k < len(walls)) or not isinstance(s, Servo):
                raise ValueError(
                    f"ParameterSet.servos must map wall indices in [0, {len(walls)}) to Servo, "
                    f"got {k!r}: {s!r}"
                )
        particles = tuple(self.particles)
        for p in particles:
            if not isinstance(p, Particles):
                raise ValueError(f"ParameterSet.particles must hold Particles, got {p!r}")
        if self.size is not None:
            object.__setattr__(self, "size", as_distribution(self.size, "ParameterSet", "size"))
        for m in self.materials:
            if not isinstance(m, Material):
                raise ValueError(f"ParameterSet.materials must hold Material, got {m!r}")
        for op in self.insertions:
            if not isinstance(op, Pack | Stream):
                raise ValueError(f"ParameterSet.insertions must hold Pack or Stream, got {op!r}")
        for outlet in self.outlets:
            if not isinstance(outlet, Outlet):
                raise ValueError(f"ParameterSet.outlets must hold Outlet, got {outlet!r}")
        object.__setattr__(self, "insertions", tuple(self.insertions))
        object.__setattr__(self, "outlets", tuple(self.outlets))
        object.__setattr__(self, "walls", walls)
        object.__setattr__(self, "servos", servos)
        object.__setattr__(self, "particles", particles)
        object.__setattr__(self, "materials", tuple(self.materials))

    def all_materials(self) -> list[Material]:
        """Every material the set refers to, each once, in registration order (particles,
        walls, explicit materials, then those only named by per-pair entries)."""
        found: list[Material] = []
        candidates: list[Material | None] = [p.material for p in self.particles]
        candidates += [w.material for w in self.walls]
        candidates += [op.material for op in self.insertions]
        candidates += list(self.materials)
        candidates += [m for key in self.contact.pairs for m in key]
        for m in candidates:
            if m is not None and m not in found:
                found.append(m)
        return found


def build_simulation(params: ParameterSet, **options: Any) -> Simulation:
    """A Simulation set up from ``params``: domain, law, gravity, time step, skin, materials,
    walls with their servos, the particle groups (in order, so ids follow the groups), then the
    insertions (packs placed now, streams registered) and the outlets.

    Args:
        params: the parameter set.
        options: further Simulation arguments (force_time_step, thermo_every, quiet, ...).
    """
    if not isinstance(params, ParameterSet):
        raise ValueError(f"build_simulation.params must be a ParameterSet, got {params!r}")
    sim = Simulation(
        domain=params.domain,
        contact=params.contact,
        gravity=params.gravity,
        time_step=params.time_step,
        skin=params.skin,
        **options,
    )
    for m in params.all_materials():
        sim.material_index(m)
    for k, wall in enumerate(params.walls):
        sim.add_wall(wall, servo=params.servos.get(k))
    for group in params.particles:
        sim.add_particles(
            group.position,
            group.radius,
            group.material,
            velocity=group.velocity,
            angular_velocity=group.angular_velocity,
        )
    for op in params.insertions:
        sim.insert(op)
    for outlet in params.outlets:
        sim.add_outlet(outlet)
    return sim
