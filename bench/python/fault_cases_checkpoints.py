"""The case table of fault_probe.py (part 3: files: checkpoints, damaged, of another set-up or
of another kind, and STL files)."""

from __future__ import annotations

import shutil
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from fault_cases import (
    BOX,
    GLASS,
    INF,
    STEEL,
    Fine,
    Probe,
    Silent,
    add,
    case,
    sim,
    stream,
    walled,
)

import grainscale as gs

geo = gs.geometry

# ---------------------------------------------------------------------------------------------
# checkpoints

K = "checkpoints"


def bed(box: gs.Box = BOX, wall_material: gs.Material = GLASS, **kw: Any) -> gs.Simulation:
    """The set-up of the probe's checkpoints: the walled box, time step 2e-6 s."""
    return walled(box, wall_material, **({"time_step": 2e-6} | kw))


def settled_checkpoint(t: Probe) -> Path:
    """A checkpoint of 162 spheres settling on the floor (contacts with particles and walls)."""
    path = t.work / "intact.h5"
    s = bed()
    pos = gs.insert.lattice(gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.006)), spacing=2.05e-3)
    s.add_particles(position=pos, radius=1e-3, material=GLASS)
    s.run(steps=2000, progress=False)
    s.checkpoint(path)
    return path


def fingerprint(s: gs.Simulation) -> bytes:
    s.run(steps=20, progress=False)
    g = s.gather(("position", "velocity"))
    return b"".join(np.ascontiguousarray(g[k]).tobytes() for k in ("id", "position", "velocity"))


def restart_damaged(t: Probe, damage: Callable[[Path], object]) -> None:
    """Restart a damaged copy: refused naming the file, or identical to the intact file."""
    intact = settled_checkpoint(t)
    fresh = bed()
    fresh.restart(intact)
    expected = fingerprint(fresh)
    damaged = t.work / "damaged.h5"
    shutil.copy(intact, damaged)
    damage(damaged)
    s = bed()
    with t.fault():
        s.restart(damaged)
        got = fingerprint(s)
    if got != expected:
        raise Silent("the damaged checkpoint restarted, and the run differs from the intact one")
    raise Fine("restarted identically to the intact file (the damaged byte is unused)")


def flip(offset: Callable[[Path], int], mask: int = 0x10) -> Callable[[Path], None]:
    def damage(path: Path) -> None:
        data = bytearray(path.read_bytes())
        data[offset(path)] ^= mask
        path.write_bytes(bytes(data))

    return damage


def in_dataset(name: str, byte: int) -> Callable[[Path], int]:
    def offset(path: Path) -> int:
        with h5py.File(path, "r") as f:
            return int(f[f"rank_0/{name}"].id.get_offset()) + byte

    return offset


def in_text(marker: bytes) -> Callable[[Path], int]:
    return lambda path: path.read_bytes().index(marker) + 1


def seeded(seed: int) -> Callable[[Path], int]:
    return lambda path: int(np.random.default_rng(seed).integers(path.stat().st_size))


FLIPS: list[tuple[str, str, Callable[[Path], int], int]] = [
    ("checkpoint_flip_signature", "a flipped byte in the HDF5 signature", lambda p: 1, 0xFF),
    ("checkpoint_flip_position", "a flipped bit in the particle positions",
     in_dataset("reals/particles/position", 203), 0x10),
    ("checkpoint_flip_ids", "a flipped bit in the particle ids",
     in_dataset("ints/particles/id", 80), 0x01),
    ("checkpoint_flip_offsets", "a flipped bit in the contact-list offsets",
     in_dataset("ints/lists/pairs/first", 160), 0x04),
    ("checkpoint_flip_history", "a flipped bit in the contact histories",
     in_dataset("reals/lists/pairs/history", 406), 0x20),
    ("checkpoint_flip_state_text", "a flipped bit in the Python state (JSON text)",
     in_text(b'"time_step"'), 0x01),
    ("checkpoint_flip_random_a", "a flipped bit at a seeded random offset", seeded(11), 0x08),
    ("checkpoint_flip_random_b", "a flipped bit at another seeded random offset", seeded(12), 0x40),
]  # fmt: skip
for _name, _what, _offset, _mask in FLIPS:

    def _flip_run(t: Probe, offset: Callable[[Path], int] = _offset, mask: int = _mask) -> None:
        restart_damaged(t, flip(offset, mask))

    _flip_run.__name__, _flip_run.__doc__ = _name, _what
    case(K, "damaged.h5")(_flip_run)


def truncate(fraction: float) -> Callable[[Path], None]:
    def damage(path: Path) -> None:
        data = path.read_bytes()
        path.write_bytes(data[: int(len(data) * fraction)])

    return damage


def restart_file(t: Probe, write: Callable[[Path], object]) -> None:
    path = t.work / "other.h5"
    write(path)
    s = bed()
    with t.fault():
        s.restart(path)


def hdf5_of_another_kind(path: Path) -> None:
    with h5py.File(path, "w") as f:
        f["data"] = np.arange(10)


def future_version(path: Path) -> None:
    shutil.copy(path.parent / "intact.h5", path)
    with h5py.File(path, "r+") as f:
        f.attrs["version"] = 99


FILES: list[tuple[str, str, Callable[[Path], object], tuple[str, ...]]] = [
    ("checkpoint_missing", "restart from a file that does not exist", lambda p: None,
     ("other.h5",)),
    ("checkpoint_empty", "restart from an empty file", lambda p: p.write_bytes(b""),
     ("other.h5",)),
    ("checkpoint_text", "restart from a text file", lambda p: p.write_text("step 10\n" * 50),
     ("other.h5",)),
    ("checkpoint_other_hdf5", "restart from an HDF5 file of another program",
     hdf5_of_another_kind, ("other.h5", "not a grainscale checkpoint")),
    ("checkpoint_future_version", "restart from a checkpoint of version 99", future_version,
     ("other.h5", "99")),
]  # fmt: skip
for _name, _what, _write, _expect in FILES:

    def _file_run(t: Probe, write: Callable[[Path], object] = _write) -> None:
        if write is future_version:
            settled_checkpoint(t)
        restart_file(t, write)

    _file_run.__name__, _file_run.__doc__ = _name, _what
    case(K, *_expect)(_file_run)


@case(K, "damaged.h5")
def checkpoint_truncated_half(t: Probe) -> None:
    """restart from a checkpoint cut at half its length"""
    restart_damaged(t, truncate(0.5))


@case(K, "damaged.h5")
def checkpoint_truncated_tail(t: Probe) -> None:
    """restart from a checkpoint missing its last 100 bytes"""
    restart_damaged(t, lambda p: p.write_bytes(p.read_bytes()[:-100]))


def old_format(key: str, change: Callable[[np.ndarray], np.ndarray]) -> Callable[[Path], None]:
    """A version-2 file (no checksums, still readable) with one dataset changed."""

    def damage(path: Path) -> None:
        with h5py.File(path, "r+") as f:
            f.attrs["version"] = 2
            data = change(f[f"rank_0/{key}"][()])
            del f[f"rank_0/{key}"]
            f[f"rank_0/{key}"] = data

    return damage


V2: list[tuple[str, str, str, Callable[[np.ndarray], np.ndarray], tuple[str, ...]]] = [
    ("checkpoint_v2_offsets_reversed", "version-2 file, contact-list offsets reversed",
     "ints/lists/pairs/first", lambda a: a[::-1].copy(), ("damaged.h5", "offsets")),
    ("checkpoint_v2_partner_range", "version-2 file, a contact partner out of range",
     "ints/lists/pairs/partner", lambda a: a + 10**6, ("damaged.h5", "partner")),
    ("checkpoint_v2_duplicate_ids", "version-2 file, every particle id 0",
     "ints/particles/id", np.zeros_like, ("damaged.h5", "id")),
    ("checkpoint_v2_nan_position", "version-2 file, a NaN position",
     "reals/particles/position", lambda a: np.where(np.arange(len(a)) == 4, np.nan, a),
     ("damaged.h5", "position")),
    ("checkpoint_v2_negative_radius", "version-2 file, negative radii",
     "reals/particles/radius", lambda a: -a, ("damaged.h5", "radius")),
    ("checkpoint_v2_outside_domain", "version-2 file, every position moved 1 m out of the box",
     "reals/particles/position", lambda a: a + 1.0, ("damaged.h5", "position|domain")),
    ("checkpoint_v2_inverse_mass", "version-2 file, inverse masses 1000 x 1/mass",
     "reals/particles/inv_mass", lambda a: a * 1000, ("damaged.h5", "mass")),
    ("checkpoint_v2_material_index", "version-2 file, material indices out of range",
     "ints/particles/material", lambda a: a + 7, ("damaged.h5", "material")),
]  # fmt: skip
for _name, _what, _key, _change, _expect in V2:

    def _v2_run(t: Probe, key: str = _key, change: Any = _change) -> None:
        restart_damaged(t, old_format(key, change))

    _v2_run.__name__, _v2_run.__doc__ = _name, _what
    case(K, *_expect)(_v2_run)


def restart_into(t: Probe, make: Callable[[], gs.Simulation]) -> gs.Simulation:
    path = settled_checkpoint(t)
    s = make()
    with t.fault():
        s.restart(path)
    return s


OTHER_SETUPS: list[tuple[str, str, Callable[[], gs.Simulation], tuple[str, ...]]] = [
    ("restart_other_domain", "into a box 30 mm long instead of 20",
     lambda: bed(box=gs.Box(lo=(0, 0, 0), hi=(0.03, 0.02, 0.02))), ("domain", "0.03")),
    ("restart_other_periodicity", "into a box periodic along x",
     lambda: bed(box=gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02), periodic=(True, False, False))),
     ("periodic",)),
    ("restart_other_dimension", "into a 2-D simulation", lambda: bed(dimension=2),
     ("dimension", "2")),
    ("restart_other_law", "into a Linear law instead of Hertz-Mindlin",
     lambda: bed(contact=gs.contact.Linear()), ("law", "linear")),
    ("restart_other_friction", "into a law with friction 0.3 instead of 0.5",
     lambda: bed(contact=gs.contact.HertzMindlin(friction=0.3)), ("contact law", "friction=0.3")),
    ("restart_other_wall_material", "into walls of steel instead of glass",
     lambda: bed(wall_material=STEEL), ("material", "steel")),
    ("restart_fewer_walls", "into a simulation without its six walls",
     lambda: sim(time_step=2e-6), ("walls",)),
    ("restart_extra_stream", "into a simulation with a stream the checkpoint lacks",
     lambda: insert_stream(bed()), ("stream",)),
]  # fmt: skip


def insert_stream(s: gs.Simulation) -> gs.Simulation:
    s.insert(stream(mass_rate=0.001))
    return s


for _name, _what, _make, _expect in OTHER_SETUPS:

    def _other_run(t: Probe, make: Callable[[], gs.Simulation] = _make) -> None:
        restart_into(t, make)

    _other_run.__name__, _other_run.__doc__ = _name, f"restart a checkpoint {_what}"
    case(K, *_expect)(_other_run)


@case(K, "time step", "1e-06", response="warning")
def restart_replaces_time_step(t: Probe) -> None:
    """restart into a simulation with an explicit time step of 1e-6 s (the file has 2e-6)"""
    restart_into(t, lambda: bed(time_step=1e-6))


@case(K, "wall 4|walls", "0.005")
def restart_wall_moved(t: Probe) -> None:
    """restart into a set-up whose floor is 5 mm higher"""

    def make() -> gs.Simulation:
        s = gs.Simulation(domain=BOX, time_step=2e-6)
        walls = gs.geometry.box_walls(BOX, GLASS)
        walls[4] = gs.Plane(point=(0, 0, 0.005), normal=(0, 0, 1), material=GLASS)
        for w in walls:
            s.add_wall(w)
        return s

    s = restart_into(t, make)
    raise Silent(f"restarted; the floor is now at z = {s.walls[4].position[2]:g} m")


@case(K, "particles", "1|162", response="either")
def restart_into_populated(t: Probe) -> None:
    """restart into a simulation that already holds a particle of its own (refused, or
    replaced with a warning: a restart replaces the state by design)"""

    def make() -> gs.Simulation:
        s = bed()
        add(s, position=[[0.01, 0.01, 0.015]])
        return s

    restart_into(t, make)


@case(K, "intact.h5", "not a hierarchy|simulation checkpoint|of a simulation")
def restart_simulation_file_into_hierarchy_set_up(t: Probe) -> None:
    """Hierarchy.restart from a plain simulation checkpoint"""
    from fault_cases_run import small_hierarchy

    path = settled_checkpoint(t)
    h = small_hierarchy()
    with t.fault():
        h.restart(path)


@case(K, "h.h5", "hierarchy")
def restart_hierarchy_file_into_simulation(t: Probe) -> None:
    """Simulation.restart from a hierarchy checkpoint"""
    from fault_cases_run import small_hierarchy

    h = small_hierarchy()
    h.run(intervals=1)
    path = t.work / "h.h5"
    h.checkpoint(path)
    with t.fault():
        h.level(0).restart(path)


# ---------------------------------------------------------------------------------------------
# STL files

L = "stl files"
ASCII_TRIANGLE = (
    "solid plate\nfacet normal 0 0 1\nouter loop\nvertex {} 0 0\nvertex 1 0 0\n"
    "vertex 0 1 0\nendloop\nendfacet\nendsolid plate\n"
)


def binary_stl(count: int, triangles: list[tuple[float, ...]]) -> bytes:
    data = b"\0" * 80 + struct.pack("<I", count)
    for tri in triangles:
        data += struct.pack("<12fH", 0, 0, 1, *tri, 0)
    return data


ONE = (0.0, 0, 0, 1, 0, 0, 0, 1, 0)
STLS: list[tuple[str, str, bytes | None, tuple[str, ...]]] = [
    ("stl_empty", "an empty file", b"", ()),
    ("stl_garbage_text", "a text file that is no STL", b"hello world, not an stl\n" * 3, ()),
    ("stl_random_bytes", "5000 random bytes", np.random.default_rng(1).bytes(5000), ()),
    ("stl_ascii_nan", "an ASCII STL with a NaN vertex", ASCII_TRIANGLE.format("nan").encode(),
     ("finite",)),
    ("stl_degenerate", "an ASCII STL whose only triangle is degenerate",
     ASCII_TRIANGLE.format("1").encode(), ("degenerate|triangle",)),
    ("stl_header_count_huge", "a binary STL whose header claims 1e9 triangles",
     binary_stl(10**9, [ONE]), ("1000000000",)),
    ("stl_header_count_short", "a binary STL whose header claims 5 triangles, holding 2",
     binary_stl(5, [ONE, (0.0, 0, 1, 1, 0, 1, 0, 1, 1)]), ("5",)),
    ("stl_binary_inf", "a binary STL with an infinite vertex",
     binary_stl(1, [(0.0, 0, 0, 1, 0, 0, INF, 1, 0)]), ("finite",)),
    ("stl_truncated_ascii", "an ASCII STL cut after 60 characters",
     ASCII_TRIANGLE.format("0")[:60].encode(), ()),
    ("stl_missing", "a file that does not exist", None, ("existing",)),
]  # fmt: skip
for _name, _what, _content, _expect in STLS:

    def _stl_run(t: Probe, content: bytes | None = _content) -> None:
        path = t.work / "part.stl"
        if content is not None:
            path.write_bytes(content)
        with t.fault():
            geo.Mesh.from_stl(path)

    _stl_run.__name__, _stl_run.__doc__ = _name, f"Mesh.from_stl of {_what}"
    case(L, "part.stl", *_expect)(_stl_run)


@case(L, "scale", "-1")
def stl_negative_scale(t: Probe) -> None:
    """Mesh.from_stl(path, scale=-1)"""
    path = t.work / "part.stl"
    path.write_text(ASCII_TRIANGLE.format("0"))
    with t.fault():
        geo.Mesh.from_stl(path, scale=-1)


@case(L, "from_stl.path", "directory")
def stl_directory(t: Probe) -> None:
    """Mesh.from_stl of a directory"""
    with t.fault():
        geo.Mesh.from_stl(t.work)
