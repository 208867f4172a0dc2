"""Sphinx configuration of the grainscale documentation (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
try:  # the installed package (make docs installs it first), else the source tree
    import grainscale  # noqa: F401
except ImportError:
    sys.path.insert(0, str(HERE.parent / "python"))

import figures  # noqa: E402  (docs/figures.py)

# Figures and tables made from the package (docs/_generated, not committed).
figures.generate(HERE / "_generated")

project = "grainscale"
author = "The grainscale developers"
copyright = "The grainscale developers"
release = "0.1.0"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_generated"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
autodoc_member_order = "bysource"
autodoc_typehints = "description"
napoleon_google_docstring = True
napoleon_numpy_docstring = False
nitpicky = True
html_theme = "furo"
html_title = "grainscale"

# Names from other libraries in the signatures; the documentation is built without network
# access, so they are not linked (internal references are all checked).
nitpick_ignore_regex = [
    ("py:class", r"(numpy|np)\..*"),
    ("py:class", r"(collections\.abc|typing|os|pathlib|contextlib|dataclasses)\..*"),
    ("py:class", r"(Any|Sequence|Mapping|Iterator|Callable|Literal|NamedTuple)"),
    ("py:class", r"(_core|grainscale\._core)\..*"),
    ("py:class", r"mpi4py\..*"),
    ("py:class", r"PathLike"),
    ("py:class", r"Extra"),  # the type of VTK.extra (a mapping of callables)
    ("py:func", r"os\..*"),
    # package-internal classes that appear in signatures (mixins, the engine interface)
    ("py:class", r"(grainscale\.)?(sim_walls\.)?(WallMethods|WallGeometry)"),
    ("py:class", r"(grainscale\.engine\.)?Engine"),
]
