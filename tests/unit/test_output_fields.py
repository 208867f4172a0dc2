"""Chosen particle fields and user arrays in the VTK output, the .pvd series that a restarted
run continues, and the docstring examples of the output modules (issue 26 point 5)."""

from __future__ import annotations

import doctest
import importlib
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from output_cases import column
from test_vtk import read_pvd, read_vtp

import grainscale as gs
from grainscale.io import PVDSeries


def test_chosen_fields_and_user_arrays(tmp_path: Path) -> None:
    sim, _ = column(n=20)
    tags = np.arange(1000) % 3  # a user's per-particle data, indexed by id
    extra = {
        "speed": lambda p: np.linalg.norm(p.velocity, axis=1),
        "tag": lambda p: tags[p.id].astype(np.int32),
        "above_half": lambda p: p.position[:, 2] > 0.02,
        "branch": lambda p: p.position - 0.005,
    }
    vtk = gs.io.VTK(tmp_path, every_steps=500, fields=["id", "radius", "velocity"], extra=extra)
    sim.output(vtk)
    sim.run(steps=500)
    got = read_vtp(vtk.files[-1])
    assert list(got["PointData"]) == ["id", "radius", "velocity", *extra]
    data = got["PointData"]
    with sim.particles(writable=False) as p:
        assert np.array_equal(got["points"], p.position)
        assert np.array_equal(data["id"], p.id) and np.array_equal(data["radius"], p.radius)
        assert np.array_equal(data["speed"], np.linalg.norm(p.velocity, axis=1))
        assert np.array_equal(data["tag"], tags[p.id]) and data["tag"].dtype == np.int32
        assert data["above_half"].dtype == np.uint8
        assert np.array_equal(data["above_half"], p.position[:, 2] > 0.02)
        assert np.array_equal(data["branch"], p.position - 0.005)


def test_default_fields_are_unchanged(tmp_path: Path) -> None:
    sim, _ = column(n=5)
    vtk = gs.io.VTK(tmp_path, every_steps=10)
    sim.output(vtk)
    sim.run(steps=1)
    names = ["radius", "velocity", "angular_velocity", "force", "torque", "id", "material", "mass"]
    assert list(read_vtp(vtk.files[0])["PointData"]) == names


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"fields": ["speed"]}, r"VTK.fields must name particle fields \(.*\), got 'speed'"),
        ({"fields": "radius"}, "VTK.fields must be a list of particle field names"),
        ({"fields": ["id", "id"]}, "VTK.fields names 'id' twice"),
        ({"extra": [lambda p: p.radius]}, "VTK.extra must be a dict of name -> callable"),
        ({"extra": {"": lambda p: p.radius}}, "VTK.extra names must be non-empty strings"),
        ({"extra": {"rank": lambda p: p.radius}}, r"VTK.extra\['rank'\] has the name of a field"),
        ({"extra": {"mass": lambda p: p.mass}}, r"VTK.extra\['mass'\] has the name of a field"),
        ({"extra": {"s": np.zeros(3)}}, r"VTK.extra\['s'\] must be a callable\(particle view\)"),
    ],
)
def test_field_validation(tmp_path: Path, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        gs.io.VTK(tmp_path, every=1.0, **kwargs)


@pytest.mark.parametrize(
    ("fn", "shape"),
    [
        (lambda p: np.zeros(len(p) + 1), r"\(5,\)"),
        (lambda p: np.zeros((len(p), 2, 2)), r"\(4, 2, 2\)"),
        (lambda p: np.array(["a"] * len(p)), r"\(4,\) of <U1"),
    ],
)
def test_user_array_of_the_wrong_shape_is_named(tmp_path: Path, fn: object, shape: str) -> None:
    sim, _ = column(n=4)
    sim.output(gs.io.VTK(tmp_path, every_steps=10, extra={"bad": fn}))
    with pytest.raises(ValueError, match=rf"VTK.extra\['bad'\] must return .*got shape {shape}"):
        sim.run(steps=1)


# ------------------------------------------------------------------- a series across a restart
def test_pvd_continues_across_a_restart(tmp_path: Path) -> None:
    out = tmp_path / "vtk"
    first, _ = column(n=30)
    first.output(gs.io.VTK(out, every_steps=1000))
    first.run(steps=3000)
    first.checkpoint(tmp_path / "state.h5")
    first.run(steps=1500)  # the run goes on past the checkpoint, then stops (say, it crashed)
    assert [e[1] for e in read_pvd(out / "particles.pvd")][-1] == "particles_00004000.vtp"

    again, _ = column(n=30, particles=False)
    again.restart(tmp_path / "state.h5")
    again.output(gs.io.VTK(out, every_steps=1000))
    again.run(steps=2000)
    series = read_pvd(out / "particles.pvd")
    steps = [int(e[1][10:18]) for e in series]
    assert steps == [0, 1000, 2000, 3000, 4000, 5000]
    times = [e[0] for e in series]
    assert times == sorted(times) and times[-1] == again.time
    dt = again.time_step
    assert times[:3] == [0.0, pytest.approx(1000 * dt), pytest.approx(2000 * dt)]
    walls = read_pvd(out / "particles_walls.pvd")  # a fixed floor: once per run
    assert [e[1] for e in walls] == ["particles_walls_00000000.vtp", "particles_walls_00003000.vtp"]

    fresh, _ = column(n=30, particles=False)  # resume=False starts a new series
    fresh.restart(tmp_path / "state.h5")
    fresh.output(gs.io.VTK(out, every_steps=1000, resume=False))
    fresh.run(steps=1000)
    assert [e[1] for e in read_pvd(out / "particles.pvd")] == [
        "particles_00003000.vtp",
        "particles_00004000.vtp",
    ]


def test_a_new_run_from_time_zero_starts_a_new_series(tmp_path: Path) -> None:
    for _ in range(2):
        sim, _ = column(n=5)
        sim.output(gs.io.VTK(tmp_path, every_steps=10))
        sim.run(steps=20)
    assert len(read_pvd(tmp_path / "particles.pvd")) == 3


def test_pvd_resume_keeps_earlier_existing_entries(tmp_path: Path) -> None:
    for name in ("a.vtp", "b.vtp", "d.vtp"):
        (tmp_path / name).write_text("")
    old = PVDSeries(tmp_path / "s.pvd")
    for t, name in [(0.0, "a.vtp"), (0.1, "b.vtp"), (0.2, "c.vtp"), (0.3, "d.vtp")]:
        old.add(t, name)
    series = PVDSeries(tmp_path / "s.pvd")
    series.resume(0.25)
    assert series.entries == [(0.0, "a.vtp", 0), (0.1, "b.vtp", 0)]  # c.vtp is missing
    series.add(0.25, "e.vtp")
    assert [e[1] for e in read_pvd(tmp_path / "s.pvd")] == ["a.vtp", "b.vtp", "e.vtp"]
    (tmp_path / "s.pvd").write_text("<VTKFile><Collection><DataSet timestep=")
    with pytest.warns(UserWarning, match="is not a readable .pvd index"):
        series.resume(1.0)
    assert series.entries == []


# ------------------------------------------------------------------------ docstring examples
@pytest.mark.parametrize(
    "module",
    [
        "grainscale.io.vtk_output",
        "grainscale.io.dump",
        "grainscale.io.contact_network",
        "grainscale.io.auto_checkpoint",
        "grainscale.io.particle_fields",
        "grainscale.sim_thermo",
        "grainscale.sim_output",
    ],
)
def test_docstring_examples(module: str) -> None:
    result = doctest.testmod(importlib.import_module(module))
    assert result.failed == 0 and result.attempted > 0


def test_guide_every_output_example_runs(tmp_path: Path) -> None:
    """The Output guide's "Every output at once" block (the README's Output section until issue
    26 moved it there): it runs on a fresh column of a few particles and reads back."""
    guide = (Path(__file__).resolve().parents[2] / "docs" / "guide" / "output.md").read_text()
    section = guide.split("\n## Every output at once\n", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    assert code is not None
    set_up = (
        "import numpy as np\nimport grainscale as gs\n"
        "from output_cases import column\nsim, floor = column(n=8)\n"
    )
    check = (
        "assert snapshots[0].time == 0.0 and len(snapshots) >= 10\n"
        "assert len(network['id_i']) > 0 and gs.io.latest_checkpoint('out/all/checkpoints')\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", set_up + code.group(1) + check],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    assert done.returncode == 0, done.stderr
    assert len(list((tmp_path / "out" / "all" / "checkpoints").glob("*.h5"))) == 3
