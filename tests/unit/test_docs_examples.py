"""Every Python block of the documentation runs (issue 26).

The ```python blocks of each page of docs/ run in sequence, as one script, in a fresh process in
a temporary directory (a later block uses what an earlier one defined); the page fails on an
exception. A block that is deliberately not runnable (a sketch with ``...``) is fenced as
```python no-run and stays rare. Blocks in other languages (sh, text) are not run.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
FENCE = re.compile(r"^(`{3,}|~{3,})[ \t]*python\b([^\n]*)\n(.*?)^\1[ \t]*$", re.S | re.M)
MAX_NOT_RUN = 6  # sketches in the design document and the guide


def blocks(page: Path) -> list[tuple[str, str]]:
    """(options, code) of every python block of a Markdown page, in order."""
    return [(m.group(2).strip(), m.group(3)) for m in FENCE.finditer(page.read_text())]


def pages() -> list[Path]:
    return sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts)


def runnable_pages() -> list[Path]:
    return [p for p in pages() if any(opts == "" for opts, _ in blocks(p))]


def script(page: Path) -> str:
    parts = []
    for k, (opts, code) in enumerate(blocks(page)):
        if opts == "":
            parts.append(f"# --- {page.relative_to(ROOT)}, python block {k + 1}\n{code}")
    return "\n".join(parts)


def test_blocks_are_found() -> None:
    """The search itself works: the guide has runnable blocks, and every page that should."""
    names = {p.relative_to(DOCS).as_posix() for p in runnable_pages()}
    for page in ("getting-started.md", "guide/multi-level.md", "guide/coarse-graining.md",
                 "guide/materials-and-contact-laws.md", "guide/insertion.md"):  # fmt: skip
        assert page in names, f"docs/{page} has no runnable python block"


def test_only_known_options_and_few_sketches() -> None:
    not_run = []
    for page in pages():
        for opts, _ in blocks(page):
            assert opts in ("", "no-run"), f"{page}: unknown python block option {opts!r}"
            if opts == "no-run":
                not_run.append(page.name)
    assert len(not_run) <= MAX_NOT_RUN, f"too many python no-run blocks: {not_run}"


@pytest.mark.parametrize("page", runnable_pages(), ids=lambda p: p.relative_to(DOCS).as_posix())
def test_page_runs(page: Path, tmp_path: Path) -> None:
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("OMPI_COMM_WORLD_SIZE", None)
    code = script(page)
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, f"{page.relative_to(ROOT)} failed:\n{done.stderr[-4000:]}"
