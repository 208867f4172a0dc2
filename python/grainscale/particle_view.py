"""ParticleView: zero-copy numpy views of a level's owned particles, handed out by
``Simulation.particles()``, and the names of the per-particle fields."""

from __future__ import annotations

import numpy as np

from . import _core

VECTOR_FIELDS = ("position", "velocity", "angular_velocity", "force", "torque")
SCALAR_FIELDS = ("radius", "mass", "id", "material")
WRITABLE_FIELDS = ("position", "velocity", "angular_velocity")


class ParticleView:
    """Zero-copy numpy views of the owned particles, valid only inside ``Simulation.particles()``.

    Attributes (all SI): position, velocity, angular_velocity (N, 3) — writable when the view
    is; force, torque (N, 3) of the last evaluation (force includes gravity); radius, mass (N,);
    id (N,) int64 global ids; material (N,) int32 material index. Particle order may change
    between runs (spatial sorting): identify particles by ``id``.
    """

    def __init__(self, level: _core.Level, writable: bool) -> None:
        self._level = level
        self._writable = writable
        self._arrays: dict[str, np.ndarray] = {}
        self._valid = True

    def _get(self, name: str) -> np.ndarray:
        if not self._valid:
            raise RuntimeError(
                f"particle array '{name}' used outside its 'with sim.particles()' block"
            )
        a = self._arrays.get(name)
        if a is None:
            a = self._level.view(name)
            if not (self._writable and name in WRITABLE_FIELDS):
                a.flags.writeable = False
            self._arrays[name] = a
        return a

    def _close(self) -> None:
        self._valid = False
        self._arrays.clear()

    def __len__(self) -> int:
        return int(self._level.num_owned)

    position = property(lambda self: self._get("position"))
    velocity = property(lambda self: self._get("velocity"))
    angular_velocity = property(lambda self: self._get("angular_velocity"))
    force = property(lambda self: self._get("force"))
    torque = property(lambda self: self._get("torque"))
    radius = property(lambda self: self._get("radius"))
    mass = property(lambda self: self._get("mass"))
    id = property(lambda self: self._get("id"))
    material = property(lambda self: self._get("material"))
