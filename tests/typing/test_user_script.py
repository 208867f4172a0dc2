"""tests/typing/user_script.py, a user's script over the public API: it passes ``mypy --strict``
against the package's annotations and the stub of the C++ core, and it runs (about 10 s)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

import grainscale

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = Path(__file__).with_name("user_script.py")


def _env() -> dict[str, str]:
    # the package the tests import, whether installed or the source tree
    package_dir = Path(grainscale.__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": str(package_dir)}
    # mypy finds an installed package itself and refuses site-packages on its search path
    if package_dir.name != "site-packages":
        env["MYPYPATH"] = str(package_dir)
    return env


def test_user_script_passes_mypy_strict(tmp_path: Path) -> None:
    pytest.importorskip("mypy", reason="mypy is in the dev extra")
    args = [sys.executable, "-m", "mypy", "--strict", "--cache-dir", str(tmp_path / "cache")]
    result = subprocess.run(
        [*args, "--config-file", str(ROOT / "pyproject.toml"), str(SCRIPT)],
        cwd=ROOT,
        env=_env(),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_user_script_runs(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, str(SCRIPT), str(tmp_path / "out")],
        env=_env(),
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "unaccounted" in result.stdout
