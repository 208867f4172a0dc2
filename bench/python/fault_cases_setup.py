"""The case table of fault_probe.py (part 2: particles, walls, insertion and output:
add_particles, add_wall and wall handles, Pack / Stream / Outlet, output writers)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from fault_cases import (
    BOX,
    CENTRE,
    GLASS,
    INF,
    NAN,
    TRI,
    Fine,
    Probe,
    Silent,
    add,
    case,
    one,
    pack,
    servo,
    sim,
    stream,
)

import grainscale as gs

geo = gs.geometry

# ---------------------------------------------------------------------------------------------
# add_particles

P = "particles"


def add_case(name: str, what: str, *expect: str, setup: Callable[[], Any] = sim, **kw: Any) -> None:
    """A case: ``add_particles(**kw)`` (position, radius, material default to one glass sphere
    at the box centre) on the simulation ``setup()`` returns."""

    def run(t: Probe) -> None:
        s = setup()
        with t.fault():
            add(s, **kw)

    run.__name__ = name
    run.__doc__ = what
    case(P, *expect)(run)


THREE = [[0.005, 0.01, 0.01], [0.01, 0.01, 0.01], [0.015, 0.01, 0.01]]
add_case("particles_length_mismatch", "3 positions, 2 radii", "radius", "(2,)",
         position=THREE, radius=[1e-3, 1e-3])  # fmt: skip
add_case("particles_negative_radius", "radius -1e-3", "radius", "-0.001", radius=-1e-3)
add_case("particles_zero_radius", "radius 0", "radius", "got 0", radius=0.0)
add_case("particles_nan_position", "a NaN coordinate", "position", "nan",
         position=[[0.01, NAN, 0.01]])  # fmt: skip
add_case("particles_inf_velocity", "velocity (inf, 0, 0)", "velocity", "inf", velocity=(INF, 0, 0))
add_case("particles_position_two_columns", "positions of shape (3, 2)", "position", "(3, 2)",
         position=[[0.01, 0.01]] * 3)  # fmt: skip
add_case("particles_position_three_dims", "positions of shape (1, 1, 3)", "position", "(1, 1, 3)",
         position=[CENTRE])  # fmt: skip
add_case("particles_complex_position", "complex positions", "position", "complex",
         position=np.array(CENTRE) + 0j)  # fmt: skip
add_case("particles_string_position", "positions as strings", "position", "dtype",
         position=[["0.01", "0.01", "0.01"]])  # fmt: skip
add_case("particles_bool_radius", "radius=True", "radius", "bool", radius=True)
add_case("particles_ragged_position", "ragged positions [[x, y, z], [x, y]]", "position",
         position=[[0.01, 0.01, 0.01], [0.012, 0.01]])  # fmt: skip
add_case("particles_velocity_two", "velocity (1, 0): two components", "velocity", "(2,)",
         velocity=(1.0, 0.0))  # fmt: skip
add_case("particles_material_none", "material=None", "material", "None", material=None)
RIGID = gs.Material(density=2500, youngs_modulus=INF, poisson_ratio=0.3)
add_case("particles_rigid_material", "a rigid wall material (E = inf) for particles", "material",
         "rigid", material=RIGID)  # fmt: skip
add_case("particles_outside_domain", "a centre outside the closed box", "position", "0.05",
         position=[[0.05, 0.01, 0.01]])  # fmt: skip
add_case("particles_larger_than_box", "a sphere of radius 15 mm in a 20 mm box",
         "larger than the box", "index 0", radius=0.015)  # fmt: skip
add_case("particles_tiny_radius", "radius 1e-200 m (its mass underflows to zero)", "radius",
         "1e-200", radius=1e-200)  # fmt: skip
add_case("particles_2d_off_plane", "a disc off the plane z = plane_z in 2-D mode", "z", "0.003",
         position=[[0.01, 0.01, 0.003]], setup=lambda: sim(dimension=2))  # fmt: skip
HUGE_BOX = gs.Box(lo=(1e12, 0, 0), hi=(1e12 + 0.02, 0.02, 0.02))
add_case("particles_huge_coordinates", "x = 1e12 m: float64 cannot resolve the radius",
         "float64", "index 0", position=[[1e12 + 0.01, 0.01, 0.01]],
         setup=lambda: sim(domain=HUGE_BOX))  # fmt: skip
FLOOR = gs.Plane(point=(0, 0, 0.005), normal=(0, 0, 1), material=GLASS)


def with_wall(wall: Any) -> Callable[[], gs.Simulation]:
    def make() -> gs.Simulation:
        s = sim()
        s.add_wall(wall)
        return s

    return make


add_case("particles_behind_plane", "a sphere behind a floor plane", "wall 0", "index 0",
         position=[[0.01, 0.01, 0.002]], setup=with_wall(FLOOR))  # fmt: skip
add_case("particles_deep_in_plane", "a sphere overlapping a floor by 50 % of its radius", "wall 0",
         "index 0", position=[[0.01, 0.01, 0.0055]], setup=with_wall(FLOOR))  # fmt: skip
add_case("particles_floor_normal_flipped", "a floor whose normal points out of the box", "wall 0",
         "index 0", setup=with_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, -1))))  # fmt: skip
DRUM = geo.Cylinder(point=(0.01, 0.01, 0), axis=(0, 0, 1), radius=0.005)
add_case("particles_outside_drum", "a sphere outside an inside-cylinder wall", "Cylinder",
         "index 0", position=[[0.018, 0.01, 0.01]], setup=with_wall(DRUM))  # fmt: skip


@case(P, "overlap", "particle 0|particle 1|index 0 and index 1")
def particles_identical_centres(t: Probe) -> None:
    """two spheres with the same centre, then run()"""
    s = sim(gravity=(0, 0, 0))
    with t.fault():
        add(s, position=CENTRE * 2)
        s.run(steps=10, progress=False)


@case(P, "overlap", "particle 0|particle 1|index 0 and index 1")
def particles_overlap_ninety_percent(t: Probe) -> None:
    """two spheres overlapping by 90 % of their radius, then run()"""
    s = sim(gravity=(0, 0, 0))
    with t.fault():
        add(s, position=[[0.01, 0.01, 0.01], [0.0111, 0.01, 0.01]])
        s.run(steps=10, progress=False)


@case(P, "ids", "0.5")
def remove_particles_fractional_id(t: Probe) -> None:
    """sim.remove_particles([0.5]): a fractional id"""
    s = one()
    with t.fault():
        removed = s.remove_particles([0.5])
    if removed:
        raise Silent(f"id 0.5 was taken as id 0: {removed} particle removed")


@case(P, "ids", "abc")
def remove_particles_string(t: Probe) -> None:
    """sim.remove_particles('abc')"""
    s = one()
    with t.fault():
        s.remove_particles("abc")  # type: ignore[arg-type]


@case(P, "fields", "'pos'")
def gather_unknown_field(t: Probe) -> None:
    """sim.gather(['pos'])"""
    s = one()
    with t.fault():
        s.gather(["pos"])


# ---------------------------------------------------------------------------------------------
# walls and wall handles

W = "walls"


@case(W, "add_wall", "'floor'")
def add_wall_string(t: Probe) -> None:
    """sim.add_wall('floor')"""
    s = sim()
    with t.fault():
        s.add_wall("floor")  # type: ignore[arg-type]


@case(W, "servo", "'x'")
def add_wall_servo_string(t: Probe) -> None:
    """sim.add_wall(plane, servo='x')"""
    s = sim()
    with t.fault():
        s.add_wall(FLOOR, servo="x")  # type: ignore[arg-type]


@case(W, "Simulation.add_wall", "id 0")
def add_wall_through_particle(t: Probe) -> None:
    """a floor added through a sphere already present"""
    s = sim()
    add(s, position=[[0.01, 0.01, 0.0052]])
    with t.fault():
        s.add_wall(FLOOR)


@case(W, "Servo.area", "None")
def servo_stress_without_area(t: Probe) -> None:
    """a stress servo on a plane without an area"""
    s = sim()
    with t.fault():
        s.add_wall(FLOOR, servo=servo(target_force=None, target_stress=100.0))


@case(W, "Servo.direction", "Cylinder")
def servo_cylinder_without_direction(t: Probe) -> None:
    """a servo on a cylinder wall without a direction"""
    s = sim()
    with t.fault():
        s.add_wall(DRUM, servo=servo())


def handle_case(name: str, what: str, action: Callable[[Any], None], *expect: str) -> None:
    def run(t: Probe) -> None:
        s = one()
        wall = s.add_wall(FLOOR)
        with t.fault():
            action(wall)

    run.__name__ = name
    run.__doc__ = what
    case(W, *expect)(run)


def set_attr(obj: Any, name: str, value: Any) -> None:
    setattr(obj, name, value)


handle_case("set_motion_nan", "wall.set_motion(velocity=(nan, 0, 0))",
            lambda w: w.set_motion(velocity=(NAN, 0, 0)), "set_motion.velocity", "nan")  # fmt: skip
handle_case("set_motion_shape", "wall.set_motion(velocity=[[0, 0]])",
            lambda w: w.set_motion(velocity=[[0, 0]]), "set_motion.velocity",
            "[[0, 0]]")  # fmt: skip
handle_case("set_motion_string", "wall.set_motion(velocity='fast')",
            lambda w: w.set_motion(velocity="fast"), "set_motion.velocity", "'fast'")  # fmt: skip
handle_case("set_motion_origin_inf", "wall.set_motion(origin=(inf, 0, 0))",
            lambda w: w.set_motion(origin=(INF, 0, 0)), "set_motion.origin", "inf")  # fmt: skip
handle_case("servo_setter_number", "wall.servo = 5",
            lambda w: set_attr(w, "servo", 5), "WallHandle.servo", "5")  # fmt: skip


def attached_servo(t: Probe, target: object) -> str:
    s = one(lost_particles="ignore")
    with t.fault():
        wall = s.add_wall(FLOOR, servo=servo(target_force=target))
        s.run(steps=20, progress=False)
    return f"the floor moved to z = {float(wall.position[2]):.6g} m"


@case(W, "Servo.target_force", "nan")
def servo_target_nan(t: Probe) -> str:
    """a servo with target_force=nan on a floor, then run()"""
    return attached_servo(t, NAN)


@case(W, "Servo.target_force", "'10'")
def servo_target_string(t: Probe) -> str:
    """a servo with target_force='10' (a string) on a floor, then run()"""
    return attached_servo(t, "10")


@case(W, "wall index", "5")
def deprecated_wall_index(t: Probe) -> None:
    """sim.wall_force(5) (deprecated index API) with one wall"""
    s = one()
    s.add_wall(FLOOR)
    with t.fault():
        s.wall_force(5)  # type: ignore[attr-defined]


@case(W, "wall|mesh", "scale|outside|domain", response="either")
def mesh_wall_outside_domain(t: Probe) -> None:
    """an STL mesh in mm read without scale=1e-3: the wall lies far outside the domain"""
    path = t.work / "plate_mm.stl"
    geo.Mesh(vertices=TRI * 1000 + 5, triangles=[[0, 1, 2]]).to_stl(path)
    s = one()
    with t.fault():
        s.add_wall(geo.Mesh.from_stl(path))
        s.run(steps=5, progress=False)


# ---------------------------------------------------------------------------------------------
# insertion: Pack, Stream, Outlet

N = "insertion"


def insert_case(name: str, what: str, make: Callable[[], Any], *expect: str, dim: int = 3) -> None:
    def run(t: Probe) -> None:
        s = one(dimension=dim)
        with t.fault():
            op = make()
            if isinstance(op, gs.insert.Outlet):
                s.add_outlet(op)
            else:
                s.insert(op)
            s.run(steps=20, progress=False)

    run.__name__ = name
    run.__doc__ = what
    case(N, *expect)(run)


FAR = gs.Box(lo=(1, 1, 1), hi=(1.02, 1.02, 1.02))
insert_case("pack_count_negative", "Pack(count=-5)", lambda: pack(count=-5), "Pack.count", "-5")
insert_case("pack_count_fraction", "Pack(count=2.5)", lambda: pack(count=2.5), "Pack.count", "2.5")
insert_case("pack_count_and_fraction", "Pack with count and volume_fraction",
            lambda: pack(volume_fraction=0.3), "count", "volume_fraction")  # fmt: skip
insert_case("pack_fraction_above_one", "Pack(volume_fraction=1.5)",
            lambda: pack(count=None, volume_fraction=1.5), "volume_fraction", "1.5")  # fmt: skip
insert_case("pack_region_outside", "Pack in a box 1 m outside the domain",
            lambda: gs.insert.Pack(FAR, radius=1e-3, material=GLASS, count=5), "Pack.region",
            "1.02")  # fmt: skip
insert_case("pack_too_dense", "Pack of 5000 spheres in a 20 mm box", lambda: pack(count=5000),
            "Pack", "5000")  # fmt: skip
insert_case("pack_region_string", "Pack(region='box')",
            lambda: gs.insert.Pack("box", radius=1e-3, material=GLASS, count=5), "Pack.region",
            "'box'")  # fmt: skip
insert_case("pack_open_mesh", "Pack in a mesh of one triangle (not closed)",
            lambda: gs.insert.Pack(geo.Mesh(vertices=TRI, triangles=[[0, 1, 2]]), radius=1e-3,
                                   material=GLASS, count=3), "Pack.region", "closed")  # fmt: skip
insert_case("pack_infinite_cylinder", "Pack in a cylinder of no length",
            lambda: gs.insert.Pack(DRUM, radius=1e-3, material=GLASS, count=3), "Pack.region",
            "length=None")  # fmt: skip
insert_case("pack_seed_negative", "Pack(seed=-1)", lambda: pack(seed=-1), "Pack.seed", "-1")
insert_case("pack_attempts_zero", "Pack(max_attempts=0)", lambda: pack(max_attempts=0),
            "max_attempts", "got 0")  # fmt: skip
insert_case("pack_radius_negative", "Pack(radius=-1e-3)", lambda: pack(radius=-1e-3), "radius",
            "-0.001")  # fmt: skip
insert_case("pack_rigid_material", "Pack of a rigid wall material",
            lambda: pack(material=RIGID),
            "Pack.material", "rigid")  # fmt: skip
insert_case("stream_rate_negative", "Stream(mass_rate=-1)", lambda: stream(mass_rate=-1),
            "Stream.mass_rate", "-1")  # fmt: skip
insert_case("stream_rate_nan", "Stream(mass_rate=nan)", lambda: stream(mass_rate=NAN),
            "Stream.mass_rate", "nan")  # fmt: skip
insert_case("stream_face_string", "Stream(face='top')",
            lambda: gs.insert.Stream("top", mass_rate=0.01, radius=1e-3, material=GLASS),
            "Stream.face", "'top'")  # fmt: skip
insert_case("stream_disc_negative_radius", "DiscFace(radius=-0.005)",
            lambda: gs.insert.DiscFace(centre=(0, 0, 0), normal=(0, 0, 1), radius=-0.005),
            "DiscFace.radius", "-0.005")  # fmt: skip
insert_case("stream_stop_before_start", "Stream(start=0.2, stop=0.1)",
            lambda: stream(start=0.2, stop=0.1), "Stream.stop", "0.2")  # fmt: skip
insert_case("stream_no_speed_no_every", "Stream with a velocity along the face and no every",
            lambda: stream(velocity=(1, 0, 0)), "Stream.every", "None")  # fmt: skip
insert_case("stream_in_2d", "a Stream in 2-D mode", lambda: stream(), "Stream", "dimension=2",
            dim=2)  # fmt: skip
insert_case("stream_face_outside", "a Stream face 1 m outside the domain",
            lambda: gs.insert.Stream(gs.insert.DiscFace(centre=(1, 1, 1), normal=(0, 0, -1),
                                                        radius=0.005), mass_rate=0.01,
                                     radius=1e-3, material=GLASS, velocity=(0, 0, -1)),
            "Stream.face", "0.995")  # fmt: skip
insert_case("outlet_every_zero", "Outlet(every=0)",
            lambda: gs.insert.Outlet(BOX, every=0), "Outlet.every", "got 0")  # fmt: skip
insert_case("outlet_infinite_cylinder", "Outlet in a cylinder of no length",
            lambda: gs.insert.Outlet(DRUM), "Outlet.region", "length=None")  # fmt: skip
insert_case("outlet_outside_domain", "an Outlet 1 m outside the domain (it can never remove)",
            lambda: gs.insert.Outlet(FAR), "Outlet.region", "1.02")  # fmt: skip


@case(N, "volume fraction", "509", response="warning")
def stream_rate_huge(t: Probe) -> None:
    """Stream(mass_rate=100 kg/s) through a 10 mm disc"""
    s = sim()
    with t.fault():
        s.insert(stream(mass_rate=100.0))


# ---------------------------------------------------------------------------------------------
# output writers

O = "output"  # noqa: E741


def not_a_dir(t: Probe) -> Path:
    """A path below a regular file: unwritable, even for root."""
    blocker = t.work / "a_file"
    blocker.write_text("x")
    return blocker / "out"


@case(O, "a_file/out", types=("ValueError", "TypeError", "RuntimeError", "OSError"))
def vtk_directory_unwritable(t: Probe) -> None:
    """VTK output into a directory below a regular file"""
    s = one()
    target = not_a_dir(t)
    with t.fault():
        s.output(gs.io.VTK(target, every_steps=5))
        s.run(steps=10, progress=False)


simple_vtk: list[tuple[str, str, dict[str, Any], tuple[str, ...]]] = [
    ("vtk_every_negative", "VTK(every=-0.01)", {"every": -0.01}, ("VTK.every", "-0.01")),
    ("vtk_every_and_steps", "VTK(every=0.01, every_steps=5)", {"every": 0.01, "every_steps": 5},
     ("every", "every_steps")),
    ("vtk_every_steps_fraction", "VTK(every_steps=2.5)", {"every_steps": 2.5},
     ("every_steps", "2.5")),
    ("vtk_prefix_path", "VTK(prefix='a/b')", {"every_steps": 5, "prefix": "a/b"},
     ("VTK.prefix", "'a/b'")),
]  # fmt: skip
for _name, _what, _kw, _expect in simple_vtk:

    def _run(t: Probe, kw: dict[str, Any] = _kw) -> None:
        with t.fault():
            gs.io.VTK(t.work / "vtk", **kw)

    _run.__name__, _run.__doc__ = _name, _what
    case(O, *_expect)(_run)


@case(O, "Simulation.output", "'out'")
def output_string(t: Probe) -> None:
    """sim.output('out')"""
    s = one()
    with t.fault():
        s.output("out")  # type: ignore[arg-type]


@case(O, "checkpoint", "c.h5")
def checkpoint_unwritable(t: Probe) -> None:
    """sim.checkpoint into a directory below a regular file"""
    s = one()
    s.run(steps=2, progress=False)
    target = not_a_dir(t)
    with t.fault():
        s.checkpoint(target / "c.h5")


@case(O, "checkpoint", "run")
def checkpoint_before_first_run(t: Probe) -> None:
    """sim.checkpoint() of a new simulation (time step not chosen yet)"""
    s = one()
    with t.fault():
        s.checkpoint(t.work / "c.h5")
    raise Fine("written")


@case(O, "emergency checkpoint", "e.h5")
def emergency_checkpoint_unwritable(t: Probe) -> None:
    """a guard trips and the emergency checkpoint path is unwritable"""
    path = not_a_dir(t) / "e.h5"
    s = sim(gravity=(0, 0, 0), guards=gs.Guards(emergency_checkpoint=path))
    add(s, velocity=(100.0, 0, 0))
    with t.fault():
        s.run(steps=10, progress=False)
