"""Cases and helpers of the MPI tests. They run under ``mpirun -np 2`` (and 3): every rank runs
every test, making the same collective calls, and compares a simulation decomposed over
``COMM_WORLD`` with the same simulation run serially (``COMM_SELF``) in the same process. Data
are gathered to every rank before an assertion, so all ranks reach the same verdict (no rank
waits for a failed one).
"""

from __future__ import annotations

import numpy as np

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")


def lattice(n: int, spacing: float, side: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """n sites of a simple-cubic lattice, `side` sites per row, filled bottom-up, with seeded
    jitter of 2.5 % of the spacing in x and y and velocities of +-0.05 m/s per component."""
    k = np.arange(n)
    ijk = np.stack([k % side, (k // side) % side, k // (side * side)], axis=1)
    x = (ijk + 0.5) * spacing
    rng = np.random.default_rng(seed)
    x[:, :2] += rng.uniform(-0.025, 0.025, size=(n, 2)) * spacing
    v = rng.uniform(-0.05, 0.05, size=(n, 3))
    return x, v


def settle(comm, n: int, seed: int = 1, particles: bool = True, **kwargs) -> gs.Simulation:
    """The 'settle' case of bench/python/settle_case.py (d = 2 mm spheres on a 2.2 mm lattice
    in a closed box of six walls, Hertz-Mindlin, dt = 1e-5 s, skin 0.2 mm); without its
    particles when `particles` is False (the set-up a restart script builds)."""
    side = max(1, int(np.ceil((n / 2) ** (1 / 3))))
    layers = -(-n // side**2)
    spacing = 2.2e-3
    box = gs.Box(lo=(0, 0, 0), hi=(side * spacing, side * spacing, (layers + 1) * spacing))
    sim = gs.Simulation(
        domain=box,
        contact=gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        time_step=1e-5,
        skin=2e-4,
        comm=comm,
        quiet=True,
        **kwargs,
    )
    for wall in gs.geometry.box_walls(box, GLASS):
        sim.add_wall(wall)
    if particles:
        x, v = lattice(n, spacing, side, seed)
        sim.add_particles(position=x, velocity=v, radius=1e-3, material=GLASS)
    return sim


def relative_difference(a: np.ndarray, b: np.ndarray, scale: float) -> float:
    return float(np.max(np.abs(a - b)) / scale) if a.size else 0.0
