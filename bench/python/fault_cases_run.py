"""The case table of fault_probe.py (part 4: runs: run()'s arguments, particle views, physical
faults the run guards must stop, hierarchies, and MPI runs on two ranks)."""

from __future__ import annotations

from typing import Any

import numpy as np
from fault_cases import (
    CENTRE,
    GLASS,
    NAN,
    Fine,
    Probe,
    Silent,
    add,
    case,
    one,
    settle,
    sim,
    walled,
)

import grainscale as gs

# ---------------------------------------------------------------------------------------------
# run() arguments

R = "run"


def run_case(name: str, what: str, kw: dict[str, Any], *expect: str, **options: Any) -> None:
    def go(t: Probe) -> None:
        s = one()
        with t.fault():
            s.run(progress=False, **kw)

    go.__name__, go.__doc__ = name, what
    case(R, *expect, **options)(go)


run_case("run_steps_negative", "run(steps=-5)", {"steps": -5}, "steps", "-5")
run_case("run_steps_fraction", "run(steps=10.5)", {"steps": 10.5}, "steps", "10.5")
run_case("run_steps_string", "run(steps='100')", {"steps": "100"}, "steps", "'100'")
run_case("run_steps_bool", "run(steps=True)", {"steps": True}, "steps", "True")
run_case("run_until_nan", "run(until=nan)", {"until": NAN}, "until", "nan")
run_case("run_until_string", "run(until='1e-4')", {"until": "1e-4"}, "until", "'1e-4'")
run_case("run_steps_and_until", "run(steps=10, until=0.1)", {"steps": 10, "until": 0.1},
         "steps", "until")  # fmt: skip
run_case("run_nothing", "run() with neither steps nor until", {}, "steps", "until")


run_case("run_until_past", "run(until=-1.0) from t = 0", {"until": -1.0}, "until", "-1.0")


@case(R, "time_stp", types=("AttributeError",))
def setting_misspelt(t: Probe) -> None:
    """sim.time_stp = 1e-6: a misspelt setting stored as a new attribute and never read"""
    s = one()
    with t.fault():
        s.time_stp = 1e-6  # type: ignore[attr-defined]


@case(R, "contact", "fixed", types=("AttributeError",))
def contact_reassigned(t: Probe) -> None:
    """sim.contact = another law after construction: the core keeps the first one"""
    s = one()
    with t.fault():
        s.contact = gs.contact.HertzMindlin(friction=0.1)


@case(R, "steps", "9223372036854775808")
def run_steps_beyond_int64(t: Probe) -> None:
    """run(steps=2**63): more steps than the int64 step counter holds"""
    s = one(lost_particles="ignore")
    with t.fault(), t.deadline(5, "run(steps=2**63)"):
        s.run(steps=2**63, progress=False)


@case(R, "until", "1e+300")
def run_until_huge(t: Probe) -> None:
    """run(until=1e300): a step count beyond int64"""
    s = one(lost_particles="ignore")
    with t.fault(), t.deadline(5, "run(until=1e300)"):
        s.run(until=1e300, progress=False)


# ---------------------------------------------------------------------------------------------
# particle views

V = "views"


def pair() -> gs.Simulation:
    s = sim(gravity=(0, 0, 0))
    add(s, position=[[0.008, 0.01, 0.01], [0.013, 0.01, 0.01]])
    s.run(steps=1, progress=False)
    return s


@case(V, "particles()", "position")
def view_array_written_after_block(t: Probe) -> None:
    """p.position taken inside `with sim.particles()`, written after the block"""
    s = pair()
    with s.particles() as p:
        a = p.position
    with t.fault():
        a[0, 0] = 0.012


@case(V, "written after", "position")
def view_slice_written_after_block(t: Probe) -> None:
    """a slice of p.position taken inside the block, written after it, then run()"""
    s = pair()
    with s.particles() as p:
        a = p.position[:, 0]
    with t.fault():
        a[0] = 0.009
        s.run(steps=1, progress=False)


@case(V, "outside", "position")
def view_object_used_after_block(t: Probe) -> None:
    """the view object of the block read after it"""
    s = pair()
    with s.particles() as p:
        pass
    with t.fault():
        _ = p.position


@case(V, "radius", "read-only|cannot")
def view_write_radius(t: Probe) -> None:
    """p.radius[0] = 2e-3 inside the block (radius is not writable)"""
    s = pair()
    with t.fault(), s.particles() as p:
        p.radius[0] = 2e-3


@case(V, "position", "set|assign")
def view_assign_attribute(t: Probe) -> None:
    """p.position = new positions inside the block (assigning instead of writing the array):
    documented to copy the values into the engine's array"""
    s = pair()
    new = [[0.007, 0.01, 0.01], [0.014, 0.01, 0.01]]
    with t.fault():
        with s.particles() as p:
            p.position = np.array(new)
        s.run(steps=1, progress=False)
    with s.particles(writable=False) as p:
        if np.allclose(p.position, new, atol=1e-6):
            raise Fine("the positions were copied into the engine's array, as documented")
        raise Silent(f"assignment accepted, the particles are at {p.position.tolist()}")


@case(V, "velocity", "read-only|writable")
def view_write_read_only_block(t: Probe) -> None:
    """p.velocity written in a `with sim.particles(writable=False)` block"""
    s = pair()
    with t.fault(), s.particles(writable=False) as p:
        p.velocity[0, 0] = 1.0


@case(V, "particle 0", "nan")
def view_nan_velocity(t: Probe) -> None:
    """a NaN velocity written inside the block, then run()"""
    s = pair()
    with t.fault():
        with s.particles() as p:
            p.velocity[0, 0] = np.nan
        s.run(steps=5, progress=False)


@case(V, "left the domain|outside", "0", response="either")
def view_position_outside_box(t: Probe) -> None:
    """a position written 0.5 m outside the closed box, then run()"""
    s = pair()
    with t.fault():
        with s.particles() as p:
            p.position[0] = (0.5, 0.5, 0.5)
        s.run(steps=5, progress=False)


# ---------------------------------------------------------------------------------------------
# physical faults: the run guards (RuntimeError naming the particle) or lost-particle reports

Y = "runtime physics"


def physics_case(name: str, what: str, make: Any, run: dict[str, Any], *expect: str,
                 **options: Any) -> None:  # fmt: skip
    def go(t: Probe) -> str:
        with t.fault():
            s = make()
            s.run(progress=False, **run)
        return f"ran to step {s.step}: {s.num_particles} particles, {s.lost_particles} lost"

    go.__name__, go.__doc__ = name, what
    case(Y, *expect, **options)(go)


def launched(speed: float, **kw: Any) -> gs.Simulation:
    """A sphere at 5 mm flying along +x at ``speed`` towards a wall at 15 mm, dt 1e-5 s."""
    s = sim(gravity=(0, 0, 0), time_step=1e-5, **kw)
    s.add_wall(gs.Plane(point=(0.015, 0, 0), normal=(-1, 0, 0), material=GLASS))
    add(s, position=[[0.005, 0.01, 0.01]], velocity=(speed, 0, 0))
    return s


def rocket() -> gs.Simulation:
    s = sim(gravity=(0, 0, 0))
    add(s, velocity=(1e6, 0, 0))
    return s


def towards_particle() -> gs.Simulation:
    s = sim(gravity=(0, 0, 0), time_step=1e-5)
    add(s, position=[[0.005, 0.01, 0.01], [0.012, 0.01, 0.01]], velocity=[[150, 0, 0], [0, 0, 0]])
    return s


def overlapping_lattice(walls: bool, overlap: float = 0.45) -> gs.Simulation:
    """216 spheres (r = 1 mm) overlapping their neighbours by ``overlap`` x the radius."""
    s = walled(gravity=(0, 0, 0)) if walls else sim(gravity=(0, 0, 0))
    region = gs.Box(lo=(0.004, 0.004, 0.004), hi=(0.016, 0.016, 0.016))
    add(s, position=gs.insert.lattice(region, spacing=(2 - overlap) * 1e-3), check_placement=False)
    return s


@case(Y, "particle", "overlaps|moved|left the domain", response="either")
def initial_overlaps_in_walls(t: Probe) -> str:
    """216 spheres overlapping by 45 % (under the guard's 50 %) in a walled box"""
    with t.fault():
        s = overlapping_lattice(True)
        s.run(steps=3000, progress=False)
        x = s.gather(("position",))["position"]
    outside = int(np.count_nonzero(np.any((x < 0) | (x > 0.02), axis=1)))
    if s.lost_particles or outside:
        raise Silent(f"{s.lost_particles} lost, {outside} outside the walls, without an error")
    ke = s.kinetic_energy()
    raise Fine(f"no particle lost or outside the walls (kinetic energy {ke:.3g} J at the end)")


def fast_wall(kind: str) -> gs.Simulation:
    """A wall at 500 m/s (5 mm per step, 2.5 diameters) driven through a resting sphere."""
    s = sim(gravity=(0, 0, 0), time_step=1e-5)
    if kind == "plane":
        wall = s.add_wall(gs.Plane(point=(0.003, 0, 0), normal=(1, 0, 0), material=GLASS))
    else:
        wall = s.add_wall(
            gs.Rectangle(corner=(0.003, 0.005, 0.005), edge1=(0, 0.01, 0), edge2=(0, 0, 0.01),
                         material=GLASS)
        )  # fmt: skip
    add(s)
    wall.set_motion(velocity=(500.0, 0, 0))
    return s


def on_mesh() -> gs.Simulation:
    s = sim(gravity=(0, 0, 0))
    v = np.array([[0, 0, 0], [0.02, 0, 0], [0, 0.02, 0], [0.02, 0.02, 0]], float) + [0, 0, 0.01]
    s.add_wall(gs.geometry.Mesh(vertices=v, triangles=[[0, 1, 2], [1, 3, 2]], material=GLASS))
    add(s)
    return s


def falling_out(policy: str) -> gs.Simulation:
    s = sim(time_step=1e-5, lost_particles=policy)
    add(s, position=[[0.005, 0.01, 0.002], [0.015, 0.01, 0.002]])
    return s


RUN = {"steps": 2000}
MOVED = ("particle", "moved|overlaps|non-finite")
physics_case("tunnel_through_wall", "a sphere at 150 m/s (1.5 radii per step) towards a wall",
             lambda: launched(150.0), {"steps": 100}, *MOVED)  # fmt: skip
physics_case("tunnel_through_particle", "a sphere at 150 m/s towards another sphere",
             towards_particle, {"steps": 100}, *MOVED)  # fmt: skip
physics_case("forced_time_step_100x", "force_time_step with 100 x the default step (a settle)",
             lambda: settle(time_step=1.7e-3, force_time_step=True), RUN, *MOVED)  # fmt: skip
physics_case("huge_gravity", "gravity -1e7 m/s^2 on a settling bed",
             lambda: settle(gravity=(0, 0, -1e7)), RUN, *MOVED)  # fmt: skip
physics_case("strong_gravity", "gravity -1e5 m/s^2 on a settling bed",
             lambda: settle(gravity=(0, 0, -1e5)), RUN, *MOVED)  # fmt: skip
physics_case("stiff_linear_law", "Linear(normal_stiffness=1e9) with the Rayleigh-based step",
             lambda: settle(contact=gs.contact.Linear(normal_stiffness=1e9)), {"until": 0.1},
             *MOVED)  # fmt: skip
physics_case("velocity_million", "a sphere launched at 1e6 m/s (default time step)", rocket,
             {"steps": 10}, *MOVED, reject=("time inf s",))  # fmt: skip
physics_case("initial_overlaps_blow_out", "216 spheres overlapping by 45 %, no walls",
             lambda: overlapping_lattice(False), {"steps": 3000}, "left the domain|particle",
             "ids|moved|overlaps", response="either")  # fmt: skip
physics_case("initial_overlaps_60_percent", "216 spheres overlapping by 60 % in a walled box",
             lambda: overlapping_lattice(True, 0.6), {"steps": 3000}, "particle",
             "overlaps|moved")  # fmt: skip
physics_case("plane_wall_at_500_m_s", "a plane wall at 500 m/s through a resting sphere",
             lambda: fast_wall("plane"), {"steps": 3}, "wall", "particle")  # fmt: skip
physics_case("rectangle_wall_at_500_m_s", "a rectangle wall at 500 m/s jumps over a sphere",
             lambda: fast_wall("rectangle"), {"steps": 3}, "wall", "particle")  # fmt: skip
physics_case("sphere_centre_on_mesh", "a sphere whose centre lies on a mesh wall", on_mesh,
             {"steps": 10}, "wall 0", "particle 0|index 0")  # fmt: skip
physics_case("lost_particles_warn", "2 spheres fall through the open floor (policy warn)",
             lambda: falling_out("warn"), {"until": 0.03}, "left the domain", "ids 0, 1",
             response="warning")  # fmt: skip
physics_case("lost_particles_error", "2 spheres fall through the open floor (policy error)",
             lambda: falling_out("error"), {"until": 0.03},
             "left the domain", "ids 0, 1")  # fmt: skip

# ---------------------------------------------------------------------------------------------
# hierarchies

H = "hierarchy"
SIZE = gs.dist.Uniform(0.95e-3, 1.05e-3)
REGION = gs.Box(lo=(0.008, 0.008, 0.0), hi=(0.032, 0.032, 0.03))
TALL = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.04, 0.08))


def reference(**extra: Any) -> gs.scaling.ParameterSet:
    """A stream of d = 2 mm spheres poured into a closed box 40 x 40 x 80 mm."""
    face = gs.insert.DiscFace(centre=(0.02, 0.02, 0.075), normal=(0, 0, -1), radius=0.012)
    pour = gs.insert.Stream(face, mass_rate=0.08, radius=SIZE, material=GLASS,
                            velocity=(0, 0, -1.0), seed=5)  # fmt: skip
    args: dict[str, Any] = {
        "domain": TALL,
        "contact": gs.contact.HertzMindlin(restitution=0.5, friction=0.5),
        "walls": tuple(gs.geometry.box_walls(TALL, GLASS)),
        "insertions": (pour,),
        "size": SIZE,
    }
    return gs.scaling.ParameterSet(**(args | extra))


def hierarchy(levels: list[gs.Level], **kw: Any) -> gs.Hierarchy:
    args: dict[str, Any] = {"base": reference(), "exchange": gs.Exchange(every=1e-3)}
    return gs.Hierarchy(levels=levels, **(args | kw))


def small_hierarchy() -> gs.Hierarchy:
    """Two levels, h = 2 over the box and h = 1 in a box at its floor."""
    return hierarchy([gs.Level(cg=2), gs.Level(cg=1, region=REGION)])


def hierarchy_case(name: str, what: str, make: Any, *expect: str, **options: Any) -> None:
    def go(t: Probe) -> None:
        with t.fault():
            make()

    go.__name__, go.__doc__ = name, what
    case(H, *expect, **options)(go)


Lv = gs.Level
hierarchy_case("level_cg_zero", "Level(cg=0)", lambda: Lv(cg=0), "Level.cg", "got 0")
hierarchy_case("level_cg_negative", "Level(cg=-2)", lambda: Lv(cg=-2), "Level.cg", "-2")
hierarchy_case("level_cg_nan", "Level(cg=nan)", lambda: Lv(cg=NAN), "Level.cg", "nan")
hierarchy_case("level_region_string", "Level(cg=1, region='floor')",
               lambda: Lv(cg=1, region="floor"), "Level.region", "'floor'")  # fmt: skip
hierarchy_case("exchange_every_negative", "Exchange(every=-1e-3)",
               lambda: gs.Exchange(every=-1e-3), "Exchange.every", "-0.001")  # fmt: skip
hierarchy_case("exchange_fade_above_layer", "Exchange(layer=1, fade=2)",
               lambda: gs.Exchange(layer=1, fade=2), "Exchange.fade", "2")  # fmt: skip
hierarchy_case("exchange_samples_zero", "Exchange(samples=0)",
               lambda: gs.Exchange(samples=0), "Exchange.samples", "got 0")  # fmt: skip
hierarchy_case("hierarchy_base_string", "Hierarchy(base='x')",
               lambda: gs.Hierarchy(base="x", levels=[Lv(cg=1)]),
               "Hierarchy.base", "'x'")  # fmt: skip
hierarchy_case("hierarchy_no_levels", "Hierarchy(levels=[])", lambda: hierarchy([]),
               "Hierarchy.levels", "[]")  # fmt: skip
hierarchy_case("hierarchy_ratios_increasing", "levels [h = 1, h = 2 in a region]",
               lambda: hierarchy([Lv(cg=1), Lv(cg=2, region=REGION)]),
               "levels[1].cg", "2")  # fmt: skip
hierarchy_case("hierarchy_coarsest_with_region", "the coarsest level given a region",
               lambda: hierarchy([Lv(cg=2, region=REGION), Lv(cg=1, region=REGION)]),
               "levels[0]", "region")  # fmt: skip
hierarchy_case("hierarchy_fine_without_region", "a finer level without a region",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1)]),
               "levels[1].region", "None|given")  # fmt: skip
hierarchy_case("hierarchy_region_outside", "a region reaching 20 mm outside the domain",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1, region=gs.Box(lo=(0.03, 0.03, 0),
                                                                    hi=(0.06, 0.06, 0.03)))]),
               "levels[1].region", "0.06")  # fmt: skip
hierarchy_case("hierarchy_region_too_small", "a region 4 mm across (2 parent diameters)",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1, region=gs.Box(lo=(0.018, 0.018, 0),
                                                                   hi=(0.022, 0.022, 0.03)))]),
               "levels[1].region", "too small")  # fmt: skip
hierarchy_case("hierarchy_cell_size_small", "Exchange(cell_size=1e-3) below the valid range",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1, region=REGION)],
                                 exchange=gs.Exchange(every=1e-3, cell_size=1e-3)),
               "cell_size", "0.001")  # fmt: skip
hierarchy_case("hierarchy_scheme_typo", "Hierarchy(scheme='magic')",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1, region=REGION)], scheme="magic"), "scheme",
               "'magic'")  # fmt: skip
hierarchy_case("hierarchy_base_without_particles", "a reference that inserts no particles",
               lambda: gs.Hierarchy(base=gs.scaling.ParameterSet(domain=TALL), levels=[Lv(cg=1)]),
               "Hierarchy.base", "particles")  # fmt: skip
hierarchy_case("hierarchy_finer_than_reference", "levels [h = 1, h = 0.5 in a region]",
               lambda: hierarchy([Lv(cg=1), Lv(cg=0.5, region=REGION)]), "cg", "0.5",
               response="either")  # fmt: skip
A = gs.Box(lo=(0.0, 0.0, 0.0), hi=(0.024, 0.024, 0.03))
B = gs.Box(lo=(0.012, 0.012, 0.0), hi=(0.04, 0.04, 0.03))
hierarchy_case("hierarchy_sibling_regions_overlap", "two finer levels whose regions overlap",
               lambda: hierarchy([Lv(cg=2), Lv(cg=1.5, region=A), Lv(cg=1, region=B)]),
               "region", "overlap")  # fmt: skip


@case(H, "intervals", "-1")
def hierarchy_run_negative(t: Probe) -> None:
    """Hierarchy.run(intervals=-1)"""
    h = small_hierarchy()
    with t.fault():
        h.run(intervals=-1)


@case(H, "region|levels[1]", "h.h5")
def hierarchy_restart_other_region(t: Probe) -> None:
    """Hierarchy.restart of a checkpoint written with another fine region"""
    h = small_hierarchy()
    h.run(intervals=1)
    path = t.work / "h.h5"
    h.checkpoint(path)
    other = gs.Box(lo=(0.006, 0.006, 0.0), hi=(0.034, 0.034, 0.03))
    h2 = hierarchy([gs.Level(cg=2), gs.Level(cg=1, region=other)])
    with t.fault():
        h2.restart(path)


# ---------------------------------------------------------------------------------------------
# MPI: two ranks (the fault differs between the ranks)

X = "mpi (2 ranks)"
LONG = gs.Box(lo=(0, 0, 0), hi=(0.04, 0.02, 0.02))


def mpi_bed() -> gs.Simulation:
    """342 spheres in a walled 40 x 20 x 20 mm box, split along x over the ranks."""
    s = walled(box=LONG, time_step=2e-6)
    add(s, position=gs.insert.lattice(gs.Box(lo=(0, 0, 0), hi=(0.04, 0.02, 0.006)), 2.05e-3))
    s.run(steps=10, progress=False)
    return s


def mpi_case(name: str, what: str, fault: Any, *expect: str, **options: Any) -> None:
    def go(t: Probe) -> None:
        s = mpi_bed()
        if s.ranks != 2:
            raise RuntimeError(f"an MPI case needs 2 ranks, got {s.ranks}")
        with t.fault():
            note = fault(s, t)
        if note:
            raise Silent(str(note))

    go.__name__, go.__doc__ = name, what
    case(X, *expect, ranks=2, **options)(go)


def differing_particles(s: gs.Simulation, t: Probe) -> str:
    """Rank 0 adds spheres at x = 10 and 30 mm, rank 1 one at x = 12 mm (a user's bug)."""
    xs = (0.01, 0.03) if s.rank == 0 else (0.012,)
    ids = add(s, position=[[x, 0.01, 0.015] for x in xs])
    s.run(steps=10, progress=False)
    return (
        f"asked for {len(xs)} sphere(s), got ids {list(map(int, ids))}; "
        f"{s.num_particles} particles in all (342 before)"
    )


def bad_input_one_rank(s: gs.Simulation, t: Probe) -> str:
    pos = CENTRE if s.rank == 0 else [[np.nan, 0.01, 0.015]]
    add(s, position=pos)
    s.run(steps=10, progress=False)
    return f"no error, {s.num_particles} particles"


def user_error_one_rank(s: gs.Simulation, t: Probe) -> None:
    if s.rank == 1:
        raise KeyError("user's own error on rank 1 only, between two runs")
    s.run(steps=10, progress=False)


def differing_motion(s: gs.Simulation, t: Probe) -> str:
    s.walls[5].set_motion(velocity=(0, 0, -0.1 * (1 + s.rank)))
    s.run(steps=20, progress=False)
    return f"lid at z = {s.walls[5].position[2]:.9f} m"


def differing_time_step(s: gs.Simulation, t: Probe) -> str:
    s.time_step = 1e-6 * (1 + s.rank)
    s.run(steps=10, progress=False)
    return f"t = {s.time:g} s after 10 more steps"


def nan_on_one_rank(s: gs.Simulation, t: Probe) -> None:
    with s.particles() as p:
        if s.rank == 1 and len(p):
            p.velocity[0] = np.nan
    s.run(steps=20, progress=False)


class FailingWriter:
    """An output operation that fails on rank 1 only (a full disk)."""

    def next_step(self, step: int, time: float, time_step: float) -> int:
        return step + 3

    def write(self, sim: gs.Simulation) -> None:
        if sim.rank == 1:
            raise OSError("no space left on device (rank 1 only)")


def writer_fails_one_rank(s: gs.Simulation, t: Probe) -> None:
    s.output(FailingWriter())
    s.run(steps=20, progress=False)


def hierarchy_run_differs(s: gs.Simulation, t: Probe) -> None:
    h = small_hierarchy()
    h.run(intervals=1 + h.sims[0].rank)


ONE_EACH = ("steps", "rank 0", "rank 1")
mpi_case("mpi_run_steps_differ", "run(steps=10 + rank)",
         lambda s, t: s.run(steps=10 + s.rank, progress=False), *ONE_EACH)  # fmt: skip
mpi_case("mpi_run_until_differs", "run(until=...) different on the ranks",
         lambda s, t: s.run(until=1e-4 * (1 + s.rank), progress=False),
         "until", "rank 1")  # fmt: skip
mpi_case("mpi_checkpoint_path_differs", "checkpoint(path) with a path per rank",
         lambda s, t: s.checkpoint(t.work / f"c{s.rank}.h5"), "path", "c1.h5")  # fmt: skip
mpi_case("mpi_processor_grid_wrong", "Simulation(processor_grid=(3, 1, 1)) on 2 ranks",
         lambda s, t: gs.Simulation(domain=LONG, processor_grid=(3, 1, 1)), "processor_grid",
         "(3, 1, 1)")  # fmt: skip
mpi_case("mpi_particles_differ", "add_particles with different particles on each rank",
         differing_particles, "add_particles", "rank")  # fmt: skip
mpi_case("mpi_bad_input_one_rank", "add_particles with a NaN on rank 1 only (ValueError there)",
         bad_input_one_rank, "position", "nan|every rank must pass the same",
         timeout=30)  # fmt: skip
mpi_case("mpi_user_error_one_rank", "an uncaught exception on rank 1 only between runs",
         user_error_one_rank, "rank 1 only", uncaught=True, timeout=30,
         types=("KeyError",))  # fmt: skip
mpi_case("mpi_wall_motion_differs", "wall.set_motion with a different velocity on each rank",
         differing_motion, "velocity", "rank")  # fmt: skip
mpi_case("mpi_time_step_differs", "sim.time_step set differently on each rank",
         differing_time_step, "time_step", "rank")  # fmt: skip
mpi_case("mpi_nan_on_one_rank", "a NaN velocity on rank 1's particle only", nan_on_one_rank,
         "non-finite", "rank 1|particle")  # fmt: skip
mpi_case("mpi_writer_fails_one_rank", "an output writer that fails on rank 1 only",
         writer_fails_one_rank, "no space left", "rank 1",
         types=("ValueError", "TypeError", "RuntimeError", "OSError"))  # fmt: skip
mpi_case("mpi_hierarchy_run_differs", "Hierarchy.run(intervals=1 + rank)", hierarchy_run_differs,
         "intervals", "rank 1")  # fmt: skip
