"""A user's script over the public API, checked with ``mypy --strict`` (make lint) and run by
tests/typing/test_user_script.py. It exercises what a user's script does: materials, walls,
insertion, runs, the particle view, output, checkpoints, a hierarchy and the readers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import numpy.typing as npt

import grainscale as gs


def settle(out: Path) -> float:
    """Pour spheres into a box, settle them, write output and a checkpoint; the floor load (N)."""
    glass = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
    box = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.02), periodic=(True, True, False))
    law = gs.contact.HertzMindlin(restitution=0.5, friction=0.5)
    sim = gs.Simulation(domain=box, contact=law, quiet=True)
    floor: gs.WallHandle = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=glass))
    lid = sim.add_wall(gs.Plane(point=(0, 0, 0.02), normal=(0, 0, -1), material=glass))

    radius: npt.NDArray[np.float64] = np.full(20, 0.5e-3)
    fill = gs.Box(lo=(0, 0, 0.001), hi=(0.01, 0.01, 0.008))
    position = gs.insert.random_in_box(fill, radius, seed=1)
    ids = sim.add_particles(position=position, radius=radius, material=glass)
    sim.insert(
        gs.insert.Pack(
            fill, radius=gs.dist.Uniform(0.4e-3, 0.5e-3), count=10, material=glass, seed=2
        )
    )
    print(f"{len(ids)} placed, {sim.num_particles} in all")

    sim.output(gs.io.VTK(out / "vtk", every=1e-3, fields=["radius", "velocity"]))
    sim.output(gs.io.Dump(out / "dumps", every=1e-3))
    sim.checkpoint_every(out / "checkpoints", every=2e-3, keep=2)
    sim.run(until=4e-3)
    sim.run(steps=10, progress=False)
    lid.set_motion(velocity=(0.0, 0.0, -0.01))

    with sim.particles(writable=False) as p:
        mass = float(p.mass.sum())
        speed = np.linalg.norm(p.velocity, axis=1)
    thermo: dict[str, float] = sim.thermo()
    print(f"t = {sim.time:.3g} s, ke = {sim.kinetic_energy():.3g} J, max |v| {speed.max():.3g}")
    print(f"{thermo['step']:.0f} steps, {sim.num_contacts()} contacts, mass {mass:.3g} kg")

    sim.checkpoint(out / "state.h5")
    again = gs.Simulation(domain=box, contact=law, quiet=True)
    again.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=glass))
    again.add_wall(gs.Plane(point=(0, 0, 0.02), normal=(0, 0, -1), material=glass))
    again.restart(out / "state.h5")
    latest = gs.io.latest_checkpoint(out / "checkpoints")
    print(f"restarted at step {again.step}; latest periodic checkpoint {latest}")

    dumps = gs.io.read_dump(out / "dumps")
    last = dumps[-1] if isinstance(dumps, list) else dumps
    print(f"last dump: step {last.step}, {len(last.arrays['id'])} particles")
    return float(-floor.force[2])


def multi_level(out: Path) -> dict[str, float]:
    """Two levels of one poured system (coarse everywhere, resolved at the bottom)."""
    glass = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3)
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.04))
    size = gs.dist.Uniform(0.95e-3, 1.05e-3)
    face = gs.insert.DiscFace(centre=(0.01, 0.01, 0.035), normal=(0, 0, -1), radius=0.005)
    stream = gs.insert.Stream(
        face, mass_rate=1e-3, radius=size, material=glass, velocity=(0, 0, -1.0), seed=5
    )
    ref = gs.scaling.ParameterSet(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        walls=tuple(gs.geometry.box_walls(box, glass)),
        insertions=(stream,),
        size=size,
    )
    coarse = gs.scaling.scale(ref, 2.0, scheme="cg")
    for broken in coarse.broken:
        print(broken.name, broken.factor)
    h = gs.Hierarchy(
        base=ref,
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.01)))],
        exchange=gs.Exchange(every=1e-3),
    )
    h.output(out / "mlcg", every=1e-3)
    h.run(intervals=2)
    h.checkpoint(out / "mlcg.h5")
    fine: gs.Simulation = h.level(1)
    print(f"t = {h.time:.3g} s, fine level {fine.num_particles} particles")
    books = h.mass_balance()
    return {"unaccounted": float(books["unaccounted"])}


def main(out: Path) -> None:
    print(f"floor load {settle(out):.3g} N")
    print(multi_level(out))


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "out/user_script"))
