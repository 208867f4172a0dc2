"""Conservation in a fully periodic box without walls or gravity.

* Linear momentum: pair forces are equal and opposite (also across periodic boundaries), so the
  total momentum is conserved to round-off even with damping and friction: gate 1e-12 relative
  to sum |m_i v_i|.
* Energy: elastic Hertz (e = 1, friction 0): kinetic energy plus the Hertz potential
  (8/15) E* sqrt(R*) delta^(5/2) of the current overlaps is conserved within 1e-3 relative
  (velocity Verlet: bounded, non-secular error).
"""

from __future__ import annotations

import math

import numpy as np

import grainscale as gs

BOX = 18e-3
N = 300
R_MIN, R_MAX = 0.8e-3, 1.2e-3
MATERIAL = gs.Material(density=2500.0, youngs_modulus=1e8, poisson_ratio=0.3, name="soft")


def dense_gas(seed, n=N, gap=0.0):
    """Random non-overlapping spheres in the periodic box (solid fraction ~ 0.2)."""
    rng = np.random.default_rng(seed)
    xs = np.zeros((0, 3))
    rs = np.zeros(0)
    for r in rng.uniform(R_MIN, R_MAX, n):
        for _ in range(10000):
            x = rng.uniform(0.0, BOX, 3)
            d = xs - x
            d -= BOX * np.round(d / BOX)
            if np.all(np.linalg.norm(d, axis=1) > rs + r + gap):
                xs = np.vstack([xs, x])
                rs = np.append(rs, r)
                break
        else:
            raise RuntimeError("packing too dense")
    return rng, xs, rs


def make_sim(law, time_step):
    return gs.Simulation(
        record_contacts=True,
        domain=gs.Box(lo=(0.0, 0.0, 0.0), hi=(BOX, BOX, BOX), periodic=(True, True, True)),
        contact=law,
        gravity=(0.0, 0.0, 0.0),
        time_step=time_step,
        thermo_every=10**9,
    )


def rayleigh_time(radius):
    g = MATERIAL.shear_modulus
    nu = MATERIAL.poisson_ratio
    return math.pi * radius * math.sqrt(MATERIAL.density / g) / (0.1631 * nu + 0.8766)


def state(sim):
    with sim.particles() as p:
        order = np.argsort(p.id)
        return (
            np.array(p.id[order]),
            np.array(p.mass[order]),
            np.array(p.radius[order]),
            np.array(p.velocity[order]),
            np.array(p.angular_velocity[order]),
        )


def test_linear_momentum_conserved():
    rng, x, r = dense_gas(seed=3)
    v = rng.normal(0.0, 0.5, (N, 3)) + np.array([0.3, -0.2, 0.1])
    w = rng.normal(0.0, 300.0, (N, 3))
    law = gs.contact.HertzMindlin(restitution=0.5, friction=0.5)
    sim = make_sim(law, 0.1 * rayleigh_time(R_MIN))
    sim.add_particles(position=x, radius=r, material=MATERIAL, velocity=v, angular_velocity=w)
    _, m, _, v0, _ = state(sim)
    p0 = (m[:, None] * v0).sum(axis=0)
    scale = float(np.sum(m * np.linalg.norm(v0, axis=1)))
    ke_rel0 = 0.5 * np.sum(m[:, None] * (v0 - p0 / m.sum()) ** 2)
    worst, contacts_seen = 0.0, 0
    for _ in range(20):
        sim.run(steps=100)
        _, m, _, vel, _ = state(sim)
        p = (m[:, None] * vel).sum(axis=0)
        err = float(np.linalg.norm(p - p0)) / scale
        worst = max(worst, err)
        contacts_seen += sim.num_contacts()
        assert err <= 1e-12, (
            f"step {sim.step}: total momentum {p} vs initial {p0} kg m/s, |dP| / sum|m v| = "
            f"{err:.3e} > 1e-12"
        )
    ke_rel = 0.5 * np.sum(m[:, None] * (vel - p0 / m.sum()) ** 2)
    # The dynamics must actually be collisional for the check to mean anything.
    assert contacts_seen > 20, f"only {contacts_seen} contacts seen at the checks"
    assert ke_rel < 0.9 * ke_rel0, (
        f"peculiar kinetic energy {ke_rel0:.4e} -> {ke_rel:.4e} J: too few dissipative collisions"
    )


def _hertz_potential(sim, row, radius):
    c = sim.contacts()
    if len(c["id_i"]) == 0:
        return 0.0, 0
    ri = radius[[row[int(k)] for k in c["id_i"]]]
    rj = radius[[row[int(k)] for k in c["id_j"]]]
    nu, e = MATERIAL.poisson_ratio, MATERIAL.youngs_modulus
    e_star = e / (2.0 * (1.0 - nu**2))
    r_star = ri * rj / (ri + rj)
    delta = np.asarray(c["overlap"])
    return float(np.sum(8.0 / 15.0 * e_star * np.sqrt(r_star) * delta**2.5)), len(delta)


def test_energy_conserved_elastic():
    rng, x, r = dense_gas(seed=7)
    v = rng.normal(0.0, 0.5, (N, 3))
    law = gs.contact.HertzMindlin(restitution=1.0, friction=0.0)
    sim = make_sim(law, 0.1 * rayleigh_time(R_MIN))
    sim.add_particles(position=x, radius=r, material=MATERIAL, velocity=v)
    ids, m, rad, vel, omega = state(sim)
    row = {int(k): n for n, k in enumerate(ids)}
    e0 = 0.5 * float(np.sum(m[:, None] * vel**2))
    assert abs(sim.kinetic_energy() / e0 - 1.0) <= 1e-12, (
        f"kinetic_energy() = {sim.kinetic_energy():.15e} J, sum m v^2 / 2 = {e0:.15e} J"
    )
    worst, pe_max, pairs_seen = 0.0, 0.0, 0
    for _ in range(100):
        sim.run(steps=20)
        ids, m, rad, vel, omega = state(sim)
        row = {int(k): n for n, k in enumerate(ids)}
        ke = sim.kinetic_energy()
        inertia = 0.4 * m * rad**2
        ke_arrays = 0.5 * np.sum(m[:, None] * vel**2) + 0.5 * np.sum(inertia[:, None] * omega**2)
        assert abs(ke / ke_arrays - 1.0) <= 1e-12, (
            f"step {sim.step}: kinetic_energy() = {ke:.15e} J but arrays give {ke_arrays:.15e} J"
        )
        pe, n_contacts = _hertz_potential(sim, row, rad)
        pairs_seen += n_contacts
        pe_max = max(pe_max, pe / e0)
        err = (ke + pe) / e0 - 1.0
        worst = max(worst, abs(err))
        assert abs(err) <= 1e-3, (
            f"step {sim.step}: KE {ke:.6e} J + Hertz PE {pe:.6e} J = {ke + pe:.6e} J vs initial "
            f"{e0:.6e} J (relative error {err:+.3e} > 1e-3)"
        )
    assert pairs_seen > 100, f"only {pairs_seen} contacts over the checks: not collisional"
    assert pe_max > 1e-5, f"Hertz potential never above {pe_max:.2e} of the energy"
