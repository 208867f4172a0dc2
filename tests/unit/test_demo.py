"""The pour-and-settle example (outputs exist and the bed settles) and the ``grainscale``
command."""

from __future__ import annotations

import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs
from grainscale import cli
from grainscale.examples import hopper_demo, pour_and_settle

MAKEFILE = Path(__file__).resolve().parents[2] / "Makefile"


@pytest.fixture(scope="module")
def quick_demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """Run ``python -m grainscale.examples.pour_and_settle --quick`` once; (output dir, stdout)."""
    out = tmp_path_factory.mktemp("demo")
    proc = subprocess.run(
        [sys.executable, "-m", "grainscale.examples.pour_and_settle", "--quick", "--output", out],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout


def test_demo_writes_paraview_files(quick_demo: tuple[Path, str]) -> None:
    out, _ = quick_demo
    pvd = out / "particles.pvd"
    assert pvd.is_file()
    files = [d.get("file") for d in ET.parse(pvd).getroot().iter("DataSet")]
    assert len(files) >= 2
    assert all((out / f).is_file() for f in files)
    assert len(list(out.glob("particles_*.vtp"))) >= 2
    root = ET.parse(out / files[-1]).getroot()
    assert root.get("type") == "PolyData"
    assert int(root.find("PolyData/Piece").get("NumberOfPoints")) == 400
    assert (out / "box.vtp").is_file()


def test_demo_prints_the_settled_bed(quick_demo: tuple[Path, str]) -> None:
    out, stdout = quick_demo
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    line = stdout.strip().splitlines()[-1]
    assert line.startswith("settled bed: height")
    assert f"packing fraction {hist['packing_fraction'][-1]:.3f}" in line
    assert str(out / "particles.pvd") in line


def test_demo_bed_settles(quick_demo: tuple[Path, str]) -> None:
    out, _ = quick_demo
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    ke = hist["kinetic_energy_J"]
    assert hist["time_s"][-1] == pytest.approx(pour_and_settle.QUICK_DURATION, abs=1e-4)
    assert ke.max() > 0
    assert ke[-1] < 1e-3 * ke.max()
    phi = hist["packing_fraction"][-1]
    assert 0.45 < phi < 0.66
    # the bed has stopped compacting: the last 20 % of the run changes phi by < 1 %
    late = hist["packing_fraction"][hist["time_s"] > 0.8 * hist["time_s"][-1]]
    assert np.ptp(late) < 0.01 * phi


def test_packing_fraction_of_a_simple_cubic_lattice() -> None:
    # 5 x 5 x 4 spheres of diameter d touching on a cubic lattice fill a 5d x 5d x 4d box:
    # bed height 4d and packing fraction pi/6.
    d = 2e-3
    box = gs.Box(lo=(0, 0, 0), hi=(5 * d, 5 * d, 20 * d))
    pos = gs.insert.lattice(gs.Box(lo=(0, 0, 0), hi=(5 * d, 5 * d, 4 * d)), spacing=d)
    radius = np.full(len(pos), d / 2)
    height = pour_and_settle.bed_height(pos, radius, box, column=d)
    assert height == pytest.approx(4 * d)
    volume = float(np.sum(4 / 3 * math.pi * radius**3))
    assert pour_and_settle.packing_fraction(volume, box, height) == pytest.approx(math.pi / 6)


def test_cli_info(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["info"]) == 0
    text = capsys.readouterr().out
    assert f"grainscale {gs.__version__}" in text
    assert ("serial build" in text) or ("built with MPI" in text)


def test_cli_demo_is_the_hopper_demo() -> None:
    """``grainscale demo`` takes the hopper demo's options (``make demo`` runs it)."""
    args = cli.build_parser().parse_args(["demo", "--quick", "--particles", "50", "--seed", "3"])
    case = hopper_demo.case_from_args(args)
    assert (case.particles, case.duration, case.seed) == (50, hopper_demo.QUICK_DURATION, 3)
    assert args.output == "out/demo"
    assert "$(VENV)/bin/grainscale demo --output out/demo" in MAKEFILE.read_text()
