"""mpi4py and matplotlib are extras (issue 26): a serial run imports neither, and a feature that
needs a missing one names the extra to install."""

from __future__ import annotations

import subprocess
import sys

import pytest

from grainscale._optional import require


def test_a_missing_module_names_the_feature_and_the_extra() -> None:
    with pytest.raises(ImportError, match=r"plotting needs no_such_plotter.*grainscale\[plot\]"):
        require("no_such_plotter.pyplot", "plot", "plotting")


def test_a_serial_run_imports_neither_mpi4py_nor_matplotlib() -> None:
    code = (
        "import sys, numpy as np, grainscale as gs\n"
        "glass = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)\n"
        "sim = gs.Simulation(domain=gs.Box((0, 0, 0), (0.01, 0.01, 0.01)), quiet=True)\n"
        "sim.add_particles(position=[[0.005, 0.005, 0.005]], radius=1e-3, material=glass)\n"
        "sim.run(steps=10)\n"
        "print(sorted(m for m in ('mpi4py', 'matplotlib') if m in sys.modules))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
