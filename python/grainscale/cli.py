"""The ``grainscale`` command.

    grainscale demo [--output DIR] [--full] [--quick] [--seed K] [--no-vtk]
    grainscale hopper [--output DIR] [--particles N] [--duration S] [--seed K] [--stl FILE]
                      [--quick]
    grainscale info

``demo`` runs the demo of ``make demo``, :mod:`grainscale.examples.silo_demo` (a silo whose
orifice jams coarse graining: pure CG and a multi-level hierarchy against a resolved
reference), with the same options; ``hopper`` the hopper example,
:mod:`grainscale.examples.hopper_demo`; ``info`` prints the version and how the C++ core was
built (native or portable, serial or MPI).
"""

from __future__ import annotations

import argparse
import platform
import sys
from collections.abc import Sequence


def mpi_build() -> bool:
    """Whether the C++ core was built with MPI (domain decomposition under mpirun)."""
    from . import _core

    return bool(_core.with_mpi())


def build_summary() -> str:
    """How the C++ core was built, in one line: ``native`` (``-march=native``, tuned for the
    machine that compiled it) or ``portable (x86-64-v2)`` (the wheel), with the vector
    instruction sets the compiled code uses, e.g. ``portable (x86-64-v2): sse4.2``."""
    from . import _core

    info = _core.build_info()
    return f"{info['kind']}: {' '.join(info['instruction_sets']) or 'baseline instructions'}"


def info_lines() -> list[str]:
    """What ``grainscale info`` prints, one entry per line."""
    import numpy as np

    from . import __version__, _core

    mpi = mpi_build()
    info = _core.build_info()
    return [
        f"grainscale {__version__}",
        f"core: {_core.__file__}",
        f"build: {build_summary()}; {info['build_type']}, {info['compiler']}",
        f"parallel: {'built with MPI' if mpi else 'serial build'}",
        f"python {platform.python_version()}, numpy {np.__version__}, {platform.platform()}",
    ]


def _info(args: argparse.Namespace) -> int:
    print("\n".join(info_lines()))
    return 0


def _demo(args: argparse.Namespace) -> int:
    from .examples import silo_demo

    try:
        silo_demo.run_from_args(args)
    except ValueError as err:
        print(f"grainscale demo: error: {err}", file=sys.stderr)
        return 2
    return 0


def _hopper(args: argparse.Namespace) -> int:
    from .examples import hopper_demo

    try:
        hopper_demo.run_from_args(args)
    except ValueError as err:
        print(f"grainscale hopper: error: {err}", file=sys.stderr)
        return 2
    return 0


def build_parser() -> argparse.ArgumentParser:
    from . import __version__
    from .examples import hopper_demo, silo_demo

    parser = argparse.ArgumentParser(
        prog="grainscale", description="grainscale: discrete element method for granular media."
    )
    parser.add_argument(
        "--version", action="version", version=f"grainscale {__version__} ({build_summary()})"
    )
    sub = parser.add_subparsers(dest="command", metavar="command")
    sub.required = True
    demo = sub.add_parser(
        "demo",
        help="a silo whose orifice jams coarse graining: pure CG and multi-level against the "
        "resolved reference; make demo",
        description=silo_demo.DESCRIPTION + " Prints the discharge rates, their errors, the "
        "particle counts and the speed-up; writes discharge.png, levels.png, ParaView files "
        "(levels.pvd, level<k>.pvd with a `level` field), summary.txt and summary.json into the "
        "output directory.",
    )
    silo_demo.add_arguments(demo)
    demo.set_defaults(func=_demo)
    hopper = sub.add_parser(
        "hopper",
        help="fill a conical hopper and discharge it (VTK, PNG plot, summary)",
        description=hopper_demo.DESCRIPTION + " Writes ParaView files (particles.pvd), a PNG "
        "plot, history.csv and summary.md into the output directory.",
    )
    hopper_demo.add_arguments(hopper)
    hopper.set_defaults(func=_hopper)
    info = sub.add_parser("info", help="version and build configuration")
    info.set_defaults(func=_info)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``grainscale`` console script; returns the exit status."""
    args = build_parser().parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    raise SystemExit(main())
