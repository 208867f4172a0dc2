"""Simulation's checkpoints: save and restart (the HDF5 format is grainscale.io.checkpoint), and
the Python-side state a checkpoint carries beside the C++ level's. A mixin of
:class:`grainscale.simulation.Simulation`, which holds that state."""

from __future__ import annotations

import dataclasses
import os
from typing import TYPE_CHECKING, Any

from . import _core
from .materials import Material


class CheckpointMethods:
    """The checkpoint methods of a Simulation (see the module docstring)."""

    _level: _core.Level
    _time_step: float | None
    _force_time_step: bool
    _skin_fixed: bool
    _wall_spin: dict[int, tuple[float, float, float]]
    _materials: list[Material]

    if TYPE_CHECKING:

        def material_index(self, material: Material) -> int: ...

        def _push_interactions(self) -> None: ...

    def checkpoint(self, path: str | os.PathLike[str]) -> None:
        """Save the state to an HDF5 checkpoint (see grainscale.io.checkpoint)."""
        from .io import checkpoint

        checkpoint.save(self, path)

    def restart(self, path: str | os.PathLike[str]) -> None:
        """Continue from a checkpoint written by a simulation with the same set-up."""
        from .io import checkpoint

        checkpoint.load(self, path)

    def _checkpoint_extra(self) -> dict[str, Any]:
        return {
            "time_step": self._time_step,
            "skin_fixed": self._skin_fixed,
            "wall_spin": {str(k): list(v) for k, v in self._wall_spin.items()},
            "materials": [dataclasses.asdict(m) for m in self._materials],
        }

    def _restore_checkpoint_extra(self, extra: dict[str, Any]) -> None:
        # Materials the set-up has not registered yet (those only particles use) are registered
        # in the saved order; a different order is a different set-up.
        for k, fields_ in enumerate(extra.get("materials", [])):
            material = Material(**fields_)
            if k < len(self._materials) and self._materials[k] != material:
                raise ValueError(
                    f"checkpoint material {k} is {material}, this simulation has "
                    f"{self._materials[k]}: the set-up differs"
                )
            self.material_index(material)
        self._push_interactions()
        if extra.get("time_step") is not None:
            self._time_step = float(extra["time_step"])
            self._level.set_time_step(self._time_step, self._force_time_step)
        self._skin_fixed = bool(extra.get("skin_fixed", True))
        self._wall_spin = {int(k): tuple(v) for k, v in extra.get("wall_spin", {}).items()}
