"""A rank that stops answering: the others abort the job with a clear message after the
timeout instead of waiting for ever (issue 25). Run as a serial test that starts its own
two-rank job, since the job is meant to die."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import grainscale as gs
from grainscale import _core

SCRIPT = textwrap.dedent(
    """
    import sys, time
    import numpy as np
    import grainscale as gs
    from mpi4py import MPI

    gs.parallel.set_timeout(2.0)
    glass = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.06))
    sim = gs.Simulation(domain=box, contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5))
    radius = np.full(100, 1e-3)
    sim.add_particles(position=gs.insert.random_in_box(box, radius, seed=1), radius=radius,
                      material=glass)
    sim.run(steps=10)
    if MPI.COMM_WORLD.Get_rank() == 1:
        if sys.argv[1] == "uncaught":
            raise KeyError("the user's own error on rank 1")
        time.sleep(120)  # stops answering
    if sys.argv[1] in ("run", "uncaught"):
        sim.run(steps=100)  # waits in the argument agreement (Python side)
    else:
        sim.kinetic_energy()  # waits in the core's sum over ranks
    print("finished", flush=True)
    """
)


def _two_rank_job(tmp_path: Path, mode: str) -> tuple[subprocess.CompletedProcess[str], float]:
    script = tmp_path / "stops_answering.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
    env["PYTHONPATH"] = os.pathsep.join([str(Path(gs.__file__).parents[1]), *sys.path])
    start = time.monotonic()
    done = subprocess.run(
        ["mpirun", "-np", "2", "--oversubscribe", sys.executable, str(script), mode],
        env=env,
        capture_output=True,
        text=True,
        timeout=100,  # the job must end long before rank 1 wakes up (120 s)
    )
    return done, time.monotonic() - start


@pytest.mark.skipif(
    not _core.with_mpi() or shutil.which("mpirun") is None, reason="needs an MPI build and mpirun"
)
@pytest.mark.parametrize(
    ("mode", "wait"),
    [("run", "the argument agreement of Simulation.run"), ("energy", "MPI_Allgather")],
)
def test_rank_that_stops_answering_aborts_the_job(tmp_path: Path, mode: str, wait: str) -> None:
    done, elapsed = _two_rank_job(tmp_path, mode)
    assert done.returncode == 70, done.stdout + done.stderr
    assert "finished" not in done.stdout
    assert "rank 0 of 2 has waited" in done.stderr and wait in done.stderr
    assert "stopped answering" in done.stderr and "set_timeout" in done.stderr
    assert elapsed < 60


@pytest.mark.skipif(
    not _core.with_mpi() or shutil.which("mpirun") is None, reason="needs an MPI build and mpirun"
)
def test_uncaught_exception_on_one_rank_ends_the_job_at_once(tmp_path: Path) -> None:
    """The script's own error on one rank: its traceback, then every rank ends (no wait for
    the watchdog)."""
    done, elapsed = _two_rank_job(tmp_path, "uncaught")
    assert done.returncode != 0 and "finished" not in done.stdout
    assert "KeyError" in done.stderr and "the user's own error on rank 1" in done.stderr
    assert "uncaught KeyError on rank 1; aborting every rank" in done.stderr
    assert "has waited" not in done.stderr  # not the watchdog: at once
    assert elapsed < 30


def test_timeout_is_set_and_checked() -> None:
    before = gs.parallel.timeout()
    try:
        gs.parallel.set_timeout(0)  # switched off
        assert gs.parallel.timeout() == 0.0
        for bad in (-1.0, float("nan"), float("inf")):
            with pytest.raises(ValueError, match="set_timeout: seconds must be finite and >= 0"):
                gs.parallel.set_timeout(bad)
        with pytest.raises(ValueError, match="parallel.set_timeout.seconds must be a number"):
            gs.parallel.set_timeout("10")  # type: ignore[arg-type]
    finally:
        gs.parallel.set_timeout(before)


def test_default_timeout_and_environment_variable() -> None:
    code = "import grainscale as gs; print(gs.parallel.timeout())"
    for value, expected in ((None, "600.0"), ("42.5", "42.5"), ("soon", "600.0")):
        env = {k: v for k, v in os.environ.items() if k != "GRAINSCALE_MPI_TIMEOUT"}
        if value is not None:
            env["GRAINSCALE_MPI_TIMEOUT"] = value
        env["PYTHONPATH"] = str(Path(gs.__file__).parents[1])
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        assert out.stdout.strip() == expected
        if value == "soon":
            assert "GRAINSCALE_MPI_TIMEOUT must be a number of seconds, got 'soon'" in out.stderr
