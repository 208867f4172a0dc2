"""The remaining-time estimate in the thermo line and the log file (sim.log; issue 26 point 5)."""

from __future__ import annotations

import re
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from output_cases import GLASS, column

import grainscale as gs
from grainscale.sim_thermo import format_remaining

CLOCK = re.compile(r"\d+:\d\d:\d\d\Z")


def test_thermo_line_estimates_the_time_remaining(capsys: pytest.CaptureFixture[str]) -> None:
    sim, _ = column(n=30, thermo_every=1000)
    sim.quiet = False
    assert sim.thermo()["remaining_seconds"] == 0.0  # outside a run
    sim.run(steps=4000)
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[-1] == "remaining" and len(lines) == 5
    rows = [line.split() for line in lines[1:]]
    assert [int(r[0]) for r in rows] == [1000, 2000, 3000, 4000]
    assert all(CLOCK.match(r[-1]) for r in rows)
    assert rows[-1][-1] == "0:00:00"
    left = [e["remaining_seconds"] for e in sim.thermo_log]
    assert all(x >= 0 for x in left) and left[-1] == 0.0
    # the estimate is the run's wall-clock time so far per step times the steps left
    sim._run_clock = (time.perf_counter() - 10.0, sim.step - 100, sim.step + 300)
    assert sim.thermo()["remaining_seconds"] == pytest.approx(30.0, rel=1e-3)
    sim._run_clock = None
    assert format_remaining(59.6) == "0:01:00" and format_remaining(-1.0) == "-"


def test_log_gets_thermo_lines_warnings_and_runs(tmp_path: Path) -> None:
    log = tmp_path / "logs" / "run.log"
    box = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01))
    sim = gs.Simulation(domain=box, gravity=(0, 0, 0), thermo_every=50, quiet=True)
    sim.add_particles(position=[[0.005, 0.005, 0.009]], radius=5e-4, material=GLASS,
                      velocity=(0, 0, 2.0))  # fmt: skip
    sim.add_particles(position=[[0.005, 0.005, 0.003]], radius=5e-4, material=GLASS)
    sim.log(log)
    assert sim.log_path == log
    with pytest.warns(UserWarning, match="left the domain"):  # still shown as usual
        sim.run(steps=200)
    text = log.read_text()
    lines = text.splitlines()
    assert lines[0].startswith("# grainscale ") and "log opened" in lines[0]
    assert lines[1] == "# run from step 0 (t = 0 s) to step 200"
    assert any(line.startswith("# warning (UserWarning):") and "left the domain" in line
               for line in lines)  # fmt: skip
    assert lines[-1].startswith("# run ended at step 200")
    header = next(line for line in lines if line.startswith("#     step"))
    assert header.split()[-1] == "remaining"
    numbers = np.loadtxt(log, usecols=range(7))
    assert numbers[:, 0].tolist() == [50, 100, 150, 200]
    assert numbers[:, 6].tolist()[-1] == 1  # one particle lost
    thermo = [e for e in sim.thermo_log if e["step"] % 50 == 0]
    assert np.allclose(numbers[:, 2], [e["kinetic_energy"] for e in thermo], rtol=1e-5)

    sim.run(steps=50)  # appended; the header only once
    assert log.read_text().startswith(text)
    assert log.read_text().count("#     step") == 1
    sim.log(log, append=False)
    assert log.read_text().count("\n") == 1
    sim.log(None)
    sim.run(steps=50)
    assert log.read_text().count("\n") == 1 and sim.log_path is None


def test_log_records_a_failed_run(tmp_path: Path) -> None:
    class Failing:
        def next_step(self, step: int, time: float, time_step: float) -> int:
            return step + 10

        def write(self, sim: Any) -> None:
            warnings.warn("about to fail", RuntimeWarning, stacklevel=1)
            raise OSError("disk full")

    sim, _ = column(n=5)
    sim.log(tmp_path / "run.log")
    sim.output(Failing())
    with pytest.raises(OSError, match="disk full"), pytest.warns(RuntimeWarning):
        sim.run(steps=100)
    lines = (tmp_path / "run.log").read_text().splitlines()
    assert lines[-2] == "# warning (RuntimeWarning): about to fail"
    assert lines[-1].startswith("# run stopped by OSError: disk full at step 10")
