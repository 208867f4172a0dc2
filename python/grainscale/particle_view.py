"""ParticleView: zero-copy numpy views of a level's owned particles, handed out by
``Simulation.particles()``, and the names of the per-particle fields."""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from . import _core, parallel
from ._validate import real_array

VECTOR_FIELDS = ("position", "velocity", "angular_velocity", "force", "torque")
SCALAR_FIELDS = ("radius", "mass", "id", "material")
WRITABLE_FIELDS = ("position", "velocity", "angular_velocity")


class ParticleArray(np.ndarray):
    """A particle array handed out by :class:`ParticleView`: a zero-copy ndarray view of the
    engine's memory (a plain ndarray in every other respect) whose refused writes say why: the
    field is read-only, the block was opened with ``writable=False``, or its block has ended.
    Assignment (``a[...] = v``), the in-place operators (``a += v``) and ``fill`` are covered;
    other writes (a ufunc's ``out=``) keep numpy's own "read-only" error."""

    # (field, the view that handed it out): set on the arrays handed out only. A slice of one
    # finds it through ``base`` (no __array_finalize__: slicing stays at numpy's speed).
    _origin: tuple[str, ParticleView] | None = None

    def _refusal(self) -> ValueError | None:
        if self.flags.writeable:
            return None
        array: Any = self
        while isinstance(array, np.ndarray):
            origin = getattr(array, "_origin", None)
            if origin is not None:
                field, view = origin
                return ValueError(view._why_read_only(field))
            array = array.base
        return None

    def __setitem__(self, key: Any, value: Any) -> None:
        try:
            super().__setitem__(key, value)
        except ValueError:
            refusal = self._refusal()
            if refusal is None:
                raise
            raise refusal from None

    def fill(self, value: Any) -> None:
        refusal = self._refusal()
        if refusal is not None:
            raise refusal
        super().fill(value)

    def __repr__(self) -> str:
        return repr(self.view(np.ndarray))


def _in_place(name: str) -> Any:
    plain = getattr(np.ndarray, name)

    def method(self: ParticleArray, other: Any) -> Any:
        refusal = self._refusal()
        if refusal is not None:
            raise refusal
        return plain(self, other)

    method.__name__ = name
    return method


for _op in ("add", "sub", "mul", "truediv", "floordiv", "mod", "pow", "matmul", "lshift",
            "rshift", "and", "or", "xor"):  # fmt: skip
    setattr(ParticleArray, f"__i{_op}__", _in_place(f"__i{_op}__"))


def _field(name: str) -> property:
    """The property of one field: reading hands out the array; assigning copies values in."""

    def get(self: ParticleView) -> ParticleArray:
        return self._get(name)

    def put(self: ParticleView, value: Any) -> None:
        self._set(name, value)

    return property(get, put, doc=f"The particles' {name} (zero-copy).")


class ParticleView:
    """Zero-copy numpy views of the owned particles, valid only inside ``Simulation.particles()``.

    Attributes (all SI): position, velocity, angular_velocity (N, 3) — writable when the view
    is; force, torque (N, 3) of the last evaluation (force includes gravity); radius, mass (N,);
    id (N,) int64 global ids; material (N,) int32 material index. Particle order may change
    between runs (spatial sorting): identify particles by ``id``.

    Write into the arrays (``p.velocity[:, 2] = 0``, ``p.position += dx``) or assign a whole
    field: ``p.velocity = v`` copies ``v`` ((N, 3), or (3,) for every particle; finite real
    numbers) into the engine's array, as ``p.velocity[...] = v`` would. A refused write (a
    read-only field, a block opened with ``writable=False``, an array kept after its block)
    raises ValueError saying which and why.
    """

    __slots__ = ("_level", "_writable", "_arrays", "_valid")

    def __init__(self, level: _core.Level, writable: bool) -> None:
        self._level = level
        self._writable = writable
        self._arrays: dict[str, ParticleArray] = {}
        self._valid = True

    def _get(self, name: str) -> ParticleArray:
        if not self._valid:
            raise RuntimeError(
                f"particle array '{name}' used outside its 'with sim.particles()' block"
            )
        a = self._arrays.get(name)
        if a is None:
            a = self._level.view(name).view(ParticleArray)
            a._origin = (name, self)
            if not (self._writable and name in WRITABLE_FIELDS):
                a.flags.writeable = False
            self._arrays[name] = a
        return a

    def _set(self, name: str, value: Any) -> None:
        """``p.<name> = value``: copies the values into the engine's array (see the class)."""
        a = self._get(name)
        if not a.flags.writeable:
            raise ValueError(self._why_read_only(name))
        a[...] = real_array("ParticleView", name, value, (3,), (len(a), 3))

    def _why_read_only(self, name: str) -> str:
        """Why the array of field ``name`` cannot be written."""
        if not self._valid:
            return (
                f"ParticleView.{name} is read-only: its 'with sim.particles()' block has ended "
                "(arrays from a block are valid only inside it); write inside a new block"
            )
        if name not in WRITABLE_FIELDS:
            return (
                f"ParticleView.{name} is read-only: only {', '.join(WRITABLE_FIELDS)} can be "
                "written (radius, mass, id and material are fixed when a particle is added; "
                "force and torque are computed at each step)"
            )
        return (
            f"ParticleView.{name} is read-only: the block was opened with "
            "sim.particles(writable=False); open it with writable=True to write"
        )

    def _close(self) -> None:
        self._valid = False
        for a in self._arrays.values():  # the arrays handed out cannot be written any more
            a.flags.writeable = False
        self._arrays.clear()

    def __len__(self) -> int:
        return int(self._level.num_owned)

    position = _field("position")
    velocity = _field("velocity")
    angular_velocity = _field("angular_velocity")
    force = _field("force")
    torque = _field("torque")
    radius = _field("radius")
    mass = _field("mass")
    id = _field("id")
    material = _field("material")


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
