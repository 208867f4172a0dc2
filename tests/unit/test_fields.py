"""Cell averages (grainscale.fields, cpp/field/cell_average.hpp): mass, Favre velocity, solid
fraction, velocity range and spread, and the stress tensor against what they must be by
construction."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)


def lattice_sim(velocity=(0.0, 0.0, 0.0), gravity=(0.0, 0.0, 0.0)) -> gs.Simulation:
    box = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02), periodic=(True, True, True))
    sim = gs.Simulation(
        domain=box, gravity=gravity, time_step=1e-6, record_contacts=True, quiet=True
    )
    x = gs.insert.lattice(gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)), spacing=2.5e-3)
    sim.add_particles(position=x, radius=1e-3, material=GLASS, velocity=velocity)
    return sim


def test_uniform_motion_gives_its_velocity_and_the_lattice_solid_fraction():
    sim = lattice_sim(velocity=(0.1, -0.2, 0.05))
    avg = gs.fields.CellAverages(sim, gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)), 0.01)
    assert avg.cells == 8
    sim.run(steps=3)
    avg.sample()
    f = avg.finish()
    n_per_cell = (0.01 / 2.5e-3) ** 3  # 4^3 lattice sites per cell
    m = 2500 * 4 / 3 * np.pi * 1e-9
    assert np.allclose(f["particles"], n_per_cell)
    assert np.allclose(f["mass"], n_per_cell * m, rtol=1e-12)
    phi = n_per_cell * 4 / 3 * np.pi * 1e-9 / 1e-6
    assert np.allclose(f["solid_fraction"], phi, rtol=1e-12)
    assert np.allclose(f["velocity"], [0.1, -0.2, 0.05], rtol=1e-12)
    assert np.allclose(f["velocity_min"], f["velocity_max"])
    # Every particle at the mean: no spread, up to the round-off of a one-pass variance (a few ulp
    # of u^2, so a few sqrt(machine epsilon) x the speed after the square root).
    assert np.allclose(f["velocity_spread"], 0, atol=1e-7)
    # No contacts (2.5 mm spacing, 2 mm spheres) and no fluctuation: no stress.
    assert np.abs(f["stress"]).max() < 1e-9
    assert avg.finish()["samples"] == 0  # finish starts a new interval


def test_kinetic_stress_is_the_velocity_fluctuation():
    sim = lattice_sim()
    with sim.particles() as p:
        sign = np.where(np.arange(len(p)) % 2 == 0, 1.0, -1.0)
        p.velocity[:, 0] = 0.3 * sign  # half at +0.3, half at -0.3 m/s: mean zero
        mass = float(p.mass.sum())
    avg = gs.fields.CellAverages(sim, gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)), 0.02)
    sim.run(steps=1)
    avg.sample()
    f = avg.finish()
    assert np.allclose(f["velocity"], 0, atol=1e-12)
    expected_xx = mass * 0.3**2 / 0.02**3
    assert f["stress"][0, 0, 0] == pytest.approx(expected_xx, rel=1e-9)
    assert abs(f["stress"][0, 1, 1]) < 1e-9 * expected_xx
    assert f["velocity_min"][0, 0] == pytest.approx(-0.3) and f["velocity_max"][0, 0] == 0.3
    # The spread is the standard deviation about the mean: 0.3 m/s along x, none across.
    assert f["velocity_spread"][0] == pytest.approx([0.3, 0.0, 0.0], abs=1e-12)


def test_virial_of_a_bed_at_rest_balances_its_weight():
    """Summed over all cells, W_zz V = sum_i z_i (F_i,z + m_i g) + sum_floor F_z delta / 2, with
    F_i the total force on particle i at the recorded step (each particle's contact forces are
    its total force minus its weight; cell_average.hpp): an identity to round-off. In a settled
    bed it is the weight moment sum m g z to the remaining vibration."""
    box = gs.Box(lo=(0, 0, 0), hi=(0.012, 0.012, 0.03), periodic=(True, True, False))
    sim = gs.Simulation(domain=box, time_step=1e-5, record_contacts=True, quiet=True)
    sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material=GLASS))
    sim.insert(
        gs.insert.Pack(
            region=gs.Box(lo=(0, 0, 0), hi=(0.012, 0.012, 0.03)),
            radius=gs.dist.Uniform(0.9e-3, 1.1e-3),
            count=150,
            material=GLASS,
            seed=3,
        )
    )
    sim.run(until=0.6)
    avg = gs.fields.CellAverages(sim, gs.Box(lo=(0, 0, 0), hi=(0.012, 0.012, 0.03)), 0.006)
    avg.sample()
    f = avg.finish()
    volume = np.prod(avg.edge)
    with sim.particles(writable=False) as p:
        z = p.position[:, 2]
        contact_moment = float(np.sum(z * (p.force[:, 2] + 9.81 * p.mass)))
        weight_moment = float(np.sum(p.mass * 9.81 * z))
        # The kinetic part of sigma_zz (one sample: the fluctuation about each cell's mean).
        kinetic = float(np.sum(p.mass * p.velocity[:, 2] ** 2))
        weight = float(np.sum(p.mass)) * 9.81
    c = sim.contacts()
    floor = c["id_j"] == -1
    correction = float(np.sum(c["force"][floor, 2] * c["overlap"][floor] / 2))
    total_zz = float(np.sum(f["stress"][:, 2, 2])) * volume
    assert sim.kinetic_energy() < 1e-7 * weight * 2e-3
    assert kinetic < 1e-6 * weight_moment
    assert total_zz == pytest.approx(contact_moment + correction, rel=1e-9)
    assert total_zz == pytest.approx(weight_moment, rel=2e-3)
    # Stress grows with depth: the lowest layer of cells (the bed is ~7 mm deep) carries most.
    layers = f["stress"][:, 2, 2].reshape(5, -1).mean(axis=1)
    assert layers[0] > 5 * layers[1] > 0 and np.all(layers[2:] == 0)


def test_cell_averages_need_recorded_contacts():
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
    with pytest.raises(ValueError, match="record_contacts=True"):
        gs.fields.CellAverages(sim, gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), 0.005)
