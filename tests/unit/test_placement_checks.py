"""Set-up checks (issue 25): particles placed by hand that would blow away at the first step
are refused with their count and the first offenders, unless the caller accepts them."""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3)
R = 1e-3


def box_sim() -> gs.Simulation:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)))
    sim.add_wall(gs.Plane(point=(0, 0, 0.002), normal=(0, 0, 1)))
    return sim


def test_particles_behind_or_deep_in_a_plane_are_refused() -> None:
    sim = box_sim()
    position = [[0.01, 0.01, 0.005], [0.01, 0.012, 0.001], [0.012, 0.01, 0.0027]]
    with pytest.raises(
        ValueError,
        match=r"add_particles: 2 particle\(s\) overlapping wall 0 \(Plane\) by more than 10% "
        r"of the radius or behind it \(first: index 1, index 2\).*check_placement=False",
    ):
        sim.add_particles(position=position, radius=R, material=GLASS)
    assert sim.num_particles == 0
    ids = sim.add_particles(position=position, radius=R, material=GLASS, check_placement=False)
    assert len(ids) == 3
    touching = [[0.01, 0.01, 0.002 + 0.95 * R]]  # 5 % overlap: a packing's usual contact
    sim.add_particles(position=touching, radius=R, material=GLASS)


def test_outside_an_inside_cylinder_and_larger_than_the_box() -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(-0.02, -0.02, 0), hi=(0.02, 0.02, 0.04)))
    sim.add_wall(gs.geometry.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=0.01))
    with pytest.raises(ValueError, match=r"overlapping wall 0 \(Cylinder\).*first: index 0\)"):
        sim.add_particles(position=[[0.0105, 0, 0.02]], radius=R, material=GLASS)
    with pytest.raises(ValueError, match=r"1 particle\(s\) larger than the box"):
        sim.add_particles(
            position=[[0, 0, 0.02]], radius=0.021, material=GLASS, check_placement=True
        )


def test_coordinates_beyond_float64_resolution_are_refused() -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(1e12, 1e12, 1e12)))
    with pytest.raises(ValueError, match="coordinates too large for float64 to resolve 1e-06"):
        sim.add_particles(position=[[5e11, 5e11, 5e11]], radius=R, material=GLASS)


def test_a_wall_added_through_particles_is_refused_naming_their_ids() -> None:
    sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02)))
    ids = sim.add_particles(
        position=[[0.01, 0.01, 0.002], [0.01, 0.01, 0.01]], radius=R, material=GLASS
    )
    lid = gs.Rectangle(corner=(0, 0, 0.0025), edge1=(0.02, 0, 0), edge2=(0, 0.02, 0))
    with pytest.raises(
        ValueError,
        match=rf"add_wall: 1 particle\(s\) overlapping the new wall \(Rectangle\).*id {ids[0]}",
    ):
        sim.add_wall(lid)
    assert sim.walls == []
    sim.add_wall(lid, check_placement=False)
    assert len(sim.walls) == 1
    assert np.all(np.isfinite(sim.walls[0].position))


# ------------------------------------------------------------------ overlaps between particles
PAIR = r"pair\(s\) of particles overlap by more than 10% of the smaller radius"


def open_sim(**box) -> gs.Simulation:
    return gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02), **box))


def test_an_overlapping_pair_is_refused_naming_both() -> None:
    sim = open_sim()
    position = [[0.005, 0.005, 0.005], [0.01, 0.01, 0.01], [0.0065, 0.005, 0.005]]  # 25 %
    with pytest.raises(
        ValueError,
        match=rf"add_particles: 1 {PAIR} \(first: index 0 and index 2\); move them, or pass "
        r"check_placement=False to accept them",
    ):
        sim.add_particles(position=position, radius=R, material=GLASS)
    assert sim.num_particles == 0
    ids = sim.add_particles(position=position, radius=R, material=GLASS, check_placement=False)
    assert len(ids) == 3


def test_an_overlap_within_the_tolerance_is_accepted() -> None:
    sim = open_sim()
    # 9 % of the smaller radius (0.5 mm): the contacts of a settled packing pass
    small = 0.5 * R
    gap = R + small - 0.09 * small
    ids = sim.add_particles(
        position=[[0.01, 0.01, 0.01], [0.01 + gap, 0.01, 0.01]],
        radius=np.array([R, small]),
        material=GLASS,
    )
    assert len(ids) == 2
    with pytest.raises(ValueError, match=rf"1 {PAIR} \(first: index 0 and id {ids[1]}\)"):
        sim.add_particles(  # 11 % of the smaller radius against the small one present
            position=[[0.01 + gap, 0.01 + small + R - 0.11 * small, 0.01]],
            radius=R,
            material=GLASS,
        )


def test_identical_centres_and_a_large_particle_among_small_ones_are_refused() -> None:
    sim = open_sim()
    with pytest.raises(ValueError, match=rf"1 {PAIR} \(first: index 1 and index 2\)"):
        sim.add_particles(
            position=[[0.004, 0.004, 0.004], [0.01, 0.01, 0.01], [0.01, 0.01, 0.01]],
            radius=R,
            material=GLASS,
        )
    # one particle of 4 mm among 0.2 mm ones: different radius classes of the search
    small = lattice_sites(spacing=0.5e-3, lo=0.0005, hi=0.0195)
    big = [[0.01, 0.01, 0.01]]
    with pytest.raises(ValueError, match=rf"add_particles: \d+ {PAIR} \(first: index 0 and"):
        sim.add_particles(
            position=np.concatenate([big, small]),
            radius=np.r_[4e-3, np.full(len(small), 0.2e-3)],
            material=GLASS,
        )
    sim.add_particles(position=small, radius=0.2e-3, material=GLASS)
    with pytest.raises(ValueError, match=rf"add_particles: \d+ {PAIR} \(first: index 0 and id"):
        sim.add_particles(position=big, radius=4e-3, material=GLASS)


def lattice_sites(spacing: float, lo: float, hi: float) -> np.ndarray:
    axis = np.arange(lo, hi, spacing)
    return np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)


def test_an_overlap_across_a_periodic_boundary_is_refused() -> None:
    sim = open_sim(periodic=(True, False, False))
    across = [[0.0004, 0.01, 0.01], [0.0196, 0.01, 0.01]]  # 0.8 mm apart through x = 0
    with pytest.raises(ValueError, match=rf"1 {PAIR} \(first: index 0 and index 1\)"):
        sim.add_particles(position=across, radius=R, material=GLASS)
    closed = open_sim()  # the same particles 19.2 mm apart in a closed box
    assert len(closed.add_particles(position=across, radius=R, material=GLASS)) == 2
    ids = sim.add_particles(position=across[:1], radius=R, material=GLASS)
    with pytest.raises(ValueError, match=rf"1 {PAIR} \(first: index 0 and id {ids[0]}\)"):
        sim.add_particles(position=[[0.0196 + 0.02, 0.01, 0.01]], radius=R, material=GLASS)


def test_new_particles_against_those_present_and_discs() -> None:
    sim = open_sim()
    ids = sim.add_particles(
        position=[[0.005, 0.005, 0.005], [0.015, 0.015, 0.015]], radius=R, material=GLASS
    )
    with pytest.raises(
        ValueError,
        match=rf"2 {PAIR} \(first: index 0 and id {ids[1]}, index 1 and id {ids[0]}\)",
    ):
        sim.add_particles(
            position=[[0.0155, 0.015, 0.015], [0.005, 0.0055, 0.005], [0.01, 0.01, 0.01]],
            radius=R,
            material=GLASS,
        )
    assert sim.num_particles == 2
    discs = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.002)), dimension=2)
    z = discs.plane_z
    with pytest.raises(ValueError, match=rf"1 {PAIR} \(first: index 0 and index 1\)"):
        discs.add_particles(position=[[0.01, 0.01, z], [0.0115, 0.01, z]], radius=R, material=GLASS)


def test_a_large_random_packing_is_accepted_and_one_overlap_in_it_is_found() -> None:
    """100 000 particles of radii 0.6-1 mm in a box periodic along x and y, on a jittered
    lattice (no overlaps); then the same with one particle moved onto its neighbour."""
    rng = np.random.default_rng(7)
    side, spacing = 47, 2.1e-3
    k = np.arange(100_000)
    ijk = np.stack([k % side, (k // side) % side, k // side**2], axis=1)
    position = (ijk + 0.5) * spacing + rng.uniform(-0.04, 0.04, (len(k), 3)) * spacing
    radius = rng.uniform(0.6e-3, 1e-3, len(k))
    top = (k[-1] // side**2 + 1) * spacing
    box = gs.Box(
        lo=(0, 0, 0), hi=(side * spacing, side * spacing, top), periodic=(True, True, False)
    )
    sim = gs.Simulation(domain=box)
    moved = position.copy()
    moved[5000] = moved[5001] - [0.5e-3, 0, 0]  # overlaps 5001 (and no other)
    with pytest.raises(ValueError, match=rf"add_particles: 1 {PAIR} \(first: index 5000 and "):
        sim.add_particles(position=moved, radius=radius, material=GLASS)
    ids = sim.add_particles(position=position, radius=radius, material=GLASS)
    assert len(ids) == 100_000 and sim.num_particles == 100_000


# ---------------------------------------------------------------------------------- mesh walls
def square_mesh(z: float) -> gs.geometry.Mesh:
    """A horizontal square of two triangles at height z, over the middle of the box."""
    vertices = [[0.005, 0.005, z], [0.015, 0.005, z], [0.015, 0.015, z], [0.005, 0.015, z]]
    return gs.geometry.Mesh(vertices=vertices, triangles=[[0, 1, 2], [0, 2, 3]])


def test_particles_overlapping_a_mesh_wall_are_refused_in_both_orders() -> None:
    sim = open_sim()
    sim.add_wall(square_mesh(0.01))
    position = [
        [0.01, 0.01, 0.0105],  # 50 % through the face
        [0.0153, 0.01, 0.0103],  # 58 % at the edge, from beyond it
        [0.012, 0.012, 0.0095],  # 50 % from below: an open mesh has no behind
        [0.0175, 0.01, 0.01],  # beyond the edge, clear
        [0.008, 0.008, 0.01 + 0.95 * R],  # 5 % (a contact)
    ]
    with pytest.raises(
        ValueError,
        match=r"add_particles: 3 particle\(s\) overlapping wall 0 \(Mesh\) by more than 10% of "
        r"the radius \(first: index 0, index 1, index 2\); move them",
    ):
        sim.add_particles(position=position, radius=R, material=GLASS)
    assert len(sim.add_particles(position=position[3:], radius=R, material=GLASS)) == 2

    fresh = open_sim()
    ids = fresh.add_particles(position=position, radius=R, material=GLASS)
    with pytest.raises(
        ValueError,
        match=rf"add_wall: 3 particle\(s\) overlapping the new wall \(Mesh\) by more than 10% "
        rf"of the radius \(first: id {ids[0]}, id {ids[1]}, id {ids[2]}\)",
    ):
        fresh.add_wall(square_mesh(0.01))
    assert fresh.walls == []
    fresh.add_wall(square_mesh(0.01), check_placement=False)
    assert len(fresh.walls) == 1


def test_a_moved_mesh_wall_is_checked_where_it_is() -> None:
    sim = open_sim()
    lid = sim.add_wall(square_mesh(0.004), check_placement=False)
    lid.set_motion(velocity=(0, 0, 1.0))
    sim.time_step = 1e-3
    sim.run(steps=6)  # the mesh moves up by 6 mm, to z = 0.01
    with pytest.raises(ValueError, match=r"overlapping wall 0 \(Mesh\)"):
        sim.add_particles(position=[[0.01, 0.01, 0.0105]], radius=R, material=GLASS)
    sim.add_particles(position=[[0.01, 0.01, 0.0045]], radius=R, material=GLASS)
