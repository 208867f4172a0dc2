"""Smoke test of an installed grainscale (the wheel of ``make wheel`` in a fresh environment).

Run it from a directory outside the source tree with the environment's interpreter, so that
``import grainscale`` finds the installed package, not the sources:

    cd /tmp && /path/to/venv/bin/python /path/to/tests/smoke/wheel_smoke.py --expect portable

It checks that the package comes from the environment, prints how the core was built (and with
``--expect`` checks it), settles a layer of spheres on a floor under gravity against the Hertz
static overlap, and round-trips a checkpoint (the restarted run is bit-identical).
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import grainscale as gs
from grainscale import _core

RADIUS = 1e-3  # m
DENSITY = 2500.0  # kg/m^3
YOUNGS = 1e7  # Pa
POISSON = 0.3
GRAVITY = 9.81  # m/s^2
SIDE = 12  # spheres per side of the square layer


def check_origin() -> None:
    where = Path(gs.__file__).resolve()
    if not where.is_relative_to(Path(sys.prefix).resolve()):
        raise SystemExit(f"grainscale imported from {where}, outside the environment {sys.prefix}")
    print(f"grainscale {gs.__version__} from {where.parent}")


def check_build(expect: str | None) -> None:
    info = _core.build_info()
    isa = " ".join(info["instruction_sets"]) or "baseline"
    print(
        f"core: {info['kind']} build, instruction sets {isa}, "
        f"{'MPI' if info['mpi'] else 'serial'}, {info['build_type']}, {info['compiler']}"
    )
    if expect == "native" and not info["native"]:
        raise SystemExit(f"expected a native build, got {info['kind']}")
    if expect == "portable":
        if info["native"]:
            raise SystemExit("expected a portable build, got a native one")
        if platform.machine() in ("x86_64", "AMD64") and info["arch"] != "x86-64-v2":
            raise SystemExit(f"expected -march=x86-64-v2, got {info['arch']}")
        wide = {"avx", "avx2", "fma", "avx512f"} & set(info["instruction_sets"])
        if wide:
            raise SystemExit(f"a portable build uses {sorted(wide)}")


def make_case() -> tuple[gs.Simulation, gs.WallHandle, gs.Material]:
    """A square layer of spheres, not touching each other, just above a floor."""
    glass = gs.Material(density=DENSITY, youngs_modulus=YOUNGS, poisson_ratio=POISSON)
    spacing = 2.5 * RADIUS
    length = SIDE * spacing
    box = gs.Box(lo=(0, 0, 0), hi=(length, length, 10 * RADIUS), periodic=(True, True, False))
    sim = gs.Simulation(domain=box, contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5))
    floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=glass))
    return sim, floor, glass


def settle() -> gs.Simulation:
    """Drop the layer from 0.2 r and compare its height at rest with the Hertz overlap."""
    sim, floor, glass = make_case()
    spacing = 2.5 * RADIUS
    i, j = np.meshgrid(np.arange(SIDE), np.arange(SIDE), indexing="ij")
    n = SIDE * SIDE
    position = np.column_stack(
        [(i.ravel() + 0.5) * spacing, (j.ravel() + 0.5) * spacing, np.full(n, 1.2 * RADIUS)]
    )
    sim.add_particles(position=position, radius=np.full(n, RADIUS), material=glass)
    start = time.perf_counter()
    sim.run(until=0.1, progress=False)
    seconds = time.perf_counter() - start
    mass = DENSITY * 4.0 / 3.0 * np.pi * RADIUS**3
    # Sphere on a plane of the same material: F = 4/3 E* sqrt(r) d^(3/2) with
    # 1/E* = 2 (1 - nu^2) / E carries the weight m g.
    e_star = YOUNGS / (2.0 * (1.0 - POISSON**2))
    overlap = (3.0 * mass * GRAVITY / (4.0 * e_star * np.sqrt(RADIUS))) ** (2.0 / 3.0)
    with sim.particles() as p:
        z = p.position[:, 2].copy()
    load = -floor.force[2] / (n * mass * GRAVITY)
    rel = np.abs((RADIUS - z) / overlap - 1.0).max()
    print(
        f"settle: {n} spheres, {sim.step} steps in {seconds:.2f} s, kinetic energy "
        f"{sim.kinetic_energy():.2e} J, floor load / weight {load:.6f}, overlap "
        f"{np.mean(RADIUS - z) * 1e6:.4f} um against Hertz {overlap * 1e6:.4f} um "
        f"(max rel. diff {rel:.1e})"
    )
    if abs(load - 1.0) > 1e-3 or rel > 1e-3:
        raise SystemExit("the settled layer does not match the Hertz static overlap")
    return sim


def checkpoint_round_trip(sim: gs.Simulation, workdir: Path) -> None:
    """Checkpoint, continue; restart a new simulation from the file: the same positions."""
    path = workdir / "state.h5"
    sim.checkpoint(path)
    sim.run(steps=500, progress=False)
    again, _, _ = make_case()
    again.restart(path)
    again.run(steps=500, progress=False)
    a, b = sim.gather(("position", "velocity")), again.gather(("position", "velocity"))
    same = (
        np.array_equal(a["id"], b["id"])
        and np.array_equal(a["position"], b["position"])
        and np.array_equal(a["velocity"], b["velocity"])
    )
    print(f"checkpoint: {path.stat().st_size} bytes, restart bit-identical after 500 steps: {same}")
    if not same:
        raise SystemExit("the restarted run differs from the continued one")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--expect", choices=("native", "portable"), default=None)
    args = parser.parse_args(argv)
    check_origin()
    check_build(args.expect)
    sim = settle()
    with tempfile.TemporaryDirectory() as tmp:
        checkpoint_round_trip(sim, Path(tmp))
    print("wheel smoke test passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
