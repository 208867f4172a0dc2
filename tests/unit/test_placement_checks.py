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
