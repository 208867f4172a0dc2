"""Simulation's checkpoints: save and restart (the HDF5 format is grainscale.io.checkpoint), and
the Python-side state a checkpoint carries beside the C++ level's. A mixin of
:class:`grainscale.simulation.Simulation`, which holds that state."""

from __future__ import annotations

import dataclasses
import os
import warnings
from typing import TYPE_CHECKING, Any

from . import _core, parallel
from .materials import Material


class CheckpointMethods:
    """The checkpoint methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _time_step: float | None
    _force_time_step: bool
    _skin_fixed: bool
    _wall_spin: dict[int, tuple[float, float, float]]
    _materials: list[Material]
    comm: Any
    engine: Any
    domain: Any
    contact: Any

    if TYPE_CHECKING:

        def material_index(self, material: Material) -> int: ...

        def _push_interactions(self) -> None: ...

    def checkpoint(self, path: str | os.PathLike[str]) -> None:
        """Save the state to an HDF5 checkpoint (see grainscale.io.checkpoint)."""
        from .io import checkpoint

        parallel.same_arguments(self.comm, "Simulation.checkpoint", path=os.fspath(path))
        self.engine.check_unseen_writes()
        checkpoint.save(self, path)

    def restart(self, path: str | os.PathLike[str]) -> None:
        """Continue from a checkpoint written by a simulation with the same set-up."""
        from .io import checkpoint

        parallel.same_arguments(self.comm, "Simulation.restart", path=os.fspath(path))
        self.engine.check_unseen_writes()
        checkpoint.load(self, path)

    def _setup_record(self) -> dict[str, Any]:
        """What a restart compares with the simulation it loads into (beyond the core's
        signature): the domain, the dimension and the contact law with its parameters."""
        d = self.domain
        return {
            "domain": [list(map(float, d.lo)), list(map(float, d.hi)), list(map(bool, d.periodic))],
            "dimension": int(self._level.dimension),
            "contact": repr(self.contact),
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
