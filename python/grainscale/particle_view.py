"""ParticleView: zero-copy numpy views of a level's owned particles, handed out by
``Simulation.particles()``, and the names of the per-particle fields."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from . import _core, parallel

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
        for a in self._arrays.values():  # the arrays handed out cannot be written any more
            a.flags.writeable = False
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


class WriteWatch:
    """Catches writes to the particle arrays after their ``with sim.particles()`` block ended
    (through a slice or copy-free view the block handed out): the engine would not see them.
    Armed at the end of a writable block with digests of the writable fields, checked before the
    engine next touches the particles (run, particles, checkpoint); a difference raises a
    RuntimeError on every rank, after telling the engine of the change."""

    def __init__(self) -> None:
        self._digests: dict[str, str] | None = None

    @staticmethod
    def _digest(level: _core.Level) -> dict[str, str]:
        return {
            f: hashlib.blake2b(np.ascontiguousarray(level.view(f)).tobytes()).hexdigest()
            for f in WRITABLE_FIELDS
        }

    def arm(self, level: _core.Level) -> None:
        self._digests = self._digest(level)

    def check(self, level: _core.Level, comm: Any) -> None:
        if self._digests is None:
            return
        before, self._digests = self._digests, None
        now = self._digest(level)
        changed = [f for f in WRITABLE_FIELDS if now[f] != before[f]]
        error = None
        if changed:
            if "position" in changed:
                level.mark_positions_changed()
            else:
                level.mark_velocities_changed()
            error = RuntimeError(
                f"particle array(s) {', '.join(changed)} were written after their 'with "
                "sim.particles()' block ended; the engine has now taken the change, but write "
                "inside the block (arrays from it are valid only there)"
            )
        parallel.agree(comm, error)
