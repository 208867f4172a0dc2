"""The case table of fault_probe.py (part 1: the machinery and the constructors' inputs).

A case is one kind of bad input or fault, tried through the public API only, as a new user
would. It runs in a subprocess of its own (fault_probe.py --worker NAME); ``Probe.fault()``
marks where the fault begins: an exception raised before it is a failure of the probe's own
set-up, not of the library. Each case declares what a clear response contains:

- ``expect``: substrings the error (or warning) message must all contain, case-insensitively
  (``"a|b"``: either), usually the parameter's name and the offending value;
- ``response``: ``"error"`` (an exception of one of ``types``), ``"warning"`` (a warning, e.g.
  lost particles under the default policy; a matching error counts too) or ``"either"``;
- ``reject``: substrings a clear message must not contain (a wrong value, say).

A case may end itself with :class:`Silent` (no error, a wrong result found) or :class:`Fine`
(the fault did no harm and nothing was owed, e.g. a flipped byte the file does not use).

Parts 2 and 3 (fault_cases_files.py, fault_cases_run.py) add their cases to ``CASES``.
"""

from __future__ import annotations

import signal
import warnings
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs

CLEAR_TYPES = ("ValueError", "TypeError", "RuntimeError")


class Silent(Exception):  # noqa: N818 - an outcome, not an error of the probe
    """Raised by a case that found no error where one was owed, or a wrong result."""


class Fine(Exception):  # noqa: N818
    """Raised by a case whose fault did no harm and owed no error (e.g. an unused byte)."""


class Probe:
    """What a case gets: a work directory (shared by the ranks of an MPI case), the marker of
    where the fault starts, and the warnings recorded since."""

    def __init__(self, work: Path, caught: list[warnings.WarningMessage]) -> None:
        self.work = work
        self.entered = False
        self._caught = caught
        self.warnings_from = 0

    @contextmanager
    def fault(self) -> Iterator[None]:
        """The block that holds the fault: what it raises is the library's response."""
        self.entered = True
        self.warnings_from = len(self._caught)
        yield

    @contextmanager
    def deadline(self, seconds: int, what: str) -> Iterator[None]:
        """Raises Silent if the block still runs after ``seconds`` (a request accepted that
        would run for ever; the handler runs between the run's C++ chunks)."""

        def expired(_signum: int, _frame: Any) -> None:
            raise Silent(f"{what}: accepted without a word, still running after {seconds} s")

        previous = signal.signal(signal.SIGALRM, expired)
        signal.alarm(seconds)
        try:
            yield
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, previous)


@dataclass(frozen=True)
class Case:
    name: str
    group: str
    run: Callable[[Probe], object]
    expect: tuple[str, ...]
    what: str
    response: str = "error"  # "error", "warning" or "either"
    types: tuple[str, ...] = CLEAR_TYPES
    reject: tuple[str, ...] = ()
    ranks: int = 1
    timeout: float | None = None  # None: the probe's --timeout
    uncaught: bool = False  # MPI: the worker re-raises, as a user's script would die


CASES: dict[str, Case] = {}
GROUPS = (
    "materials",
    "contact laws",
    "geometry",
    "simulation",
    "particles",
    "walls",
    "insertion",
    "run",
    "output",
    "checkpoints",
    "stl files",
    "views",
    "runtime physics",
    "guards",
    "scaling and sizes",
    "hierarchy",
    "mpi (2 ranks)",
)  # the order of the report


def _register(c: Case) -> None:
    if c.name in CASES:
        raise KeyError(f"two fault cases named {c.name!r}")
    CASES[c.name] = c


def case(group: str, *expect: str, **options: Any) -> Callable[[Callable[[Probe], object]], Any]:
    """Decorator: a case whose function takes the Probe (the first docstring line says what)."""

    def register(fn: Callable[[Probe], object]) -> Callable[[Probe], object]:
        what = (fn.__doc__ or fn.__name__).strip().splitlines()[0]
        _register(Case(fn.__name__, group, fn, tuple(expect), what, **options))
        return fn

    return register


def simple(name: str, group: str, what: str, call: Callable[[], object], *expect: str) -> None:
    """A case that is one call (no set-up): the whole call is the fault."""

    def run(t: Probe) -> None:
        with t.fault():
            call()

    _register(Case(name, group, run, tuple(expect), what))


# ---------------------------------------------------------------------------------------------
# shared set-ups

GLASS = gs.Material(density=2500, youngs_modulus=1e7, poisson_ratio=0.3, name="glass")
STEEL = gs.Material(density=7800, youngs_modulus=2e8, poisson_ratio=0.3, name="steel")
BOX = gs.Box(lo=(0, 0, 0), hi=(0.02, 0.02, 0.02))
CENTRE = [[0.01, 0.01, 0.01]]
NAN, INF = float("nan"), float("inf")


def material(**kw: Any) -> gs.Material:
    args: dict[str, Any] = {"density": 2500, "youngs_modulus": 1e7, "poisson_ratio": 0.3}
    return gs.Material(**(args | kw))


def sim(**kw: Any) -> gs.Simulation:
    return gs.Simulation(**({"domain": BOX} | kw))


def one(**kw: Any) -> gs.Simulation:
    """A simulation holding one sphere (r = 1 mm) at the centre of the 20 mm box."""
    s = sim(**kw)
    s.add_particles(position=CENTRE, radius=1e-3, material=GLASS)
    return s


def walled(box: gs.Box = BOX, wall_material: gs.Material = GLASS, **kw: Any) -> gs.Simulation:
    """A simulation in ``box`` closed by six planes."""
    s = gs.Simulation(domain=box, **kw)
    for w in gs.geometry.box_walls(box, wall_material):
        s.add_wall(w)
    return s


def settle(**kw: Any) -> gs.Simulation:
    """60 spheres (r 0.8-1 mm) at random in the walled box."""
    s = walled(**kw)
    r = np.random.default_rng(1).uniform(0.8e-3, 1e-3, 60)
    s.add_particles(position=gs.insert.random_in_box(BOX, r, seed=2), radius=r, material=GLASS)
    return s


def disc_face() -> gs.insert.DiscFace:
    return gs.insert.DiscFace(centre=(0.01, 0.01, 0.015), normal=(0, 0, -1), radius=0.005)


def stream(**kw: Any) -> gs.insert.Stream:
    args: dict[str, Any] = {
        "mass_rate": 0.01,
        "radius": 1e-3,
        "material": GLASS,
        "velocity": (0, 0, -1),
    }
    return gs.insert.Stream(disc_face(), **(args | kw))


def pack(**kw: Any) -> gs.insert.Pack:
    args: dict[str, Any] = {"radius": 1e-3, "material": GLASS, "count": 5}
    return gs.insert.Pack(BOX, **(args | kw))


def servo(**kw: Any) -> gs.geometry.Servo:
    args: dict[str, Any] = {"gain": 1e-2, "max_speed": 0.05, "target_force": 0.01}
    return gs.geometry.Servo(**(args | kw))


def add(s: gs.Simulation, **kw: Any) -> Any:
    args: dict[str, Any] = {"position": CENTRE, "radius": 1e-3, "material": GLASS}
    return s.add_particles(**(args | kw))


# ---------------------------------------------------------------------------------------------
# materials

M = "materials"
simple("material_density_negative", M, "Material(density=-2500)",
       lambda: material(density=-2500), "Material.density", "-2500")  # fmt: skip
simple("material_density_zero", M, "Material(density=0)",
       lambda: material(density=0), "Material.density", "got 0")  # fmt: skip
simple("material_density_nan", M, "Material(density=nan)",
       lambda: material(density=NAN), "Material.density", "nan")  # fmt: skip
simple("material_density_inf", M, "Material(density=inf)",
       lambda: material(density=INF), "Material.density", "inf")  # fmt: skip
simple("material_density_string", M, "Material(density='2500')",
       lambda: material(density="2500"), "Material.density", "'2500'")  # fmt: skip
simple("material_density_complex", M, "Material(density=2500+0j)",
       lambda: material(density=2500 + 0j), "Material.density", "2500+0j")  # fmt: skip
simple("material_density_bool", M, "Material(density=True)",
       lambda: material(density=True), "Material.density", "True")  # fmt: skip
simple("material_density_array", M, "Material(density=np.array([2500, 2600]))",
       lambda: material(density=np.array([2500, 2600])), "Material.density", "2500")  # fmt: skip
simple("material_youngs_negative", M, "Material(youngs_modulus=-1e7)",
       lambda: material(youngs_modulus=-1e7), "youngs_modulus", "-1")  # fmt: skip
simple("material_youngs_nan", M, "Material(youngs_modulus=nan)",
       lambda: material(youngs_modulus=NAN), "youngs_modulus", "nan")  # fmt: skip
simple("material_youngs_string", M, "Material(youngs_modulus='1e7'): a string",
       lambda: material(youngs_modulus="1e7"), "youngs_modulus", "'1e7'")  # fmt: skip
simple("material_poisson_half", M, "Material(poisson_ratio=0.5)",
       lambda: material(poisson_ratio=0.5), "poisson_ratio", "0.5")  # fmt: skip
simple("material_poisson_negative", M, "Material(poisson_ratio=-0.1)",
       lambda: material(poisson_ratio=-0.1), "poisson_ratio", "-0.1")  # fmt: skip
simple("material_restitution_above_one", M, "Material(restitution=1.5)",
       lambda: material(restitution=1.5), "Material.restitution", "1.5")  # fmt: skip
simple("material_friction_negative", M, "Material(friction=-0.2)",
       lambda: material(friction=-0.2), "Material.friction", "-0.2")  # fmt: skip

# ---------------------------------------------------------------------------------------------
# contact laws

C = "contact laws"
law = gs.contact
simple("hertz_restitution_negative", C, "HertzMindlin(restitution=-0.5)",
       lambda: law.HertzMindlin(restitution=-0.5), "HertzMindlin.restitution", "-0.5")  # fmt: skip
simple("hertz_restitution_nan", C, "HertzMindlin(restitution=nan)",
       lambda: law.HertzMindlin(restitution=NAN), "restitution", "nan")  # fmt: skip
simple("hertz_friction_inf", C, "HertzMindlin(friction=inf)",
       lambda: law.HertzMindlin(friction=INF), "HertzMindlin.friction", "inf")  # fmt: skip
simple("hertz_rolling_number", C, "HertzMindlin(rolling=0.1) instead of a rolling model",
       lambda: law.HertzMindlin(rolling=0.1), "HertzMindlin.rolling", "0.1")  # fmt: skip
simple("hertz_history_typo", C, "HertzMindlin(tangential_history='totl')",
       lambda: law.HertzMindlin(tangential_history="totl"),
       "tangential_history", "totl")  # fmt: skip
simple("hertz_limit_force_string", C, "HertzMindlin(limit_force='no'): a string as a flag",
       lambda: law.HertzMindlin(limit_force="no"), "limit_force", "'no'")  # fmt: skip
simple("hertz_pairs_names", C, "HertzMindlin(pairs={('glass', 'steel'): Pair()}): names as keys",
       lambda: law.HertzMindlin(pairs={("glass", "steel"): law.Pair()}),
       "pairs", "glass")  # fmt: skip
simple("linear_stiffness_negative", C, "Linear(normal_stiffness=-1e5)",
       lambda: law.Linear(normal_stiffness=-1e5), "Linear.normal_stiffness", "-1")  # fmt: skip
simple("linear_velocity_zero", C, "Linear(characteristic_velocity=0)",
       lambda: law.Linear(characteristic_velocity=0),
       "characteristic_velocity", "got 0")  # fmt: skip
simple("eepa_exponent_two", C, "EEPA(exponent=2)",
       lambda: law.EEPA(exponent=2), "EEPA.exponent", "2")  # fmt: skip
simple("eepa_unloading_ratio_below_one", C, "EEPA(unloading_ratio=0.5)",
       lambda: law.EEPA(unloading_ratio=0.5), "unloading_ratio", "0.5")  # fmt: skip
simple("eepa_unloading_ratio_string", C, "EEPA(unloading_ratio='3'): a string",
       lambda: law.EEPA(unloading_ratio="3"), "unloading_ratio", "'3'")  # fmt: skip
simple("eepa_pull_off_nan", C, "EEPA(pull_off_force=nan)",
       lambda: law.EEPA(pull_off_force=NAN), "pull_off_force", "nan")  # fmt: skip
simple("epsd_negative", C, "EPSD(rolling_friction=-0.1)",
       lambda: law.EPSD(-0.1), "EPSD.rolling_friction", "-0.1")  # fmt: skip
simple("pair_restitution_two", C, "Pair(restitution=2)",
       lambda: law.Pair(restitution=2), "Pair.restitution", "2")  # fmt: skip
simple("pair_unloading_ratio_string", C, "Pair(unloading_ratio='3'): a string",
       lambda: law.Pair(unloading_ratio="3"), "Pair.unloading_ratio", "'3'")  # fmt: skip
simple("simulation_contact_string", C, "Simulation(contact='hertz')",
       lambda: sim(contact="hertz"), "Simulation.contact", "'hertz'")  # fmt: skip

# ---------------------------------------------------------------------------------------------
# geometry

G = "geometry"
geo = gs.geometry
TRI = np.array([[0, 0, 0], [0.02, 0, 0], [0, 0.02, 0]], float)
simple("box_inverted", G, "Box(lo=(0, 0, 0), hi=(0.01, 0.01, -0.01))",
       lambda: gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, -0.01)), "Box.hi", "-0.01")  # fmt: skip
simple("box_flat", G, "Box with hi = lo along z",
       lambda: gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0)), "Box.hi", "0.01, 0.01, 0")  # fmt: skip
simple("box_nan", G, "Box(lo=(nan, 0, 0))",
       lambda: gs.Box(lo=(NAN, 0, 0), hi=(1, 1, 1)), "Box.lo", "nan")  # fmt: skip
simple("box_periodic_two", G, "Box(periodic=(True, False)): two entries",
       lambda: gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic=(True, False)), "Box.periodic",
       "(True, False)")  # fmt: skip
simple("box_periodic_string", G, "Box(periodic='yes'): a string",
       lambda: gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic="yes"),
       "Box.periodic", "'yes'")  # fmt: skip
simple("box_periodic_none", G, "Box(periodic=None)",
       lambda: gs.Box(lo=(0, 0, 0), hi=(1, 1, 1), periodic=None),
       "Box.periodic", "None")  # fmt: skip
simple("plane_zero_normal", G, "Plane(normal=(0, 0, 0))",
       lambda: gs.Plane(point=(0, 0, 0), normal=(0, 0, 0)),
       "Plane.normal", "(0, 0, 0)")  # fmt: skip
simple("plane_nan_point", G, "Plane(point=(0, nan, 0))",
       lambda: gs.Plane(point=(0, NAN, 0), normal=(0, 0, 1)), "Plane.point", "nan")  # fmt: skip
simple("plane_material_name", G, "Plane(material='steel'): a name for a Material",
       lambda: gs.Plane(point=(0, 0, 0), normal=(0, 0, 1), material="steel"), "Plane.material",
       "'steel'")  # fmt: skip
simple("rectangle_parallel_edges", G, "Rectangle with parallel edges",
       lambda: gs.Rectangle(corner=(0, 0, 0), edge1=(1, 0, 0), edge2=(2, 0, 0)), "Rectangle.edge2",
       "(2, 0, 0)")  # fmt: skip
simple("cylinder_negative_radius", G, "Cylinder(radius=-0.01)",
       lambda: geo.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=-0.01), "Cylinder.radius",
       "-0.01")  # fmt: skip
simple("cylinder_zero_axis", G, "Cylinder(axis=(0, 0, 0))",
       lambda: geo.Cylinder(point=(0, 0, 0), axis=(0, 0, 0), radius=0.01), "Cylinder.axis",
       "(0, 0, 0)")  # fmt: skip
simple("cylinder_negative_length", G, "Cylinder(length=-0.1)",
       lambda: geo.Cylinder(point=(0, 0, 0), axis=(0, 0, 1), radius=0.01, length=-0.1),
       "Cylinder.length", "-0.1")  # fmt: skip
simple("mesh_index_out_of_range", G, "Mesh with a triangle index 5 of 3 vertices",
       lambda: geo.Mesh(vertices=TRI, triangles=[[0, 1, 5]]), "Mesh.triangles", "5")  # fmt: skip
simple("mesh_negative_index", G, "Mesh with a triangle index -1",
       lambda: geo.Mesh(vertices=TRI, triangles=[[0, 1, -1]]), "Mesh.triangles", "-1")  # fmt: skip
simple("mesh_nan_vertex", G, "Mesh with a NaN vertex",
       lambda: geo.Mesh(vertices=np.where(TRI == 0.02, NAN, TRI), triangles=[[0, 1, 2]]),
       "Mesh.vertices", "nan")  # fmt: skip
simple("mesh_no_triangles", G, "Mesh with no triangles",
       lambda: geo.Mesh(vertices=TRI, triangles=np.zeros((0, 3), int)),
       "Mesh.triangles", "(0, 3)")  # fmt: skip
simple("mesh_float_triangles", G, "Mesh with float triangle indices [0, 1, 2.5]",
       lambda: geo.Mesh(vertices=TRI, triangles=[[0, 1, 2.5]]),
       "Mesh.triangles", "2.5")  # fmt: skip
simple("servo_negative_gain", G, "Servo(gain=-1)",
       lambda: servo(gain=-1), "Servo.gain", "-1")  # fmt: skip
simple("servo_two_targets", G, "Servo with target_force and target_stress",
       lambda: servo(target_stress=100.0), "target_force", "target_stress")  # fmt: skip

# ---------------------------------------------------------------------------------------------
# Simulation constructor and settings

S = "simulation"
simple("sim_domain_tuple", S, "Simulation(domain=((0, 0, 0), (1, 1, 1)))",
       lambda: gs.Simulation(domain=((0, 0, 0), (1, 1, 1))),
       "Simulation.domain", "(0, 0, 0)")  # fmt: skip
simple("sim_dimension_four", S, "Simulation(dimension=4)",
       lambda: sim(dimension=4), "Simulation.dimension", "4")  # fmt: skip
simple("sim_gravity_nan", S, "Simulation(gravity=(0, 0, nan))",
       lambda: sim(gravity=(0, 0, NAN)), "Simulation.gravity", "nan")  # fmt: skip
simple("sim_gravity_two", S, "Simulation(gravity=(0, -9.81))",
       lambda: sim(gravity=(0, -9.81)), "Simulation.gravity", "(0, -9.81)")  # fmt: skip
simple("sim_gravity_complex", S, "Simulation(gravity=(0, 0, -9.81+0j))",
       lambda: sim(gravity=(0, 0, -9.81 + 0j)), "Simulation.gravity", "9.81+0j")  # fmt: skip
simple("sim_time_step_negative", S, "Simulation(time_step=-1e-5)",
       lambda: sim(time_step=-1e-5), "Simulation.time_step", "-1e-05")  # fmt: skip
simple("sim_time_step_zero", S, "Simulation(time_step=0)",
       lambda: sim(time_step=0), "Simulation.time_step", "got 0")  # fmt: skip
simple("sim_time_step_string", S, "Simulation(time_step='1e-5')",
       lambda: sim(time_step="1e-5"), "Simulation.time_step", "'1e-5'")  # fmt: skip
simple("sim_skin_negative", S, "Simulation(skin=-1e-3)",
       lambda: sim(skin=-1e-3), "Simulation.skin", "-0.001")  # fmt: skip
simple("sim_thermo_every_zero", S, "Simulation(thermo_every=0)",
       lambda: sim(thermo_every=0), "thermo_every", "got 0")  # fmt: skip
simple("sim_thermo_every_fraction", S, "Simulation(thermo_every=10.5)",
       lambda: sim(thermo_every=10.5), "thermo_every", "10.5")  # fmt: skip
simple("sim_thermo_every_bool", S, "Simulation(thermo_every=True)",
       lambda: sim(thermo_every=True), "thermo_every", "True")  # fmt: skip
simple("sim_force_time_step_string", S, "Simulation(force_time_step='no'): a string as a flag",
       lambda: one(time_step=1e-3, force_time_step="no").run(steps=1, progress=False),
       "force_time_step", "'no'")  # fmt: skip
simple("sim_processor_grid_serial", S, "Simulation(processor_grid=(2, 1, 1)) in a serial run",
       lambda: sim(processor_grid=(2, 1, 1)), "processor_grid", "(2, 1, 1)")  # fmt: skip
simple("sim_lost_policy_typo", S, "Simulation(lost_particles='silent')",
       lambda: sim(lost_particles="silent"), "lost_particles", "'silent'")  # fmt: skip
simple("sim_comm_string", S, "Simulation(comm='world')",
       lambda: sim(comm="world"), "Simulation.comm", "'world'")  # fmt: skip
simple("sim_time_step_above_limit", S, "time_step 1e-3 s, 40 x the Rayleigh time, not forced",
       lambda: one(time_step=1e-3).run(steps=1, progress=False), "time_step", "0.001")  # fmt: skip
simple("sim_no_time_step_empty", S, "run() of an empty simulation without a time step",
       lambda: sim().run(steps=1, progress=False), "time_step", "None")  # fmt: skip


@case(S, "Simulation.time_step", "nan")
def sim_time_step_setter_nan(t: Probe) -> None:
    """sim.time_step = nan after the set-up"""
    s = one()
    with t.fault():
        s.time_step = NAN


@case(S, "contacts()", "record_contacts")
def sim_contacts_not_recorded(t: Probe) -> None:
    """sim.contacts() without record_contacts=True"""
    s = one()
    s.run(steps=2, progress=False)
    with t.fault():
        s.contacts()


# ---------------------------------------------------------------------------------------------
# guards and the lost-particle policy

U = "guards"
simple("guards_displacement_zero", U, "Guards(max_step_displacement=0)",
       lambda: gs.Guards(max_step_displacement=0),
       "Guards.max_step_displacement", "got 0")  # fmt: skip
simple("guards_overlap_nan", U, "Guards(max_overlap=nan)",
       lambda: gs.Guards(max_overlap=NAN), "Guards.max_overlap", "nan")  # fmt: skip
simple("guards_enabled_int", U, "Guards(enabled=1)",
       lambda: gs.Guards(enabled=1), "Guards.enabled", "1")  # fmt: skip
simple("guards_checkpoint_number", U, "Guards(emergency_checkpoint=3)",
       lambda: gs.Guards(emergency_checkpoint=3), "emergency_checkpoint", "3")  # fmt: skip
simple("sim_guards_number", U, "Simulation(guards=0.5)",
       lambda: sim(guards=0.5), "Simulation.guards", "0.5")  # fmt: skip


@case(U, "Simulation.guards", "'on'")
def sim_guards_setter_string(t: Probe) -> None:
    """sim.guards = 'on'"""
    s = one()
    with t.fault():
        s.guards = "on"


@case(U, "lost_particles", "None")
def lost_policy_setter_none(t: Probe) -> None:
    """sim.lost_particles_policy = None"""
    s = one()
    with t.fault():
        s.lost_particles_policy = None  # type: ignore[assignment]


simple("lost_policy_uppercase", U, "Simulation(lost_particles='WARN')",
       lambda: sim(lost_particles="WARN"), "lost_particles", "'WARN'")  # fmt: skip

# ---------------------------------------------------------------------------------------------
# scaling, distributions, helpers

D = "scaling and sizes"
dist = gs.dist
simple("scale_h_zero", D, "scaling.scale(params, h=0)",
       lambda: gs.scaling.scale(gs.scaling.ParameterSet(domain=BOX), 0), "h", "got 0")  # fmt: skip
simple("scale_scheme_typo", D, "scaling.scale(params, 2, scheme='magic')",
       lambda: gs.scaling.scale(gs.scaling.ParameterSet(domain=BOX), 2, "magic"), "scheme",
       "'magic'")  # fmt: skip
simple("scale_dimension_four", D, "scaling.scale(params, 2, dimension=4)",
       lambda: gs.scaling.scale(gs.scaling.ParameterSet(domain=BOX), 2, "cg", dimension=4),
       "dimension", "4")  # fmt: skip
simple("parameterset_servo_index", D, "ParameterSet(servos={5: Servo}) without walls",
       lambda: gs.scaling.ParameterSet(domain=BOX, servos={5: servo()}), "servos", "5")  # fmt: skip
simple("build_simulation_dict", D, "scaling.build_simulation({'domain': box})",
       lambda: gs.scaling.build_simulation({"domain": BOX}), "params", "domain")  # fmt: skip
simple("uniform_inverted", D, "dist.Uniform(2e-3, 1e-3)",
       lambda: dist.Uniform(2e-3, 1e-3), "Uniform.max", "0.001")  # fmt: skip
simple("normal_negative_std", D, "dist.Normal(std=-1e-4)",
       lambda: dist.Normal(mean=1e-3, std=-1e-4, min=5e-4, max=2e-3), "std", "-0.0001")  # fmt: skip
simple("discrete_weights_short", D, "dist.Discrete with 2 radii and 1 weight",
       lambda: dist.Discrete(radii=(1e-3, 2e-3), weights=(1.0,)), "weights", "1")  # fmt: skip
simple("lattice_negative_spacing", D, "insert.lattice(box, spacing=-1e-3)",
       lambda: gs.insert.lattice(BOX, -1e-3), "lattice.spacing", "-0.001")  # fmt: skip
simple("random_in_box_negative_radius", D, "insert.random_in_box(box, radius=-1e-3)",
       lambda: gs.insert.random_in_box(BOX, -1e-3, count=3),
       "random_in_box.radius", "-0.001")  # fmt: skip
simple("random_in_box_string_radius", D, "insert.random_in_box(box, radius='1e-3'): a string",
       lambda: gs.insert.random_in_box(BOX, "1e-3", count=3), "radius", "'1e-3'")  # fmt: skip
simple("random_in_box_too_full", D, "insert.random_in_box: 5000 spheres in a 20 mm box",
       lambda: gs.insert.random_in_box(BOX, 1e-3, count=5000),
       "could not place", "fraction")  # fmt: skip
simple("rayleigh_negative_radius", D, "timestep.rayleigh_time(glass, -1e-3)",
       lambda: gs.timestep.rayleigh_time(GLASS, -1e-3), "radius", "-0.001")  # fmt: skip
simple("hertz_time_zero_speed", D, "timestep.hertz_contact_time(glass, 1e-3, 0)",
       lambda: gs.timestep.hertz_contact_time(GLASS, 1e-3, 0.0),
       "impact_velocity", "got 0")  # fmt: skip
simple("cell_averages_negative", D, "fields.CellAverages(sim, box, cell_size=-1)",
       lambda: gs.fields.CellAverages(sim(record_contacts=True), BOX, -1),
       "cell_size", "-1")  # fmt: skip
