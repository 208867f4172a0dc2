"""Simulation's checkpoints: save and restart (the HDF5 format is grainscale.io.checkpoint), and
the Python-side state a checkpoint carries beside the C++ level's. A mixin of
:class:`grainscale.simulation.Simulation`, which holds that state."""

from __future__ import annotations

import dataclasses
import hashlib
import os
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _core, parallel
from .materials import Material


def _plain(value: Any) -> str:
    """A parameter value as text that does not depend on how it was given (bool or numpy bool,
    int or float, tuple or list); arrays by their shape and SHA-256."""
    if isinstance(value, np.ndarray):
        a = np.ascontiguousarray(value)
        return f"<{a.dtype.str}{list(a.shape)} sha256 {hashlib.sha256(a.tobytes()).hexdigest()}>"
    if isinstance(value, bool | np.bool_):
        return repr(bool(value))
    if isinstance(value, int | float | np.integer | np.floating):
        return repr(float(value))
    if isinstance(value, tuple | list):
        return "(" + ", ".join(_plain(v) for v in value) + ")"
    return repr(value)


def geometry_record(geometry: Any, materials: list[Material] | None = None) -> str:
    """A wall's or a region's geometry as constructed (its type and parameters), as the text a
    restart compares (a plane's normal normalised). Motion (velocity, angular_velocity) is left
    out: it is state, which the checkpoint restores; a wall's material is given by its index in
    ``materials``."""
    parts = []
    for field in dataclasses.fields(geometry):
        if field.name in ("velocity", "angular_velocity"):
            continue
        value = getattr(geometry, field.name)
        if field.name == "normal":  # a plane's, normalised by the core
            value = tuple(float(v) for v in np.divide(value, np.linalg.norm(value)))
        if field.name == "material":
            if materials is None:
                continue
            index = next((k for k, m in enumerate(materials) if m == value), None)
            parts.append(f"material={'rigid' if value is None else index}")
        else:
            parts.append(f"{field.name}={_plain(value)}")
    return f"{type(geometry).__name__}({', '.join(parts)})"


class CheckpointMethods:
    """The checkpoint methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _time_step: float | None
    _force_time_step: bool
    _skin_fixed: bool
    _wall_spin: dict[int, tuple[float, float, float]]
    _walls: list[Any]  # WallHandle
    _materials: list[Material]
    engine: Any
    domain: Any
    contact: Any

    if TYPE_CHECKING:

        @property
        def comm(self) -> Any: ...  # Simulation's property

        def material_index(self, material: Material) -> int: ...

        def _push_interactions(self) -> None: ...

    def checkpoint(self, path: str | os.PathLike[str]) -> None:
        """Save the state to an HDF5 checkpoint (see grainscale.io.checkpoint). Before the
        first run, the time step and skin not given are chosen first, as ``run`` would (from
        the particles and streams present), so that a restart continues exactly.

        Raises:
            ValueError: the file cannot be written (naming the path; the OSError is its
                cause), or no time step can be chosen yet (no particles, no streams).
        """
        from .io import checkpoint

        parallel.same_arguments(self.comm, "Simulation.checkpoint", path=os.fspath(path))
        self.engine.check_unseen_writes()
        checkpoint.save(self, path)

    def restart(self, path: str | os.PathLike[str]) -> None:
        """Continue from a checkpoint written by a simulation with the same set-up.

        Build the simulation as for the run that wrote the file — domain, dimension, contact
        law, materials, walls (their geometry as constructed), inserters — and restart it
        instead of adding particles. The restart replaces the whole state: the particles (those
        added before the restart are dropped, with a UserWarning giving their count), step and
        time, the time step and skin, the walls' positions and motion (velocity, spin, servo
        state: a moving wall continues where it was) and the inserters' state.

        Raises:
            ValueError: naming the file: not a grainscale checkpoint, damaged, a hierarchy's
                checkpoint (use Hierarchy.restart), or written for another set-up (naming what
                differs). Nothing changes then.
        """
        from .io import checkpoint

        parallel.same_arguments(self.comm, "Simulation.restart", path=os.fspath(path))
        self.engine.check_unseen_writes()
        held = int(self._level.global_count())
        checkpoint.load(self, path)
        loaded = int(self._level.global_count())  # collective, as held
        if held > 0:
            warnings.warn(
                f"Simulation.restart replaced the {held} particle(s) this simulation held with "
                f"the {loaded} of the checkpoint {os.fspath(path)!r} (a restart replaces the "
                "whole state: add particles after it)",
                UserWarning,
                stacklevel=2,
            )

    def _setup_record(self) -> dict[str, Any]:
        """What a restart compares with the simulation it loads into (beyond the core's
        signature): the domain, the dimension, the contact law with its parameters and every
        wall's geometry as constructed (geometry_record)."""
        d = self.domain
        return {
            "domain": [list(map(float, d.lo)), list(map(float, d.hi)), list(map(bool, d.periodic))],
            "dimension": int(self._level.dimension),
            "contact": repr(self.contact),
            "walls": [geometry_record(w.geometry, self._materials) for w in self._walls],
        }

    def _check_checkpoint_extra(self, extra: dict[str, Any]) -> None:
        """Refuses a checkpoint written for another set-up (before anything changes); a file
        written before the set-up was recorded is checked by the core's signature only."""
        self._saved_materials(extra)
        saved = extra.get("setup")
        if saved is None:
            return
        here = self._setup_record()
        names = {
            "domain": "domain [lo, hi, periodic]",
            "dimension": "dimension",
            "contact": "contact law",
        }
        for key, name in names.items():
            if saved.get(key) != here[key]:
                raise ValueError(
                    f"checkpoint was written for the {name} {saved.get(key)!r}, this simulation's "
                    f"is {here[key]!r}"
                )
        walls = saved.get("walls")  # None: written before the walls were recorded
        if walls is None:
            return
        if len(walls) != len(here["walls"]):
            raise ValueError(
                f"checkpoint was written for {len(walls)} walls, this simulation has "
                f"{len(here['walls'])}"
            )
        for k, (theirs, mine) in enumerate(zip(walls, here["walls"], strict=True)):
            if theirs != mine:
                raise ValueError(
                    f"checkpoint wall {k} was set up as {theirs}, this simulation's wall {k} is "
                    f"{mine}: the set-up differs (a wall's geometry as constructed must match; "
                    "its position and motion are then restored from the checkpoint)"
                )

    def _saved_materials(self, extra: dict[str, Any]) -> list[Material]:
        """The checkpoint's materials, in order; ValueError where one differs from the material
        this simulation registered at that index (a different order is a different set-up)."""
        saved = [Material(**fields_) for fields_ in extra.get("materials", [])]
        for k, (mine, theirs) in enumerate(zip(self._materials, saved, strict=False)):
            if mine != theirs:
                raise ValueError(
                    f"checkpoint material {k} is {theirs}, this simulation has {mine}: the set-up "
                    "differs"
                )
        return saved

    def _checkpoint_extra(self) -> dict[str, Any]:
        return {
            "setup": self._setup_record(),
            "time_step": self._time_step,
            "skin_fixed": self._skin_fixed,
            "wall_spin": {str(k): list(v) for k, v in self._wall_spin.items()},
            "materials": [dataclasses.asdict(m) for m in self._materials],
        }

    def _restore_checkpoint_extra(self, extra: dict[str, Any]) -> None:
        # Materials the set-up has not registered yet (those only particles use) are registered
        # in the saved order.
        for material in self._saved_materials(extra):
            self.material_index(material)
        self._push_interactions()
        if extra.get("time_step") is not None:
            saved = float(extra["time_step"])
            if self._time_step is not None and self._time_step != saved:
                warnings.warn(
                    f"restart: the checkpoint's time step {saved:g} s replaces the time step "
                    f"{self._time_step:g} s set on this simulation (set it again after the "
                    "restart to change it)",
                    stacklevel=4,
                )
            self._time_step = saved
            self._level.set_time_step(self._time_step, self._force_time_step)
        self._skin_fixed = bool(extra.get("skin_fixed", True))
        self._wall_spin = {int(k): tuple(v) for k, v in extra.get("wall_spin", {}).items()}
