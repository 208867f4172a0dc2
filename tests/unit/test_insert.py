"""Insertion and removal: size distributions, Pack, Stream, Outlet, particle deletion.

Distributions are checked against their exact (truncated) moments and CDFs; packings and streams
for overlaps, containment and mass bookkeeping; outlets for mass consistency and discharge rates.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.spatial import cKDTree

import grainscale as gs

GLASS = gs.Material(density=2500.0, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
LAW = gs.contact.HertzMindlin(restitution=0.5, friction=0.5)


def state(sim: gs.Simulation) -> dict[str, np.ndarray]:
    """Copies of the particle arrays, sorted by id."""
    with sim.particles(writable=False) as p:
        order = np.argsort(p.id)
        return {
            "id": p.id[order].copy(),
            "position": p.position[order].copy(),
            "velocity": p.velocity[order].copy(),
            "radius": p.radius[order].copy(),
            "mass": p.mass[order].copy(),
        }


def min_gap(x: np.ndarray, r: np.ndarray, among: np.ndarray | None = None) -> float:
    """Smallest surface gap |x_i - x_j| - r_i - r_j over pairs (involving ``among`` if given)."""
    if len(r) < 2:
        return math.inf
    pairs = cKDTree(x).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    if among is not None:
        pairs = pairs[among[pairs[:, 0]] | among[pairs[:, 1]]]
    if len(pairs) == 0:
        return math.inf
    d = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    return float(np.min(d - r[pairs[:, 0]] - r[pairs[:, 1]]))


def sphere_volume(r: np.ndarray) -> np.ndarray:
    return 4.0 / 3.0 * np.pi * np.asarray(r) ** 3


# --------------------------------------------------------------------------- distributions

DISTRIBUTIONS = [
    gs.dist.Monodisperse(1e-3),
    gs.dist.Uniform(min=0.8e-3, max=1.4e-3),
    gs.dist.Normal(mean=1e-3, std=0.2e-3, min=0.7e-3, max=1.5e-3),
    gs.dist.LogNormal(median=1e-3, sigma=0.3, min=0.5e-3, max=2.5e-3),
    gs.dist.Discrete(radii=(0.5e-3, 1e-3, 2e-3), weights=(0.2, 0.5, 0.3)),
    gs.dist.Discrete(radii=(0.5e-3, 1e-3, 2e-3), weights=(0.2, 0.5, 0.3), fractions="mass"),
]


@pytest.mark.parametrize("dist", DISTRIBUTIONS, ids=lambda d: type(d).__name__)
def test_sampled_moments_match_the_exact_truncated_moments(dist):
    n = 200_000
    r = dist.sample(n, seed=11)
    assert r.shape == (n,)
    assert r.min() >= dist.min_radius and r.max() <= dist.max_radius
    standard_error = dist.std_radius / math.sqrt(n)
    assert abs(r.mean() - dist.mean_radius) <= 5 * standard_error + 1e-15
    assert r.std() == pytest.approx(dist.std_radius, rel=0.015, abs=1e-15)


def test_truncated_moments_agree_with_scipy():
    d = gs.dist.Normal(mean=1e-3, std=0.2e-3, min=0.7e-3, max=1.5e-3)
    ref = stats.truncnorm((d.min - d.mean) / d.std, (d.max - d.mean) / d.std, d.mean, d.std)
    assert d.mean_radius == pytest.approx(ref.mean(), rel=1e-12)
    assert d.std_radius == pytest.approx(ref.std(), rel=1e-10)
    ln = gs.dist.LogNormal(median=1e-3, sigma=0.3, min=0.5e-3, max=2.5e-3)
    grid = np.linspace(ln.min, ln.max, 200_001)
    pdf = stats.lognorm(ln.sigma, scale=ln.median).pdf(grid)
    pdf /= np.trapezoid(pdf, grid)
    assert ln.mean_radius == pytest.approx(np.trapezoid(grid * pdf, grid), rel=1e-8)


@pytest.mark.parametrize(
    ("dist", "cdf"),
    [
        (gs.dist.Uniform(min=1e-3, max=2e-3), stats.uniform(1e-3, 1e-3).cdf),
        (
            gs.dist.Normal(mean=1e-3, std=0.2e-3, min=0.9e-3, max=1.6e-3),
            stats.truncnorm(-0.5, 3.0, 1e-3, 0.2e-3).cdf,
        ),
        (
            # Bounds far in the upper tail exercise the reflected inversion.
            gs.dist.Normal(mean=1e-3, std=0.1e-3, min=1.35e-3, max=1.5e-3),
            stats.truncnorm(3.5, 5.0, 1e-3, 0.1e-3).cdf,
        ),
        (
            gs.dist.LogNormal(median=1e-3, sigma=0.4, min=0.6e-3, max=2e-3),
            lambda x: (
                (stats.norm.cdf(np.log(x / 1e-3) / 0.4) - stats.norm.cdf(np.log(0.6) / 0.4))
                / (stats.norm.cdf(np.log(2.0) / 0.4) - stats.norm.cdf(np.log(0.6) / 0.4))
            ),
        ),
    ],
    ids=["uniform", "normal", "normal-upper-tail", "lognormal"],
)
def test_samples_follow_the_distribution(dist, cdf):
    r = dist.sample(50_000, seed=3)
    assert stats.kstest(r, cdf).pvalue > 1e-3


def test_discrete_mass_fractions_are_honoured():
    d = gs.dist.Discrete(radii=(0.5e-3, 1e-3, 2e-3), weights=(0.2, 0.5, 0.3), fractions="mass")
    r = d.sample(400_000, seed=5)
    volume = sphere_volume(r)
    fractions = [volume[r == radius].sum() / volume.sum() for radius in d.radii]
    np.testing.assert_allclose(fractions, d.weights, atol=0.01)
    assert d.number_fractions()[0] > 0.7  # the many small ones carry 20 % of the mass


def test_sampling_is_seeded_and_portable():
    d = gs.dist.LogNormal(median=1e-3, sigma=0.3)
    np.testing.assert_array_equal(d.sample(1000, seed=7), d.sample(1000, seed=7))
    assert not np.array_equal(d.sample(1000, seed=7), d.sample(1000, seed=8))
    # std::mt19937_64 is fully specified by the standard: its first output for the default seed
    # 5489 is 14514284786278117030; a radius uses its top 53 bits.
    u = (14514284786278117030 >> 11) * 2.0**-53
    assert gs.dist.Uniform(1.0, 2.0).sample(1, seed=5489)[0] == 1.0 + u


# --------------------------------------------------------------------------- Pack

BOX = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.03, 0.03, 0.03))
CYLINDER = gs.geometry.Cylinder(
    point=(0.015, 0.015, 0.0), axis=(0, 0, 1), radius=0.015, length=0.03
)


def inside_region(region, x: np.ndarray, r: np.ndarray) -> np.ndarray:
    if isinstance(region, gs.Box):
        return np.all((x - r[:, None] >= region.lo) & (x + r[:, None] <= region.hi), axis=1)
    q = x - np.asarray(region.point)
    h = q @ np.asarray(region.axis)
    rho = np.linalg.norm(q - np.outer(h, region.axis), axis=1)
    return (rho + r <= region.radius) & (h - r >= 0) & (h + r <= region.length)


@pytest.mark.parametrize("region", [BOX, CYLINDER], ids=["box", "cylinder"])
@pytest.mark.parametrize("target", [{"count": 800}, {"volume_fraction": 0.3}])
def test_pack_reaches_its_target_inside_the_region_without_overlaps(region, target):
    radius = gs.dist.Uniform(0.8e-3, 1.2e-3)
    sim = gs.Simulation(domain=BOX, contact=LAW)
    ids = sim.insert(gs.insert.Pack(region, radius=radius, material=GLASS, seed=4, **target))
    s = state(sim)
    np.testing.assert_array_equal(np.sort(ids), s["id"])
    assert np.all(inside_region(region, s["position"], s["radius"]))
    assert min_gap(s["position"], s["radius"]) >= 0.0
    if "count" in target:
        assert len(ids) == target["count"]
    else:
        volume = region.volume  # Box and finite Cylinder
        phi = sphere_volume(s["radius"]).sum() / volume
        assert abs(phi - 0.3) <= 0.5 * sphere_volume(1.2e-3) / volume + 1e-12
    # Largest first: ids follow decreasing radius.
    by_id = s["radius"][np.argsort(s["id"])]
    assert np.all(np.diff(by_id) <= 0)


def test_pack_of_equal_spheres_gets_close_to_jamming():
    """Random sequential addition of equal spheres saturates at 0.384 in bulk (Zhang & Torquato
    2013), less in a box 15 diameters wide (the walls are loosely packed). Directed sampling of the
    space left reaches 0.34 here, where 1000 uniform trials per particle stall below 0.27."""
    sim = gs.Simulation(domain=BOX, contact=LAW)
    ids = sim.insert(gs.insert.Pack(BOX, radius=1e-3, material=GLASS, volume_fraction=0.34, seed=8))
    s = state(sim)
    assert sphere_volume(1e-3) * len(ids) / BOX.volume == pytest.approx(0.34, abs=1e-3)
    assert np.all(inside_region(BOX, s["position"], s["radius"]))
    assert min_gap(s["position"], s["radius"]) >= 0.0


def test_pack_avoids_particles_already_present_and_is_reproducible():
    def build() -> gs.Simulation:
        sim = gs.Simulation(domain=BOX, contact=LAW)
        sim.insert(gs.insert.Pack(BOX, radius=1.5e-3, material=GLASS, volume_fraction=0.15, seed=1))
        sim.insert(
            gs.insert.Pack(
                CYLINDER,
                radius=gs.dist.Normal(0.8e-3, 0.1e-3),
                material=GLASS,
                volume_fraction=0.12,
                seed=2,
            )
        )
        return sim

    a, b = build(), build()
    s = state(a)
    assert min_gap(s["position"], s["radius"]) >= 0.0
    np.testing.assert_array_equal(s["position"], state(b)["position"])


def test_pack_refuses_an_impossible_target_and_inserts_nothing():
    sim = gs.Simulation(domain=BOX, contact=LAW)
    with pytest.raises(RuntimeError, match=r"Pack placed only \d+ of \d+ particles") as err:
        sim.insert(gs.insert.Pack(BOX, radius=1e-3, material=GLASS, volume_fraction=0.6, seed=1))
    assert "Nothing was inserted" in str(err.value)
    assert sim.num_particles == 0
    with pytest.raises(RuntimeError, match="does not fit inside the region"):
        sim.insert(gs.insert.Pack(BOX, radius=0.02, material=GLASS, count=1))
    outside = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.03, 0.03, 0.05))
    with pytest.raises(ValueError, match="Pack.region must be inside the simulation domain"):
        sim.insert(gs.insert.Pack(outside, radius=1e-3, material=GLASS, count=1))


# --------------------------------------------------------------------------- Stream

POUR_BOX = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.03, 0.03, 0.08))
TOP = gs.insert.RectangleFace(corner=(0.0, 0.0, 0.08), edge1=(0.03, 0, 0), edge2=(0, 0.03, 0))


def pouring(mass_rate: float = 0.05, **stream) -> tuple[gs.Simulation, gs.insert.StreamHandle]:
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW)
    for wall in gs.geometry.box_walls(POUR_BOX, GLASS):
        sim.add_wall(wall)
    stream.setdefault("radius", gs.dist.Uniform(1.2e-3, 1.6e-3))
    stream.setdefault("velocity", (0.0, 0.0, -1.0))
    handle = sim.insert(
        gs.insert.Stream(TOP, mass_rate=mass_rate, material=GLASS, seed=3, **stream)
    )
    return sim, handle


def test_stream_delivers_the_mass_rate_without_overlaps():
    sim, h = pouring()
    assert sim.time_step is None  # picked from the stream's smallest particle at the first run
    # Step by step through the first batches: new particles never overlap anything.
    checked = 0
    while sim.time < 0.03:
        before = h.inserted_count
        sim.run(steps=1)
        if h.inserted_count > before:
            s = state(sim)
            new = s["id"] >= s["id"].max() - (h.inserted_count - before) + 1
            assert min_gap(s["position"], s["radius"], among=new) >= 0.0
            assert np.all(h.slab().contains(s["position"][new], 0.0))
            checked += 1
    assert checked >= 10
    sim.run(until=0.5)
    status = h.status()
    assert status["requested_mass"] == pytest.approx(0.05 * sim.time, rel=1e-12)
    assert h.inserted_mass == pytest.approx(h.requested_mass, rel=0.02)
    # Inserted + pending = scheduled, which leads the request by at most a batch and a particle.
    assert h.pending_mass == 0.0 and h.scheduled_mass == h.inserted_mass
    lead = h.scheduled_mass - h.requested_mass
    assert -1e-12 <= lead <= 0.05 * h.interval + GLASS.density * sphere_volume(1.6e-3)
    s = state(sim)
    assert len(s["id"]) == h.inserted_count and sim.lost_particles == 0
    assert s["mass"].sum() == pytest.approx(h.inserted_mass, rel=1e-12)


def test_stream_and_outlet_do_not_depend_on_run_chunking():
    """Insertion and removal (also of particles in contact) happen inside the steps: the same
    trajectory whether run() is called once or in many small chunks."""

    def build() -> tuple[gs.Simulation, gs.insert.StreamHandle, gs.insert.OutletHandle]:
        sim, h = pouring(every=2.5e-3)
        hole = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.012, 0.012, 0.003))  # a drain in one corner
        return sim, h, sim.add_outlet(gs.insert.Outlet(hole))

    a, ha, oa = build()
    a.run(until=0.2)
    b, hb, ob = build()
    b.time_step = a.time_step
    while b.step < a.step:
        b.run(steps=min(37, a.step - b.step))
    sa, sb = state(a), state(b)
    assert a.num_contacts() > 50 and oa.removed_count > 5
    np.testing.assert_array_equal(sa["id"], sb["id"])
    np.testing.assert_array_equal(sa["position"], sb["position"])
    assert ha.status() == hb.status()
    assert oa.removed_mass == ob.removed_mass


def test_stream_starts_when_registered_unless_told_otherwise():
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW, time_step=2e-5)
    sim.run(steps=500)
    t0 = sim.time
    now = sim.insert(
        gs.insert.Stream(TOP, mass_rate=0.05, radius=1e-3, material=GLASS, velocity=(0, 0, -1))
    )
    late = sim.insert(
        gs.insert.Stream(
            TOP,
            mass_rate=0.05,
            radius=1e-3,
            material=GLASS,
            velocity=(0, 0, -1),
            start=0.02,
            stop=0.025,
            seed=1,
        )
    )
    sim.run(until=0.03)
    assert now.requested_mass == pytest.approx(0.05 * (sim.time - t0), rel=1e-9)
    assert late.requested_mass == pytest.approx(0.05 * 0.005, rel=1e-9)
    assert late.scheduled_mass == late.inserted_mass >= late.requested_mass


def test_blocked_slab_carries_pending_mass_over_until_it_is_free():
    """A lid of touching spheres fills the slab: nothing fits, the due mass stays pending; once
    the lid is removed the backlog is inserted and the stream catches up."""
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW, gravity=(0.0, 0.0, 0.0))
    r = 1e-3
    h = sim.insert(
        gs.insert.Stream(
            TOP, mass_rate=0.02, radius=r, material=GLASS, velocity=(0, 0, -1.0), seed=9
        )
    )
    outlet = sim.add_outlet(gs.insert.Outlet(gs.Box(lo=(0, 0, -1), hi=(0.03, 0.03, 0.02))))
    slab = gs.Box(lo=(0.0, 0.0, 0.08 - h.status()["thickness"]), hi=(0.03, 0.03, 0.08))
    # Simple-cubic lattice of spacing 2r: its largest hole holds a sphere of radius 0.73 r.
    lid_positions = gs.insert.lattice(slab, spacing=2 * r)
    lid = sim.add_particles(position=lid_positions, radius=0.99999 * r, material=GLASS)
    sim.run(until=0.02)
    assert h.inserted_count == 0
    assert h.pending_mass == pytest.approx(h.scheduled_mass, rel=1e-12)
    assert h.pending_mass >= h.requested_mass > 0
    assert sim.remove_particles(lid) == len(lid)
    sim.run(until=0.12)
    assert h.pending_count == 0
    # Caught up: what is inserted leads the request by at most one batch and one particle.
    particle = GLASS.density * sphere_volume(r)
    assert 0 <= h.inserted_mass - h.requested_mass <= 0.02 * h.interval + particle
    s = state(sim)
    assert s["mass"].sum() + outlet.removed_mass == pytest.approx(h.inserted_mass, rel=1e-12)
    assert min_gap(s["position"], s["radius"]) >= -1e-9


# --------------------------------------------------------------------------- Outlet


def test_outlet_removes_and_counts_mass_with_a_discharge_history():
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW)
    fill = gs.Box(lo=(0.0, 0.0, 0.04), hi=(0.03, 0.03, 0.08))
    sim.insert(
        gs.insert.Pack(
            fill, radius=gs.dist.Uniform(1e-3, 1.5e-3), material=GLASS, count=300, seed=2
        )
    )
    before = state(sim)
    outlet = sim.add_outlet(gs.insert.Outlet(gs.Box(lo=(0, 0, -1), hi=(0.03, 0.03, 0.01))))
    sim.run(until=0.1)
    after = state(sim)
    gone = ~np.isin(before["id"], after["id"])
    assert outlet.removed_count == gone.sum() > 50
    assert outlet.removed_mass == pytest.approx(before["mass"][gone].sum(), rel=1e-12)
    assert np.all(after["position"][:, 2] > 0.01)
    t, m, c = outlet.history()
    assert t[0] == 0.0 and m[0] == 0.0 and c[-1] == outlet.removed_count
    assert m[-1] == pytest.approx(outlet.removed_mass, rel=1e-12)
    assert np.all(np.diff(t) > 0) and np.all(np.diff(m) > 0)


def test_outlet_discharge_rate_matches_a_steady_stream():
    box = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.03, 0.03, 0.05))
    top = gs.insert.DiscFace(centre=(0.015, 0.015, 0.05), normal=(0, 0, -1), radius=0.014)
    sim = gs.Simulation(domain=box, contact=LAW)
    sim.insert(
        gs.insert.Stream(
            top,
            mass_rate=0.05,
            radius=gs.dist.Uniform(1.2e-3, 1.6e-3),
            material=GLASS,
            velocity=(0, 0, -1.0),
            seed=1,
        )
    )
    outlet = sim.add_outlet(gs.insert.Outlet(gs.Box(lo=(0, 0, -1), hi=(0.03, 0.03, 0.005))))
    sim.run(until=0.25)
    t, m, _ = outlet.history()
    steady = t > 0.08
    rate = np.polyfit(t[steady], m[steady], 1)[0]
    assert rate == pytest.approx(0.05, rel=0.03)


def test_removing_particles_keeps_the_contact_histories_of_the_others():
    """Two identical resting beds with friction; in one, a free particle far above is deleted.
    The contact forces (whose tangential part lives in the histories) must not change."""

    def bed() -> tuple[gs.Simulation, int]:
        box = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.02, 0.02, 0.06))
        sim = gs.Simulation(
            domain=box, contact=LAW, gravity=(0.3, 0.0, -9.81), record_contacts=True
        )
        for wall in gs.geometry.box_walls(box, GLASS):
            sim.add_wall(wall)
        sim.insert(
            gs.insert.Pack(
                gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)),
                radius=1e-3,
                material=GLASS,
                count=150,
                seed=5,
            )
        )
        lone = sim.add_particles(position=[[0.01, 0.01, 0.055]], radius=1e-3, material=GLASS)
        return sim, int(lone[0])

    a, _ = bed()
    b, lone = bed()
    a.run(until=0.08)
    b.run(until=0.08)
    assert b.remove_particles([lone, 10**9]) == 1
    a.run(steps=1)
    b.run(steps=1)
    ca, cb = a.contacts(), b.contacts()
    key_a = {
        (int(i), int(j)): f for i, j, f in zip(ca["id_i"], ca["id_j"], ca["force"], strict=True)
    }
    key_b = {
        (int(i), int(j)): f for i, j, f in zip(cb["id_i"], cb["id_j"], cb["force"], strict=True)
    }
    assert key_a.keys() == key_b.keys() and len(key_a) > 100
    scale = max(np.linalg.norm(f) for f in key_a.values())
    for k, f in key_a.items():
        np.testing.assert_allclose(key_b[k], f, atol=1e-9 * scale)


def test_checkpoint_restores_streams_and_outlets():
    pytest.importorskip("h5py")
    import tempfile

    def build() -> tuple[gs.Simulation, gs.insert.StreamHandle, gs.insert.OutletHandle]:
        sim, h = pouring(every=2e-3)
        sim.time_step = 2e-5
        sim.skin = 3e-4  # a restart into an empty simulation needs the skin given
        o = sim.add_outlet(gs.insert.Outlet(gs.Box(lo=(0, 0, -1), hi=(0.03, 0.03, 0.03))))
        return sim, h, o

    a, ha, oa = build()
    a.run(until=0.05)
    with tempfile.TemporaryDirectory() as tmp:
        path = f"{tmp}/run.h5"
        a.checkpoint(path)
        a.run(until=0.1)
        b, hb, ob = build()
        b.restart(path)
    b.run(until=0.1)
    np.testing.assert_array_equal(state(a)["position"], state(b)["position"])
    assert ha.status() == hb.status()
    for x, y in zip(oa.history(), ob.history(), strict=True):
        np.testing.assert_array_equal(x, y)


# --------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("factory", "message"),
    [
        (
            lambda: gs.dist.Uniform(min=-1, max=1),
            "Uniform.min must be positive and finite (m), got -1",
        ),
        (lambda: gs.dist.Uniform(min=2e-3, max=1e-3), "Uniform.max must be >= Uniform.min"),
        (lambda: gs.dist.Monodisperse(0), "Monodisperse.radius must be positive and finite (m)"),
        (
            lambda: gs.dist.Normal(mean=1e-3, std=0.5e-3),
            "Normal.min must be positive (m), got -",
        ),
        (lambda: gs.dist.Normal(mean=1e-3, std=-1), "Normal.std must be non-negative"),
        (
            lambda: gs.dist.Normal(mean=1e-3, std=1e-5, min=2e-3, max=3e-3),
            "Normal.min must be such that [min, max] holds some probability",
        ),
        (lambda: gs.dist.LogNormal(median=1e-3, sigma=float("nan")), "LogNormal.sigma must be"),
        (
            lambda: gs.dist.Discrete(radii=(1e-3, 2e-3), weights=(1.0,)),
            "Discrete.weights must have one weight per radius (2), got 1",
        ),
        (
            lambda: gs.dist.Discrete(radii=(1e-3,), weights=(1.0,), fractions="volume"),
            "Discrete.fractions must be 'number' or 'mass', got 'volume'",
        ),
        (
            lambda: gs.insert.Pack(BOX, radius=1e-3, material=GLASS),
            "Pack needs exactly one of count and volume_fraction",
        ),
        (
            lambda: gs.insert.Pack(BOX, radius=1e-3, material=GLASS, volume_fraction=1.5),
            "Pack.volume_fraction must be in [0, 1], got 1.5",
        ),
        (
            lambda: gs.insert.Pack(BOX, radius=-1e-3, material=GLASS, count=3),
            "Pack.radius must be positive and finite (m), got -0.001",
        ),
        (
            lambda: gs.insert.Pack(
                gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=1.0),
                radius=1e-3,
                material=GLASS,
                count=3,
            ),
            "Pack.region must be a finite Cylinder",
        ),
        (
            lambda: gs.insert.Stream(TOP, mass_rate=-1, radius=1e-3, material=GLASS),
            "Stream.mass_rate must be positive and finite (kg/s), got -1",
        ),
        (
            lambda: gs.insert.Stream(TOP, mass_rate=1, radius=1e-3, material=GLASS),
            "Stream.every must be given when the velocity has no component across the face",
        ),
        (
            lambda: gs.insert.Stream(
                TOP,
                mass_rate=1,
                radius=1e-3,
                material=GLASS,
                velocity=(0, 0, -1),
                start=1.0,
                stop=0.5,
            ),
            "Stream.stop must be greater than start",
        ),
        (
            lambda: gs.insert.DiscFace(centre=(0, 0, 0), normal=(0, 0, 0), radius=1),
            "DiscFace.normal must be a non-zero vector",
        ),
        (lambda: gs.insert.Outlet(BOX, every=0), "Outlet.every must be a positive integer, got 0"),
    ],
)
def test_invalid_parameters_name_parameter_constraint_and_value(factory, message):
    with pytest.raises(ValueError) as err:
        factory()
    assert message in str(err.value)


def test_stream_checks_fit_domain_and_time_step():
    sim = gs.Simulation(domain=POUR_BOX, contact=LAW, time_step=1e-3)
    stream = gs.insert.Stream(TOP, mass_rate=0.05, radius=1e-3, material=GLASS, velocity=(0, 0, -1))
    with pytest.raises(
        ValueError,
        match=r"Simulation.time_step must be at most 0.3 x the "
        r"Rayleigh time of the smallest streamed particle",
    ):
        sim.insert(stream)
    sim.time_step = 1e-5
    wrong_side = gs.insert.Stream(
        TOP, mass_rate=0.05, radius=1e-3, material=GLASS, velocity=(0, 0, 1)
    )
    with pytest.raises(
        ValueError,
        match=r"Stream.face \(with its insertion slab .* must be "
        r"inside the simulation domain \[0, 0.08\] on axis z",
    ):
        sim.insert(wrong_side)
    tiny = gs.insert.DiscFace(centre=(0.015, 0.015, 0.08), normal=(0, 0, -1), radius=0.5e-3)
    with pytest.raises(ValueError, match="Stream.face must be large enough for the largest"):
        sim.insert(
            gs.insert.Stream(tiny, mass_rate=0.05, radius=1e-3, material=GLASS, velocity=(0, 0, -1))
        )
    with pytest.warns(UserWarning, match="Stream volume fraction"):
        sim.insert(
            gs.insert.Stream(TOP, mass_rate=5.0, radius=1e-3, material=GLASS, velocity=(0, 0, -1))
        )
