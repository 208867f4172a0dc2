"""The README's Python example runs and prints what the README shows (issue 26)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

README = Path(__file__).resolve().parents[2] / "README.md"


def example_and_output() -> tuple[str, str]:
    """The first python block of the "Python example" section and the text block after it."""
    section = README.read_text().split("## Python example", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S)
    printed = re.search(r"```text\n(.*?)```", section, re.S)
    assert code and printed, "README: the Python example or its printed output is missing"
    return code.group(1), printed.group(1)


def test_readme_example_prints_what_the_readme_shows(tmp_path: Path) -> None:
    code, expected = example_and_output()
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == expected
    assert (tmp_path / "out" / "example" / "particles.pvd").is_file()
