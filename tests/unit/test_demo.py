"""The demo (``make demo``, ``grainscale demo``: grainscale.examples.silo_demo, a silo whose
orifice jams coarse graining, pure CG and MLCG against the shipped resolved reference), the
pour-and-settle example (outputs exist and the bed settles) and the ``grainscale`` command."""

from __future__ import annotations

import base64
import dataclasses
import json
import math
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import grainscale as gs
from grainscale import cli
from grainscale.examples import hopper_demo, pour_and_settle, silo_demo, silo_reference

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
    assert ("build: native: " in text) or ("build: portable (" in text)


def test_build_info_says_native_or_portable(capsys: pytest.CaptureFixture[str]) -> None:
    """``_core.build_info()``: native (-march=native) or portable (x86-64-v2 on x86-64, no AVX);
    ``grainscale --version`` names it."""
    from grainscale import _core

    info = _core.build_info()
    assert info["mpi"] == _core.with_mpi()
    if info["native"]:
        assert (info["kind"], info["arch"]) == ("native", "native")
    else:
        assert info["kind"] == f"portable ({info['arch']})"
        assert not {"avx", "avx2", "fma", "avx512f"} & set(info["instruction_sets"])
    with pytest.raises(SystemExit):
        cli.main(["--version"])
    assert capsys.readouterr().out.strip() == f"grainscale {gs.__version__} ({cli.build_summary()})"


def test_cli_demo_is_the_silo_demo_and_hopper_the_hopper() -> None:
    """``grainscale demo`` takes the silo demo's options (``make demo`` runs it); ``grainscale
    hopper`` the hopper's."""
    parser = cli.build_parser()
    args = parser.parse_args(["demo", "--quick", "--full", "--seed", "3"])
    assert (args.quick, args.full, args.seed, args.no_vtk, args.func) == (
        True, True, 3, False, cli._demo,
    )  # fmt: skip
    assert args.output == "out/demo"
    assert "$(VENV)/bin/grainscale demo --output out/demo" in MAKEFILE.read_text()
    args = parser.parse_args(["hopper", "--quick", "--particles", "50", "--seed", "3"])
    case = hopper_demo.case_from_args(args)
    assert (case.particles, case.duration, case.seed) == (50, hopper_demo.QUICK_DURATION, 3)
    assert (args.output, args.func) == ("out/hopper", cli._hopper)


# ------------------------------------------------------------------------------------------
# the demo (make demo, grainscale demo): the silo whose orifice jams coarse graining
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def quick_silo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str, dict[str, Any]]:
    """Run ``grainscale demo --quick`` (what ``make demo`` runs, shorter) once; (output dir,
    stdout, summary.json)."""
    out = tmp_path_factory.mktemp("silo")
    proc = subprocess.run(
        [sys.executable, "-m", "grainscale.cli", "demo", "--quick", "--output", out],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout, json.loads((out / "summary.json").read_text())


def test_silo_demo_compares_with_the_shipped_reference(quick_silo) -> None:
    _, stdout, s = quick_silo
    ref = s["runs"]["reference"]
    assert s["reference"] == "reference" and not ref["live"]
    entry = silo_reference.load("quick", silo_demo.QUICK)
    assert entry is not None
    assert ref["rate"] == pytest.approx(entry["rate"])
    assert ref["rate"] > 0.015  # kg/s
    assert "silo_reference.json" in stdout


def test_silo_demo_pure_cg_jams_and_the_hierarchy_discharges(quick_silo) -> None:
    """Pure CG at h = 2 (3 parcels across the orifice) stops; the hierarchy runs near the
    resolved rate. One seed of this short run scatters by about 20 % (studies/mlcg_jam's
    reduced test), so the tolerance is loose; the full run's is in studies/mlcg_jam."""
    _, stdout, s = quick_silo
    assert s["errors"]["cg"] < -0.7
    assert abs(s["errors"]["mlcg"]) < 0.25
    # Pure CG clogs: over the last quarter of this short run it discharges less than a fifth of
    # the resolved rate. Arches of 3 parcels may break and form again: seed 1 of the quick run
    # stayed jammed with the contact arithmetic before issue 27's reciprocals and flows
    # intermittently with it (3.4 against 24.4 g/s); the full demo jams for good with both.
    cg = np.array(s["runs"]["cg"]["history"])
    last_quarter = cg[:, 0] >= 0.75 * cg[-1, 0]
    end_rate = np.ptp(cg[last_quarter, 1]) / np.ptp(cg[last_quarter, 0])  # kg/s
    assert end_rate < 0.2 * s["runs"]["reference"]["rate"]
    assert "pure CG, h = 2" in stdout
    mlcg = s["runs"]["mlcg"]
    assert len(mlcg["particles"]) == 2 and all(n > 0 for n in mlcg["particles"])
    assert sum(mlcg["particles"]) < 0.5 * s["runs"]["reference"]["particles"][0]
    if not gs._core.build_info()["sanitized"]:  # instrumented code is several times slower
        assert s["speed_up"] > 1


def test_silo_demo_books_close(quick_silo) -> None:
    _, stdout, s = quick_silo
    mlcg = s["runs"]["mlcg"]
    books = mlcg["mass_balance"]
    assert books["inserted"] == pytest.approx(silo_demo.QUICK.fill_mass, rel=0.01)
    assert abs(books["unaccounted"]) < 1e-12 * books["inserted"]
    assert mlcg["max_unaccounted"] < 1e-12
    assert books["discharged"] == pytest.approx(mlcg["history"][-1][1], rel=1e-12)
    assert "unaccounted mass" in stdout


def _level_field(vtp: Path) -> np.ndarray:
    """The int32 ``level`` point array of a base64-encoded .vtp file."""
    root = ET.parse(vtp).getroot()
    (da,) = [a for a in root.iter("DataArray") if a.get("Name") == "level"]
    assert da.get("type") == "Int32"
    raw = base64.b64decode("".join((da.text or "").split()))
    return np.frombuffer(raw[8:], dtype="<i4")


def test_silo_demo_writes_plots_vtk_and_summary(quick_silo) -> None:
    out, stdout, s = quick_silo
    for name in ("discharge.png", "levels.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "summary.txt").read_text() in stdout
    assert s["case"]["seed"] == 1
    for k in (0, 1):  # every level's own series carries its level
        files = [d.get("file") for d in ET.parse(out / f"level{k}.pvd").getroot().iter("DataSet")]
        assert len(files) >= 2
        assert set(_level_field(out / files[-1])) == {k}
    files = [d.get("file") for d in ET.parse(out / "levels.pvd").getroot().iter("DataSet")]
    assert len(files) >= 2
    assert set(_level_field(out / files[-1])) == {0, 1}  # both levels, each where it is finest
    assert (out / "cells0.pvd").is_file()


def test_shipped_reference_has_its_provenance() -> None:
    for name, case in (("default", silo_demo.JAM), ("quick", silo_demo.QUICK)):
        entry = silo_reference.load(name, case)
        assert entry is not None, name
        assert entry["rate"] == pytest.approx(np.mean(entry["rates"]))
        assert len(entry["rates"]) == len(entry["seeds"]) >= 3
        m = np.array(entry["history"])[:, 1]
        assert np.all(np.diff(m) >= 0) and m[-1] > 0
        for step in entry["provenance"]:
            assert {"what", "command", "commit", "date"} <= set(step)
    # the default case's seed 1 was rerun by the demo's code and gave the study's discharge
    default = silo_reference.load("default", silo_demo.JAM)
    assert default is not None
    assert any(step.get("history_identical") for step in default["provenance"])
    # a changed case has no reference
    other = dataclasses.replace(silo_demo.JAM, orifice=0.014)
    assert silo_reference.load("default", other) is None
    assert silo_demo.load_reference("default", other) is None
