"""Output directories: checked when an output is made, created when it first writes.

A path that names an existing file, or lies below one, or below a directory that cannot be
written, would otherwise fail deep inside a run with a bare OSError that names no output.
"""

from __future__ import annotations

import os
from pathlib import Path


def output_directory(owner: str, directory: str | os.PathLike[str]) -> Path:
    """``directory`` as a Path, or ValueError naming ``owner`` when it cannot become a writable
    directory: it is a file, or its nearest existing ancestor is a file or not writable."""
    if isinstance(directory, bool) or not isinstance(directory, str | os.PathLike):
        raise ValueError(f"{owner} must be a directory path (str or PathLike), got {directory!r}")
    path = Path(directory)
    if str(path).strip() == "":
        raise ValueError(f"{owner} must be a directory path, got {str(directory)!r}")
    if path.exists() and not path.is_dir():
        raise ValueError(f"{owner} must be a directory, got '{path}': a file of that name exists")
    ancestor = path
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise ValueError(f"{owner} must be a directory, got '{path}': '{ancestor}' is a file")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise ValueError(
            f"{owner} must be a directory that can be written, got '{path}': '{ancestor}' is "
            "not writable"
        )
    return path


def make_directory(owner: str, path: Path) -> None:
    """``path`` created with its parents if missing; ValueError naming ``owner`` if it cannot be
    (the file system changed since the output was made)."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise ValueError(
            f"{owner} must be a directory that can be created, got '{path}' "
            f"({type(err).__name__}: {err.strerror or err})"
        ) from err
