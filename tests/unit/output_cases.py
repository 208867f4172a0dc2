"""Shared set-ups of the output tests (issue 26, output): a settled column on a floor."""

from __future__ import annotations

import numpy as np

import grainscale as gs

GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
GRAVITY = np.array([0.0, 0.0, -9.81])


def column(
    n: int = 80, seed: int = 1, particles: bool = True, **options: object
) -> tuple[gs.Simulation, gs.WallHandle]:
    """``n`` spheres dropped into a box periodic in x and y onto a floor (wall 0); settles in
    about 0.25 s. Returns the simulation and the floor; without the particles when
    ``particles`` is False (the set-up a restart script builds)."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.04), periodic=(True, True, False))
    law = gs.contact.HertzMindlin(restitution=0.3, friction=0.5)
    sim = gs.Simulation(domain=box, contact=law, quiet=True, **options)  # type: ignore[arg-type]
    floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    r = np.random.default_rng(seed).uniform(0.8e-3, 1.0e-3, n)
    pos = gs.insert.random_in_box(gs.Box(lo=(0, 0, 0.001), hi=(0.01, 0.01, 0.04)), r, seed=seed)
    if particles:
        sim.add_particles(position=pos, radius=r, material=GLASS)
    return sim, floor
