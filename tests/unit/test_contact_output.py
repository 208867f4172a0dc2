"""The contact and force network output (grainscale.io.ContactNetwork, issue 26 point 5): the
table's forces are the forces the engine applied (they carry the floor's load and add up to
every particle's force), and the VTK lines join the centres that touch."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from output_cases import GLASS, GRAVITY, column
from test_vtk import read_pvd, read_vtp

import grainscale as gs


@pytest.fixture(scope="module")
def settled(tmp_path_factory: pytest.TempPathFactory) -> tuple[gs.Simulation, object, Path]:
    out = tmp_path_factory.mktemp("network")
    sim, floor = column()
    sim.output(gs.io.ContactNetwork(out, every=0.05))
    sim.run(until=0.25)
    return sim, floor, out


def last_table(out: Path) -> dict:
    tables = gs.io.read_contacts(out)
    assert isinstance(tables, list)
    return tables[-1]


def test_registering_turns_on_contact_recording(tmp_path: Path) -> None:
    sim, _ = column(n=5)
    assert not sim.record_contacts
    sim.output(gs.io.ContactNetwork(tmp_path, every_steps=10))
    assert sim.record_contacts


def test_wall_contacts_carry_the_floor_load(settled) -> None:
    sim, floor, out = settled
    t = last_table(out)
    assert t["step"] == sim.step and t["time"] == sim.time
    on_floor = t["wall"] == 0
    assert on_floor.sum() >= 10
    assert np.array_equal(t["id_j"][on_floor], np.full(on_floor.sum(), -1))
    # the floor's load is the sum of the forces its contacts put on the particles
    assert np.allclose(t["force"][on_floor].sum(axis=0), -np.asarray(floor.force), rtol=1e-12)
    assert t["normal_force"][on_floor].sum() == pytest.approx(-floor.force[2], rel=1e-12)
    with sim.particles(writable=False) as p:
        weight = -GRAVITY[2] * p.mass.sum()
    assert t["normal_force"][on_floor].sum() == pytest.approx(weight, rel=0.01)  # settled


def test_network_adds_up_to_every_particle_force(settled) -> None:
    sim, _, out = settled
    t = last_table(out)
    assert len(t["id_i"]) == sim.num_contacts() > 100
    with sim.particles(writable=False) as p:
        ids, mass, force = np.array(p.id), np.array(p.mass), np.array(p.force)
    index = {int(k): n for n, k in enumerate(ids)}
    total = mass[:, None] * GRAVITY
    for a, b, f in zip(t["id_i"], t["id_j"], t["force"], strict=True):
        total[index[int(a)]] += f
        if b >= 0:
            total[index[int(b)]] -= f
    assert np.allclose(total, force, rtol=0, atol=1e-12 * np.abs(force).max())


def test_columns_decompose_the_force(settled) -> None:
    _, _, out = settled
    t = last_table(out)
    n, f = t["normal"], t["force"]
    assert np.allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-14)
    assert np.allclose(t["force_normal"] + t["force_tangential"], f, rtol=0, atol=1e-18)
    assert np.allclose(np.einsum("ij,ij->i", t["force_tangential"], n), 0, atol=1e-15)
    assert np.all(t["overlap"] > 0) and np.all(t["normal_force"] > 0)  # no adhesion
    # the contact point lies between the centres, overlap / 2 inside the surface of i
    pairs = t["id_j"] >= 0
    gap = np.linalg.norm(t["position_i"] - t["position_j"], axis=1)
    reach = np.linalg.norm(t["point"] - t["position_i"], axis=1)
    assert np.all(reach[pairs] < gap[pairs])
    floor = ~pairs
    assert np.allclose(t["position_j"][floor][:, 2], 0.0, atol=1e-15)  # on the floor plane


def test_vtk_lines_join_the_touching_centres(settled) -> None:
    sim, _, out = settled
    t = last_table(out)
    got = read_vtp(out / f"contacts_{sim.step:08d}.vtp")
    n = len(t["id_i"])
    assert got["counts"]["NumberOfLines"] == n and got["counts"]["NumberOfPoints"] == 2 * n
    connectivity, offsets = got["Lines"]
    assert np.array_equal(offsets, 2 * np.arange(1, n + 1))
    ends = got["points"][connectivity.reshape(-1, 2)]
    assert np.array_equal(ends[:, 0], t["position_i"]) and np.array_equal(
        ends[:, 1], t["position_j"]
    )
    cells = got["CellData"]
    for name in ("id_i", "id_j", "wall", "overlap", "normal", "force", "normal_force"):
        assert np.array_equal(cells[name], t[name]), name
    assert "force_tangential" in cells and "force_normal" in cells and "point" in cells
    # a line spans r_i + r_j - overlap
    with sim.particles(writable=False) as p:
        radius = dict(zip(p.id.tolist(), p.radius.tolist(), strict=True))
    pairs = t["id_j"] >= 0
    r_i = np.array([radius[int(k)] for k in t["id_i"][pairs]])
    r_j = np.array([radius[int(k)] for k in t["id_j"][pairs]])
    length = np.linalg.norm(ends[pairs, 0] - ends[pairs, 1], axis=1)
    assert np.allclose(length, r_i + r_j - t["overlap"][pairs], rtol=1e-12)
    series = read_pvd(out / "contacts.pvd")
    assert [s[0] for s in series] == sorted(s[0] for s in series) and len(series) == 6


def test_a_pair_across_a_periodic_side_is_drawn_to_the_image(tmp_path: Path) -> None:
    box = gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01), periodic=(True, True, True))
    sim = gs.Simulation(domain=box, gravity=(0, 0, 0), quiet=True)
    sim.add_particles(position=[[0.00029, 0.005, 0.005], [0.00971, 0.005, 0.005]], radius=3e-4,
                      material=GLASS)  # fmt: skip
    sim.output(gs.io.ContactNetwork(tmp_path, every_steps=1, table=True))
    sim.run(steps=1)
    t = last_table(tmp_path)
    assert len(t["id_i"]) == 1
    gap = np.linalg.norm(t["position_i"][0] - t["position_j"][0])
    assert gap == pytest.approx(6e-4 - t["overlap"][0], rel=1e-9)  # not the box width
    assert gap < 1e-3


def test_walls_false_keeps_the_pairs_and_table_only(tmp_path: Path) -> None:
    sim, _ = column(n=40)
    sim.output(gs.io.ContactNetwork(tmp_path, every_steps=4000, walls=False, vtk=False))
    sim.run(steps=8000)
    t = last_table(tmp_path)
    assert len(t["id_i"]) > 0 and np.all(t["id_j"] >= 0) and np.all(t["wall"] == -1)
    assert not list(tmp_path.glob("*.vtp")) and not (tmp_path / "contacts.pvd").exists()
    assert [x["step"] for x in gs.io.read_contacts(tmp_path)] == [0, 4000, 8000]


def test_step_without_recorded_contacts_is_skipped_after_a_restart(tmp_path: Path) -> None:
    first, _ = column(n=40)
    first.output(gs.io.ContactNetwork(tmp_path / "net", every_steps=2000))
    first.run(steps=6000)
    first.checkpoint(tmp_path / "state.h5")
    again, _ = column(n=40, particles=False)
    again.restart(tmp_path / "state.h5")
    network = gs.io.ContactNetwork(tmp_path / "net", every_steps=2000)
    again.output(network)
    again.run(steps=4000)
    assert network.skipped == [6000]  # the checkpoint's run wrote it
    steps = [t["step"] for t in gs.io.read_contacts(tmp_path / "net")]
    assert steps == [0, 2000, 4000, 6000, 8000, 10000]
    times = [e[0] for e in read_pvd(tmp_path / "net" / "contacts.pvd")]
    assert len(times) == 6 and times == sorted(times)


def test_validation(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="ContactNetwork needs exactly one of every"):
        gs.io.ContactNetwork(tmp_path)
    with pytest.raises(ValueError, match="needs vtk=True or table=True"):
        gs.io.ContactNetwork(tmp_path, every=1.0, vtk=False, table=False)
    with pytest.raises(ValueError, match="ContactNetwork.prefix must be a non-empty file name"):
        gs.io.ContactNetwork(tmp_path, every=1.0, prefix="a/b")
    with pytest.raises(ValueError, match="is not a grainscale-contacts file"):
        sim, _ = column(n=3)
        sim.output(gs.io.Dump(tmp_path, every_steps=10))
        sim.run(steps=1)
        gs.io.read_contacts(tmp_path / "dump_00000000.h5")
    with pytest.raises(ValueError, match="no contact tables"):
        gs.io.read_contacts(tmp_path)
