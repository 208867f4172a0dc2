"""Optional dependencies, imported where a feature needs them: mpi4py for runs under mpirun
(extra ``mpi``), matplotlib for the plots of the demo and examples (extra ``plot``). A serial
run without plots needs neither; a feature that does names the extra to install."""

from __future__ import annotations

import importlib
from typing import Any


def require(module: str, extra: str, feature: str) -> Any:
    """``module`` imported, or ImportError naming the feature and the extra that provides it."""
    try:
        return importlib.import_module(module)
    except ImportError as err:
        raise ImportError(
            f"{feature} needs {module.split('.')[0]}, which is not installed: "
            f"pip install 'grainscale[{extra}]' (or pip install {module.split('.')[0]})"
        ) from err


def mpi() -> Any:
    """mpi4py.MPI (extra ``mpi``)."""
    return require("mpi4py.MPI", "mpi", "running under mpirun")


def pyplot() -> Any:
    """matplotlib.pyplot with the file-only Agg backend (extra ``plot``)."""
    matplotlib = require("matplotlib", "plot", "plotting")
    matplotlib.use("Agg")
    return require("matplotlib.pyplot", "plot", "plotting")
