"""2-D disc mode: masses and inertia, parameter errors, insertion in the plane, VTK output and
checkpoint/restart (bit-identical, dimension recorded)."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import grainscale as gs

STONE = gs.Material(density=2600.0, youngs_modulus=5e7, poisson_ratio=0.25, name="stone")
BOX = gs.Box(lo=(0, 0, -0.004), hi=(0.04, 0.04, 0.006))  # plane z = 0.001


def disc_sim(**kwargs: object) -> gs.Simulation:
    return gs.Simulation(domain=BOX, dimension=2, **kwargs)


def test_mass_and_inertia_are_those_of_unit_thickness_discs() -> None:
    sim = disc_sim(gravity=(0, 0, 0))
    assert sim.dimension == 2 and sim.plane_z == pytest.approx(0.001)
    r = np.array([1e-3, 2e-3])
    sim.add_particles(
        position=[[0.01, 0.01, sim.plane_z], [0.03, 0.03, sim.plane_z]],
        radius=r,
        material=STONE,
        angular_velocity=(0, 0, 10.0),
    )
    with sim.particles(writable=False) as p:
        m = p.mass.copy()
    np.testing.assert_allclose(m, 2600.0 * math.pi * r**2 * 1.0, rtol=1e-15)
    # Spinning in place: E = 1/2 I w^2 with I = m r^2 / 2.
    assert sim.kinetic_energy() == pytest.approx(np.sum(0.5 * 0.5 * m * r**2 * 100.0), rel=1e-14)


@pytest.mark.parametrize("value", [1, 4, 2.5, True, "2"])
def test_dimension_must_be_2_or_3(value: object) -> None:
    with pytest.raises(ValueError, match=r"Simulation.dimension must be 2 or 3, got"):
        gs.Simulation(domain=BOX, dimension=value)  # type: ignore[arg-type]


def test_particles_off_the_plane_are_refused() -> None:
    sim = disc_sim()
    with pytest.raises(
        ValueError,
        match=r"add_particles.position z must be equal to the plane z = 0.001 m of the 2-D mode "
        r"\(particle 0\), got 0.002",
    ):
        sim.add_particles(position=[[0.01, 0.01, 0.002]], radius=1e-3, material=STONE)


def test_streams_are_refused_in_2d() -> None:
    sim = disc_sim()
    face = gs.insert.RectangleFace(
        corner=(0.0, 0.03, -0.004), edge1=(0.04, 0, 0), edge2=(0, 0, 0.01)
    )
    stream = gs.insert.Stream(
        face=face, radius=1e-3, material=STONE, mass_rate=0.1, velocity=(0, -0.5, 0)
    )
    with pytest.raises(ValueError, match=r"Simulation.insert\(Stream\) must be used in 3-D only"):
        sim.insert(stream)


def no_overlaps(pos: np.ndarray, r: np.ndarray) -> bool:
    d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    return bool(np.all(d >= (r[:, None] + r[None, :]) * (1 - 1e-12)))


def test_insertion_helpers_place_discs_in_the_plane() -> None:
    sim = disc_sim()
    z = sim.plane_z
    lat = gs.insert.lattice(gs.Box(lo=(0, 0, -0.004), hi=(0.02, 0.01, 0.006)), 2e-3, plane_z=z)
    assert lat.shape == (50, 3) and np.all(lat[:, 2] == z)  # 10 x 5 sites, one layer
    rad = np.full(80, 1e-3)
    rnd = gs.insert.random_in_box(BOX, rad, seed=1, plane_z=z)
    assert np.all(rnd[:, 2] == z) and no_overlaps(rnd, rad)
    with pytest.raises(ValueError, match=r"random_in_box.plane_z must lie in the region's z"):
        gs.insert.random_in_box(BOX, rad, seed=1, plane_z=1.0)
    # Pack: an area fraction of 0.5 is beyond 3-D random sequential addition but below the
    # 2-D jamming limit (about 0.547); it needs the planar voxel sampler.
    pack = gs.insert.Pack(
        BOX, radius=gs.dist.Uniform(0.8e-3, 1.2e-3), material=STONE, volume_fraction=0.5, seed=2
    )
    ids = sim.insert(pack)
    with sim.particles(writable=False) as p:
        pos, r = p.position.copy(), p.radius.copy()
    assert len(ids) == len(r) > 200
    assert np.all(pos[:, 2] == z) and no_overlaps(pos, r)
    assert np.all((pos[:, :2] - r[:, None] >= -1e-15) & (pos[:, :2] + r[:, None] <= 0.04 + 1e-15))
    area = np.sum(math.pi * r**2) / 0.04**2
    assert area == pytest.approx(0.5, abs=0.01)
    cyl = gs.geometry.Cylinder(point=(0.02, 0.02, 0), axis=(0, 0, 1), radius=0.01, length=0.004)
    with pytest.raises(ValueError, match=r"Pack.region must be a gs.Box in 2-D mode"):
        sim.insert(gs.insert.Pack(cyl, radius=1e-3, material=STONE, count=3))
    off = gs.Box(lo=(0, 0, 0.002), hi=(0.04, 0.04, 0.006))
    with pytest.raises(ValueError, match=r"Pack.region z range must be to contain the plane"):
        sim.insert(gs.insert.Pack(off, radius=1e-3, material=STONE, count=3))


def bed() -> gs.Simulation:
    law = gs.contact.HertzMindlin(restitution=0.5, friction=0.5, rolling=gs.contact.EPSD(0.1, 0.3))
    sim = disc_sim(contact=law, time_step=2e-6, skin=2e-4)
    for wall in gs.geometry.box_walls(gs.Box(lo=(0, 0, -1), hi=(0.04, 0.04, 1))):
        if abs(wall.normal[2]) == 0:
            sim.add_wall(wall)
    lid = gs.Rectangle(corner=(0, 0.03, -0.004), edge1=(0, 0, 0.01), edge2=(0.04, 0, 0))
    sim.add_wall(
        lid, servo=gs.geometry.Servo(target_stress=50.0, area=0.04, gain=0.02, max_speed=0.05)
    )
    return sim


def populated_bed() -> gs.Simulation:
    sim = bed()
    sim.insert(
        gs.insert.Pack(
            gs.Box(lo=(0, 0, -0.004), hi=(0.04, 0.029, 0.006)),
            radius=gs.dist.Uniform(0.8e-3, 1.2e-3),
            material=STONE,
            count=150,
            velocity=(0.1, -0.3, 0),
            seed=5,
        )
    )
    return sim


def state(sim: gs.Simulation) -> dict[str, np.ndarray]:
    with sim.particles(writable=False) as p:
        out = {
            k: getattr(p, k).copy()
            for k in ("position", "velocity", "angular_velocity", "force", "torque", "id")
        }
    out["lid"] = np.concatenate([sim.walls[4].force, sim.walls[4].position])
    return out


def test_restart_in_2d_is_bit_identical_and_records_the_dimension(tmp_path: Path) -> None:
    straight = populated_bed()
    straight.run(steps=3000, progress=False)
    straight.run(steps=3000, progress=False)
    first = populated_bed()
    first.run(steps=3000, progress=False)
    path = tmp_path / "disc.h5"
    first.checkpoint(path)
    again = bed()
    again.restart(path)
    again.run(steps=3000, progress=False)
    assert straight.num_contacts() > 30
    expected, got = state(straight), state(again)
    for key, value in expected.items():
        assert np.array_equal(got[key], value), f"{key} differs after restart"
    spheres = gs.Simulation(domain=BOX, contact=straight.contact, time_step=2e-6, skin=2e-4)
    for wall in straight.walls:
        spheres.add_wall(wall.geometry)
    with pytest.raises(ValueError, match=r"set-up '.*;dimension=2', this simulation is"):
        spheres.restart(path)


def test_vtk_output_in_2d(tmp_path: Path) -> None:
    sim = populated_bed()
    sim.output(gs.io.VTK(tmp_path, every_steps=100))
    sim.run(steps=200, progress=False)
    files = sorted(tmp_path.glob("particles_0*.vtp"))
    assert len(files) == 3
    assert len(list(tmp_path.glob("particles_walls_*.vtp"))) == 3  # the servo lid moves
    piece = ET.parse(files[-1]).getroot().find(".//Piece")
    assert piece is not None and piece.get("NumberOfPoints") == "150"
