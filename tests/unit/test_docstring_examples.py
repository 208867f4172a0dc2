"""Every docstring example of the package runs and prints what it shows (issue 26).

doctest over every module of grainscale, in a temporary directory (an example may write files).
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil
from pathlib import Path

import pytest

import grainscale


def modules() -> list[str]:
    names = ["grainscale"]
    names += [m.name for m in pkgutil.walk_packages(grainscale.__path__, "grainscale.")]
    return sorted(n for n in names if not n.endswith("._core"))


MODULES = modules()


def test_the_package_has_examples() -> None:
    """The search itself works: the package's docstrings hold examples in many modules."""
    finder = doctest.DocTestFinder()
    with_examples = [
        name
        for name in MODULES
        if any(t.examples for t in finder.find(importlib.import_module(name)))
    ]
    assert len(with_examples) >= 10, with_examples


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS, report=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"
