"""Verlet neighbour list vs brute force (DESIGN.md 2.3).

Polydisperse packings (radius ratio 1:3), periodic in all axes or in some (plane walls close the
other axes). Checks:
* at a build (particles at rest, nothing moves): the list equals the brute-force set of pairs with
  |x_i - x_j| < r_i + r_j + skin (minimum image on periodic axes), also after an insertion;
* while moving through many rebuilds: no self or duplicate pairs, every overlapping pair is listed,
  no listed pair is farther than r_i + r_j + 2 skin (each particle moves < skin/2 between builds),
  and sim.contacts() holds exactly the brute-force overlapping particle pairs and wall contacts.
"""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

R_MIN, R_MAX = 0.5e-3, 1.5e-3
BOX = 22e-3
MATERIAL = gs.Material(density=2500.0, youngs_modulus=5e7, poisson_ratio=0.3, name="soft")
PERIODIC = {
    "xyz": (True, True, True),
    "xy": (True, True, False),
    "z": (False, False, True),
}
EPS = 1e-12  # m; pairs this close to a cutoff are ambiguous in floating point and skipped


def random_packing(rng, n, periodic, lo=0.0, hi=BOX, existing=None, gap=0.0):
    """Random sequential placement of n non-overlapping spheres, r uniform in [R_MIN, R_MAX].

    On non-periodic axes the spheres stay inside [lo + r, hi - r]. ``existing`` = (x, r) to avoid.
    """
    per = np.asarray(periodic)
    xs = [] if existing is None else list(existing[0])
    rs = [] if existing is None else list(existing[1])
    n0 = len(xs)
    radii = rng.uniform(R_MIN, R_MAX, n)
    if existing is None:
        radii[:2] = (R_MAX, R_MIN)  # the full 1:3 ratio is always present
    for r in radii:
        for _ in range(10000):
            low = np.where(per, lo, lo + r + gap)
            high = np.where(per, hi, hi - r - gap)
            x = rng.uniform(low, high)
            if xs:
                d = min_image(np.asarray(xs) - x, periodic, hi - lo)
                if np.any(np.linalg.norm(d, axis=1) <= np.asarray(rs) + r + gap):
                    continue
            xs.append(x)
            rs.append(r)
            break
        else:
            raise RuntimeError("packing too dense for random sequential placement")
    return np.array(xs[n0:]), np.array(rs[n0:])


def min_image(d, periodic, length):
    d = np.array(d, dtype=float)
    for a in range(3):
        if periodic[a]:
            d[..., a] -= length * np.round(d[..., a] / length)
    return d


def pair_gaps(x, r, ids, periodic, length):
    """All unordered pairs (id_small, id_large) -> gap = |x_i - x_j| - r_i - r_j."""
    i, j = np.triu_indices(len(x), 1)
    dist = np.linalg.norm(min_image(x[i] - x[j], periodic, length), axis=1)
    gap = dist - r[i] - r[j]
    a, b = ids[i], ids[j]
    keys = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)
    return keys, gap


def as_set(keys):
    return {(int(a), int(b)) for a, b in keys}


def add_walls(sim, periodic):
    """Plane walls on the non-periodic axes; returns {wall index: (axis, side)} in add order."""
    walls = {}
    for axis in range(3):
        if periodic[axis]:
            continue
        for side, point, normal in ((0, 0.0, 1.0), (1, BOX, -1.0)):
            p = [0.0, 0.0, 0.0]
            n = [0.0, 0.0, 0.0]
            p[axis], n[axis] = point, normal
            sim.add_wall(gs.geometry.Plane(point=tuple(p), normal=tuple(n), material=None))
            walls[len(walls)] = (axis, side)
    return walls


def make_sim(periodic, skin):
    return gs.Simulation(
        domain=gs.Box(lo=(0.0, 0.0, 0.0), hi=(BOX, BOX, BOX), periodic=periodic),
        contact=gs.contact.HertzMindlin(restitution=1.0, friction=0.3),
        gravity=(0.0, 0.0, 0.0),
        skin=skin,
        thermo_every=10**9,
    )


def snapshot(sim):
    with sim.particles() as p:
        order = np.argsort(p.id)
        return (np.array(p.id[order]), np.array(p.position[order]), np.array(p.radius[order]))


def check_pairs_array(pairs, ids, where):
    assert pairs.ndim == 2 and pairs.shape[1] == 2, f"{where}: neighbor_pairs shape {pairs.shape}"
    assert pairs.dtype == np.int64, f"{where}: neighbor_pairs dtype {pairs.dtype}"
    self_pairs = int(np.sum(pairs[:, 0] == pairs[:, 1]))
    assert self_pairs == 0, f"{where}: {self_pairs} self pairs in the neighbour list"
    keys = np.sort(pairs, axis=1)
    n_unique = len(np.unique(keys, axis=0)) if len(keys) else 0
    assert n_unique == len(keys), f"{where}: {len(keys) - n_unique} duplicate pairs in the list"
    unknown = np.setdiff1d(pairs.ravel(), ids)
    assert unknown.size == 0, f"{where}: unknown ids in the neighbour list: {unknown[:10]}"
    return as_set(keys)


@pytest.mark.parametrize("skin", [None, 0.1e-3], ids=["default_skin", "skin_0.1mm"])
@pytest.mark.parametrize("geometry", list(PERIODIC))
def test_list_equals_brute_force_at_build(geometry, skin):
    periodic = PERIODIC[geometry]
    rng = np.random.default_rng(11)
    x, r = random_packing(rng, 350, periodic, gap=1e-6)
    sim = make_sim(periodic, skin)
    add_walls(sim, periodic)
    sim.add_particles(position=x, radius=r, material=MATERIAL)
    for stage in ("first build", "after insertion"):
        ids0, x0, _ = snapshot(sim)
        sim.run(steps=1)
        ids, x1, rad = snapshot(sim)
        s = sim.skin
        assert s > 0, f"sim.skin = {s}"
        moved = np.max(np.abs(min_image(x1 - x0, periodic, BOX)))
        assert np.array_equal(ids, ids0) and moved == 0.0, (
            f"{geometry} {stage}: particles at rest without contacts moved by {moved:.3e} m"
        )
        where = f"{geometry} skin={s:.3e} {stage}"
        listed = check_pairs_array(sim.neighbor_pairs(), ids, where)
        keys, gap = pair_gaps(x1, rad, ids, periodic, BOX)
        clear = np.abs(gap - s) > EPS
        expected = as_set(keys[(gap < s) & clear])
        listed_clear = listed - as_set(keys[~clear])
        missing = sorted(expected - listed_clear)
        extra = sorted(listed_clear - expected)
        assert not missing and not extra, (
            f"{where}: list differs from brute force with cutoff r_i + r_j + skin: "
            f"{len(missing)} missing (e.g. {missing[:5]}), {len(extra)} extra "
            f"(e.g. {extra[:5]}); {len(expected)} expected"
        )
        assert len(expected) > len(x1), f"{where}: only {len(expected)} pairs, test too sparse"
        if stage == "first build":
            # Insert a second batch; the list must be rebuilt to include the new particles.
            xn, rn = random_packing(rng, 60, periodic, existing=(x1, rad), gap=1e-6)
            sim.add_particles(position=xn, radius=rn, material=MATERIAL)


@pytest.mark.parametrize("skin", [None, 0.05e-3], ids=["default_skin", "skin_0.05mm"])
@pytest.mark.parametrize("geometry", list(PERIODIC))
def test_list_and_contacts_through_rebuilds(geometry, skin):
    periodic = PERIODIC[geometry]
    rng = np.random.default_rng(5)
    x, r = random_packing(rng, 400, periodic)
    v = rng.normal(0.0, 1.0, (len(x), 3))
    sim = make_sim(periodic, skin)
    walls = add_walls(sim, periodic)
    sim.add_particles(position=x, radius=r, material=MATERIAL, velocity=v)
    sim.run(steps=1)
    s = sim.skin
    distinct_lists = set()
    path = np.zeros(len(x))
    _, x_prev, _ = snapshot(sim)
    n_overlaps_seen = 0
    n_wall_contacts_seen = 0
    checks = 0
    while sim.step < 1500:
        sim.run(steps=int(rng.integers(1, 30)))
        checks += 1
        ids, xs, rad = snapshot(sim)
        where = f"{geometry} skin={s:.3e} step {sim.step}"
        path += np.linalg.norm(min_image(xs - x_prev, periodic, BOX), axis=1)
        x_prev = xs
        listed = check_pairs_array(sim.neighbor_pairs(), ids, where)
        distinct_lists.add(frozenset(listed))
        keys, gap = pair_gaps(xs, rad, ids, periodic, BOX)
        gap_of = dict(zip(map(tuple, keys.tolist()), gap.tolist()))

        overlapping = as_set(keys[gap < -EPS])
        missing = sorted(overlapping - listed)
        assert not missing, (
            f"{where}: {len(missing)} overlapping pairs not in the neighbour list, e.g. "
            f"{[(m, gap_of[m]) for m in missing[:5]]}"
        )
        too_far = sorted(p for p in listed if gap_of[p] >= 2.0 * s + EPS)
        assert not too_far, (
            f"{where}: {len(too_far)} listed pairs farther than r_i + r_j + 2 skin "
            f"({2 * s:.3e} m), e.g. {[(p, gap_of[p]) for p in too_far[:5]]}"
        )

        c = sim.contacts()
        is_wall = c["id_j"] < 0
        got = np.stack([c["id_i"][~is_wall], c["id_j"][~is_wall]], axis=1)
        got_keys = np.sort(got, axis=1) if len(got) else np.zeros((0, 2), np.int64)
        got_set = as_set(got_keys)
        assert len(got_set) == len(got_keys), f"{where}: duplicate contacts in sim.contacts()"
        ambiguous = as_set(keys[np.abs(gap) <= EPS])
        missing = sorted(overlapping - got_set)
        extra = sorted(got_set - overlapping - ambiguous)
        assert not missing and not extra, (
            f"{where}: sim.contacts() vs brute-force overlaps: missing "
            f"{[(m, gap_of[m]) for m in missing[:5]]}, extra {[(e, gap_of[e]) for e in extra[:5]]}"
        )
        n_overlaps_seen += len(overlapping)

        # Wall contacts: plane at lo (normal +e_a) or hi (normal -e_a) on non-periodic axes.
        row = {int(k): n for n, k in enumerate(ids)}
        expected_wall = set()
        for w, (axis, side) in walls.items():
            wgap = (xs[:, axis] if side == 0 else BOX - xs[:, axis]) - rad
            expected_wall |= {(int(ids[k]), -1 - w) for k in np.nonzero(wgap < -EPS)[0]}
        got_wall = {(int(a), int(b)) for a, b in zip(c["id_i"][is_wall], c["id_j"][is_wall])}
        for a, b in got_wall - expected_wall:
            axis, side = walls[-1 - b]
            xa = xs[row[a], axis]
            wgap = (xa if side == 0 else BOX - xa) - rad[row[a]]
            assert abs(wgap) <= EPS, f"{where}: spurious wall contact {(a, b)} with gap {wgap:.3e}"
        assert expected_wall <= got_wall, (
            f"{where}: missing wall contacts {sorted(expected_wall - got_wall)[:5]}"
        )
        n_wall_contacts_seen += len(got_wall)
        assert sim.num_contacts() == len(c["id_i"]), (
            f"{where}: num_contacts() = {sim.num_contacts()} but contacts() has {len(c['id_i'])}"
        )

    assert checks >= 50, f"only {checks} checks"
    assert np.median(path) > 10.0 * s, (
        f"median path {np.median(path):.3e} m is not >> skin {s:.3e} m: too few rebuilds exercised"
    )
    assert len(distinct_lists) >= 10, f"neighbour list changed only {len(distinct_lists)} times"
    assert n_overlaps_seen > 50, f"only {n_overlaps_seen} overlaps seen: no collisions exercised"
    if walls:
        assert n_wall_contacts_seen > 0, "no wall contacts exercised"
