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


def gap_matrix(x, r, periodic, length=BOX):
    """(N, N) matrix of |x_i - x_j| - r_i - r_j (minimum image on periodic axes)."""
    d = min_image(x[:, None, :] - x[None, :, :], periodic, length)
    return np.linalg.norm(d, axis=2) - r[:, None] - r[None, :]


def pair_mask(pairs, ids, where, what):
    """Upper-triangular (N, N) mask of the id pairs; checks shape, dtype, self pairs, duplicates.

    ``ids`` must be sorted; the mask is indexed by position in ``ids``.
    """
    n = len(ids)
    pairs = np.asarray(pairs)
    assert pairs.ndim == 2 and pairs.shape[1] == 2, f"{where}: {what} shape {pairs.shape}"
    assert pairs.dtype == np.int64, f"{where}: {what} dtype {pairs.dtype}"
    rows = np.searchsorted(ids, pairs)
    rows_ok = np.clip(rows, 0, n - 1)
    unknown = pairs[ids[rows_ok] != pairs]
    assert unknown.size == 0, f"{where}: unknown ids in {what}: {unknown[:10]}"
    n_self = int(np.sum(pairs[:, 0] == pairs[:, 1]))
    assert n_self == 0, f"{where}: {n_self} self pairs in {what}"
    lo, hi = np.minimum(rows[:, 0], rows[:, 1]), np.maximum(rows[:, 0], rows[:, 1])
    counts = np.bincount(lo * n + hi, minlength=n * n)
    n_dup = int(np.sum(counts > 1))
    assert n_dup == 0, f"{where}: {n_dup} duplicate pairs in {what}"
    return counts.reshape(n, n) > 0


def examples(mask, ids, gap, k=5):
    rows = np.argwhere(mask)[:k]
    return [(int(ids[a]), int(ids[b]), float(f"{gap[a, b]:.3e}")) for a, b in rows]


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
        record_contacts=True,
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
        listed = pair_mask(sim.neighbor_pairs(), ids, where, "neighbor_pairs()")
        gap = gap_matrix(x1, rad, periodic)
        upper = np.triu(np.ones_like(listed), 1)
        expected = upper & (gap < s)
        clear = np.abs(gap - s) > EPS
        missing = expected & ~listed & clear
        extra = listed & ~expected & clear
        assert not missing.any() and not extra.any(), (
            f"{where}: list differs from brute force with cutoff r_i + r_j + skin: "
            f"{missing.sum()} missing (id, id, gap: {examples(missing, ids, gap)}), "
            f"{extra.sum()} extra ({examples(extra, ids, gap)}); {expected.sum()} expected"
        )
        assert expected.sum() >= 30, f"{where}: only {expected.sum()} pairs, test too sparse"
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
        listed = pair_mask(sim.neighbor_pairs(), ids, where, "neighbor_pairs()")
        distinct_lists.add(np.packbits(listed).tobytes())
        gap = gap_matrix(xs, rad, periodic)
        upper = np.triu(np.ones_like(listed), 1)

        overlapping = upper & (gap < -EPS)
        missing = overlapping & ~listed
        assert not missing.any(), (
            f"{where}: {missing.sum()} overlapping pairs not in the neighbour list "
            f"(id, id, gap): {examples(missing, ids, gap)}"
        )
        too_far = listed & (gap >= 2.0 * s + EPS)
        assert not too_far.any(), (
            f"{where}: {too_far.sum()} listed pairs farther than r_i + r_j + 2 skin "
            f"({2 * s:.3e} m): {examples(too_far, ids, gap)}"
        )

        c = sim.contacts()
        is_wall = np.asarray(c["id_j"]) < 0
        got = np.stack([c["id_i"][~is_wall], c["id_j"][~is_wall]], axis=1).astype(np.int64)
        got = pair_mask(got, ids, where, "contacts()")
        ambiguous = np.abs(gap) <= EPS
        missing = overlapping & ~got
        extra = got & ~overlapping & ~ambiguous
        assert not missing.any() and not extra.any(), (
            f"{where}: sim.contacts() vs brute-force overlaps: missing "
            f"{examples(missing, ids, gap)}, extra {examples(extra, ids, gap)}"
        )
        n_overlaps_seen += int(overlapping.sum())

        # Wall contacts: plane at lo (normal +e_a) or hi (normal -e_a) on non-periodic axes.
        row = {int(k): n for n, k in enumerate(ids)}
        expected_wall = set()
        for w, (axis, side) in walls.items():
            wgap = (xs[:, axis] if side == 0 else BOX - xs[:, axis]) - rad
            expected_wall |= {(int(ids[k]), -1 - w) for k in np.nonzero(wgap < -EPS)[0]}
        wall_i, wall_j = c["id_i"][is_wall], c["id_j"][is_wall]
        got_wall = [(int(a), int(b)) for a, b in zip(wall_i, wall_j, strict=True)]
        assert len(set(got_wall)) == len(got_wall), f"{where}: duplicate wall contacts"
        for a, b in set(got_wall) - expected_wall:
            assert -1 - b in walls, f"{where}: wall contact with unknown wall id_j = {b}"
            axis, side = walls[-1 - b]
            xa = xs[row[a], axis]
            wgap = (xa if side == 0 else BOX - xa) - rad[row[a]]
            assert abs(wgap) <= EPS, f"{where}: spurious wall contact {(a, b)} with gap {wgap:.3e}"
        assert expected_wall <= set(got_wall), (
            f"{where}: missing wall contacts {sorted(expected_wall - set(got_wall))[:5]}"
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
