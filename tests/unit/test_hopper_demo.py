"""The hopper example (``grainscale hopper``, grainscale.examples.hopper_demo): STL hopper,
poured fill, discharge; its files and physics."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from test_vtk import read_vtp

import grainscale as gs
from grainscale import cli
from grainscale.examples import hopper_demo, hopper_geometry, pour_and_settle


@pytest.fixture(scope="module")
def quick_hopper(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """Run ``grainscale hopper --quick`` once; (output dir, stdout)."""
    out = tmp_path_factory.mktemp("hopper")
    proc = subprocess.run(
        [sys.executable, "-m", "grainscale.cli", "hopper", "--quick", "--output", out],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    return out, proc.stdout


def _datasets(pvd: Path) -> list[str]:
    return [d.get("file") for d in ET.parse(pvd).getroot().iter("DataSet")]


def test_hopper_demo_writes_paraview_files(quick_hopper: tuple[Path, str]) -> None:
    out, _ = quick_hopper
    files = _datasets(out / "particles.pvd")
    assert len(files) >= 2
    assert all((out / f).is_file() for f in files)
    first = ET.parse(out / files[0]).getroot()
    assert first.get("type") == "PolyData"
    # the hopper and the gate: one snapshot before the gate moves, more while it slides away
    walls = _datasets(out / "particles_walls.pvd")
    assert len(walls) >= 2
    assert all((out / f).is_file() for f in walls)
    piece = ET.parse(out / walls[0]).getroot().find("PolyData/Piece")
    hopper = gs.geometry.Mesh.from_stl(out / "hopper.stl")
    counts = np.bincount(read_vtp(out / walls[0])["CellData"]["wall"])
    # every wall is drawn: the hopper's triangles, the gate's two, two per box plane
    assert len(hopper.triangles) in counts.tolist() and np.all(counts > 0)
    assert int(piece.get("NumberOfPolys")) == counts.sum() > len(hopper.triangles) + 2
    assert (out / "bin.vtp").is_file()


def test_hopper_demo_writes_plot_summary_history(quick_hopper: tuple[Path, str]) -> None:
    out, stdout = quick_hopper
    assert (out / "hopper.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summary = (out / "summary.md").read_text()
    for text in ("hopper.stl read with gs.geometry.Mesh.from_stl", "discharge rate", "wall-clock"):
        assert text in summary
    assert "(lost: 0)" in summary
    assert summary in stdout
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    assert hist["time_s"][-1] == pytest.approx(hopper_demo.QUICK_DURATION, abs=1e-3)


def test_hopper_demo_particles_flow_out(quick_hopper: tuple[Path, str]) -> None:
    out, _ = quick_hopper
    hist = np.genfromtxt(out / "history.csv", delimiter=",", names=True)
    total = hist["hopper_count"] + hist["discharged_count"]
    inserted = int(total[-1])
    assert inserted == pytest.approx(hopper_demo.QUICK_PARTICLES, abs=2)
    # nothing is lost once the pour is over: every particle is in the hopper or below it
    assert np.all(total[np.argmax(total == inserted) :] == inserted)
    # the hopper filled with the gate closed, then emptied through its outlet
    full = int(np.nonzero(hist["discharged_count"] == 0)[0][-1])  # just before the gate opened
    assert hist["hopper_count"][full] == inserted
    assert hist["discharged_count"][full] == 0
    assert hist["discharged_count"][-1] > 0.9 * inserted
    assert hist["discharged_mass_kg"][-1] > 0.9 * (
        hist["hopper_mass_kg"][full] + hist["discharged_mass_kg"][full]
    )
    # the hopper wall carried part of the weight of the filled hopper, and none once empty
    weight = 9.81 * hist["hopper_mass_kg"][full]
    assert 0.1 * weight < hist["hopper_wall_load_N"][full] < weight
    assert abs(hist["hopper_wall_load_N"][-1]) < 0.05 * weight


def test_packaged_stl_is_the_generated_hopper(tmp_path: Path) -> None:
    packaged = gs.geometry.Mesh.from_stl(hopper_geometry.PACKAGED_STL)
    written = gs.geometry.Mesh.from_stl(hopper_geometry.write_hopper_stl(tmp_path / "h.stl"))
    assert np.array_equal(packaged.vertices, written.vertices)
    assert np.array_equal(packaged.triangles, written.triangles)
    assert hopper_geometry.PACKAGED_STL.stat().st_size < 200_000


def test_hopper_geometry_read_off_the_mesh() -> None:
    shape = hopper_geometry.HopperShape()
    geo = hopper_geometry.HopperGeometry.of(hopper_geometry.hopper_mesh(shape))
    assert geo.outlet_z == pytest.approx(0.0, abs=1e-12)
    assert geo.outlet_radius == pytest.approx(0.5 * shape.outlet_diameter)
    assert geo.top_radius == pytest.approx(0.5 * shape.bin_diameter)
    assert geo.top_z == pytest.approx(shape.height)
    # a 30-degree cone: the radius grows by tan(30 deg) per unit height
    assert shape.cone_height == pytest.approx(
        0.5 * (shape.bin_diameter - shape.outlet_diameter) / np.tan(np.radians(30.0))
    )


@pytest.mark.parametrize(
    ("main", "message"),
    [
        (hopper_demo.main, "HopperCase.particles must be at least 10, got 3"),
        (pour_and_settle.main, "DemoCase.particles must be an integer of at least 10, got 3"),
    ],
)
def test_examples_reject_bad_options(
    main: Any, message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["--particles", "3", "--output", "unused"])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_grainscale_hopper_rejects_bad_options(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["hopper", "--particles", "3", "--output", "unused"]) == 2
    err = capsys.readouterr().err
    assert "grainscale hopper: error: HopperCase.particles must be at least 10, got 3" in err
