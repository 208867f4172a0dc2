"""HDF5 checkpoints: save a simulation's state and continue it bit-identically.

A checkpoint holds the dynamic state — particles (in their current order, with forces),
contact histories and neighbour lists, wall positions, motion and servo state, insertion state,
step and time. The set-up (materials, contact law, walls, inserters, outputs) comes from the
script: build the simulation as before, then ``load(sim, path)`` instead of adding particles.

    gs.io.checkpoint.save(sim, "run.h5")
    ...
    sim = build()                      # the same set-up, no particles
    gs.io.checkpoint.load(sim, "run.h5")
    sim.run(steps=...)                 # identical to never having stopped
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

FORMAT = "grainscale-checkpoint"
VERSION = 1


def save(sim: Any, path: str | os.PathLike[str]) -> None:
    """Write the state of ``sim`` to the HDF5 file ``path`` (atomically)."""
    import h5py

    from .. import __version__

    state = sim._level.save_state()
    extra = sim._checkpoint_extra()
    tmp = os.fspath(path) + ".tmp"
    with h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["version"] = VERSION
        f.attrs["grainscale"] = __version__
        f.attrs["python_state"] = json.dumps(extra)
        for key, value in state.items():
            if key.startswith("texts/"):
                f.attrs[key] = value
            else:
                f.create_dataset(key, data=np.asarray(value))
    os.replace(tmp, path)


def load(sim: Any, path: str | os.PathLike[str]) -> None:
    """Restore the state saved in ``path`` into ``sim`` (which must have the same set-up).

    Raises:
        ValueError: the file is not a grainscale checkpoint, is corrupt, or was written for a
            different set-up (contact law, materials, walls, inserters).
    """
    import h5py

    try:
        f = h5py.File(os.fspath(path), "r")
    except OSError as err:
        raise ValueError(
            f"checkpoint.path must be a readable HDF5 file, got {path!r} ({err})"
        ) from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"checkpoint.path is not a grainscale checkpoint: {path!r}")
        if int(f.attrs.get("version", -1)) != VERSION:
            raise ValueError(
                f"checkpoint version must be {VERSION}, got {f.attrs.get('version')!r}"
            )
        state: dict[str, Any] = {}
        for key, value in f.attrs.items():
            if key.startswith("texts/"):
                state[key] = str(value)

        def visit(name: str, obj: Any) -> None:
            if isinstance(obj, h5py.Dataset):
                state[name] = obj[()]

        f.visititems(visit)
        extra = json.loads(f.attrs["python_state"])
    sim._restore_checkpoint_extra(extra)
    sim._level.load_state(state)
