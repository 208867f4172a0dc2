"""Simulation: one DEM system driven from Python, executed by the C++ core.

Python decides what runs and when (outputs, thermo, progress); ``run`` advances whole chunks of
steps in C++ with the GIL released, so Ctrl-C is honoured between chunks.
"""

from __future__ import annotations

import os
import sys
import time as _time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from . import _core, parallel
from ._validate import flag, id_array, positive, real_array, vector3, whole
from .contact import EEPA, ContactLaw, HertzMindlin, Linear
from .engine import Engine
from .geometry import Box, Servo
from .guards import GuardMethods, Guards
from .insert import Outlet, OutletHandle, Pack, Stream, StreamHandle
from .materials import Material, check_masses
from .particle_view import WRITABLE_FIELDS, ParticleView
from .placement import check_new_particles
from .sim_checkpoint import CheckpointMethods
from .sim_output import Output, OutputMethods
from .sim_ranks import RankMethods
from .sim_run import check_run_arguments, next_chunk, target_step
from .sim_thermo import ThermoMethods
from .sim_walls import WallHandle, WallMethods
from .strict_attributes import StrictAttributes


class Simulation(
    WallMethods,
    RankMethods,
    CheckpointMethods,
    GuardMethods,
    ThermoMethods,
    OutputMethods,
    StrictAttributes,
):
    """A DEM simulation of spheres in a box, with walls and one contact law.

    Args:
        domain: the simulation box; periodic axes wrap, particles leaving through a closed axis
            are removed and counted as lost.
        contact: the contact law (default ``HertzMindlin()``).
        gravity: m/s^2.
        time_step: s; None picks 0.2 x the smallest Rayleigh time at the first run. A step above
            0.3 x the Rayleigh time is refused unless ``force_time_step`` is True.
        skin: Verlet skin (m); None picks 0.1 x the largest diameter at the first run.
        force_time_step: accept a time step above 0.3 t_R.
        thermo_every: steps between thermo lines (None: no thermo lines; entries are still
            recorded at the end of each run in ``thermo_log``).
        quiet: do not print thermo lines.
        record_contacts: keep a record of every touching contact at the end of each run, for
            ``contacts()`` (80 bytes per contact; off by default).
        dimension: 3 (spheres) or 2 (discs of unit thickness, 1 m, for plane tests): centres
            lie in the plane z = ``plane_z`` (the domain's mid-height); z, v_z, w_x and w_y stay
            frozen (velocities zero), m = rho pi r^2 x 1 m, I = m r^2 / 2. Contact laws are the
            3-D ones (a Hertz force in 2-D is the force between the discs' sphere equivalents,
            not a line-contact law): forces are N on a 1 m thick disc, so a wall force / wall
            length is a stress per unit thickness (Pa).
        comm: the ranks that run this simulation (an mpi4py communicator); None means
            ``MPI.COMM_WORLD`` when started by ``mpirun`` with several ranks, else a serial run
            (see :mod:`grainscale.parallel`). Under MPI every rank makes the same calls with the
            same arguments; each owns the particles of its subdomain.
        processor_grid: (px, py, pz) ranks along x, y, z (px py pz = ranks); None chooses the
            grid with the smallest subdomain surface for the box's shape.
        guards: per-step checks that stop a run (:class:`~grainscale.guards.Guards`: step
            displacement and overlap as fractions of the radius, emergency checkpoint); None
            means ``Guards()``, False switches them off.
        lost_particles: ``"warn"`` (default), ``"error"`` or ``"ignore"``: the report of
            particles removed through a closed side, once per run chunk (grainscale.guards).

    Example:
        >>> import grainscale as gs
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)))
        >>> ids = sim.add_particles(position=[[0.005, 0.005, 0.005]], radius=1e-3, material=glass)
        >>> sim.run(steps=10, progress=False)
        >>> sim.step
        10
    """

    def __init__(
        self,
        domain: Box,
        contact: ContactLaw | None = None,
        gravity: Sequence[float] = (0.0, 0.0, -9.81),
        time_step: float | None = None,
        skin: float | None = None,
        force_time_step: bool = False,
        thermo_every: int | None = None,
        quiet: bool = False,
        record_contacts: bool = False,
        dimension: int = 3,
        comm: Any = None,
        processor_grid: Sequence[int] | None = None,
        guards: Guards | bool | None = None,
        lost_particles: str = "warn",
    ) -> None:
        if not isinstance(domain, Box):
            raise ValueError(f"Simulation.domain must be a grainscale.Box, got {domain!r}")
        if isinstance(dimension, bool) or dimension not in (2, 3):
            raise ValueError(f"Simulation.dimension must be 2 or 3, got {dimension!r}")
        self.domain = domain
        self._comm = parallel.resolve(comm)
        parallel.same_arguments(
            self._comm,
            "Simulation",
            domain=domain,
            contact=contact,
            gravity=gravity,
            time_step=time_step,
            skin=skin,
            force_time_step=force_time_step,
            dimension=dimension,
            processor_grid=processor_grid,
            guards=guards,
            lost_particles=lost_particles,
        )
        handle = None if self._comm is None else int(self._comm.py2f())
        self._level = _core.Level(domain.lo, domain.hi, domain.periodic, handle)
        self._level.set_dimension(int(dimension))
        self._init_guards(guards, lost_particles)
        # the package's modules (insertion, checkpoints, fields, hierarchies) use this, never
        # _level (package-internal; grainscale/engine.py)
        self.engine = Engine(self._level, self._comm)
        if processor_grid is not None:
            grid = tuple(processor_grid)
            if len(grid) != 3 or not all(isinstance(g, int) and g >= 1 for g in grid):
                raise ValueError(
                    f"Simulation.processor_grid must be three positive integers, got "
                    f"{processor_grid!r}"
                )
            self._level.set_processor_grid(grid)
        self._materials: list[Material] = []
        self.contact: ContactLaw = contact if contact is not None else HertzMindlin()
        if not isinstance(self.contact, HertzMindlin | Linear | EEPA):
            raise ValueError(
                "Simulation.contact must be a grainscale.contact law (HertzMindlin, Linear, "
                f"EEPA), got {self.contact!r}"
            )
        self.contact._apply_law(self._level)
        self._interactions_for = -1  # number of materials the interaction table was built for
        self._gravity = vector3("Simulation", "gravity", gravity)
        self._level.set_gravity(self._gravity)
        self._force_time_step = flag("Simulation", "force_time_step", force_time_step)
        self._time_step: float | None = None
        if time_step is not None:
            self.time_step = time_step
        self._skin_fixed = False
        if skin is not None:
            self._level.set_skin(positive("Simulation", "skin", skin, " (m)"))
            self._skin_fixed = True
        self.thermo_every = (
            None if thermo_every is None else whole("Simulation", "thermo_every", thermo_every, 1)
        )
        self.quiet = flag("Simulation", "quiet", quiet)
        self.record_contacts = record_contacts
        self.thermo_log: list[dict[str, float]] = []
        self._outputs: list[tuple[Output, int]] = []
        self._log_path = None  # the log file (sim.log)
        self._run_clock = None  # (wall-clock start, first step, target) of the current run
        self._walls: list[WallHandle] = []
        self._wall_spin: dict[int, tuple[float, float, float]] = {}
        self._wall_servos: dict[int, Servo] = {}
        self._header_printed = False
        self._rate_clock = (_time.perf_counter(), 0)
        self._chunk = 1  # steps per C++ call in run(), adapted to the step cost
        self._streams: list[StreamHandle] = []  # insertion and outlets
        self._outlets: list[OutletHandle] = []
        self._fixed_after_construction = ("domain", "contact", "engine")
        self._freeze_attributes()

    # ----------------------------------------------------------------- configuration
    @property
    def gravity(self) -> tuple[float, float, float]:
        """Gravitational acceleration (m/s^2); a new value acts from the next step (part of
        the set-up: a checkpoint does not hold it)."""
        return self._gravity

    @gravity.setter
    def gravity(self, value: Sequence[float]) -> None:
        parallel.same_arguments(self._comm, "Simulation.gravity", value=value)
        g = vector3("Simulation", "gravity", value)
        self._level.set_gravity(g)
        self._gravity = g

    @property
    def dimension(self) -> int:
        """3 (spheres) or 2 (discs in the plane z = plane_z)."""
        return int(self._level.dimension)

    @property
    def comm(self) -> Any:
        """The mpi4py communicator of a parallel run, None for a serial one."""
        return self._comm

    @property
    def rank(self) -> int:
        """This process's rank in the simulation's communicator (0 when serial)."""
        return int(self._level.rank)

    @property
    def ranks(self) -> int:
        """Number of ranks the simulation is decomposed over (1 when serial)."""
        return int(self._level.ranks)

    @property
    def plane_z(self) -> float:
        """z of the particles' plane in 2-D mode (the domain's mid-height, m)."""
        return float(self._level.plane_z)

    @property
    def time_step(self) -> float | None:
        """Time step (s); None until resolved at the first run."""
        return self._time_step

    @time_step.setter
    def time_step(self, value: float) -> None:
        parallel.same_arguments(self._comm, "Simulation.time_step", value=value)
        dt = positive("Simulation", "time_step", value, " (s)")
        self._level.set_time_step(dt, self._force_time_step)
        self._time_step = dt

    @property
    def skin(self) -> float:
        """Verlet skin (m); changing it rebuilds the lists (contact histories are kept)."""
        return float(self._level.skin)

    @skin.setter
    def skin(self, value: float) -> None:
        parallel.same_arguments(self._comm, "Simulation.skin", value=value)
        self._level.set_skin(positive("Simulation", "skin", value, " (m)"))
        self._skin_fixed = True

    def material_index(self, material: Material) -> int:
        """Index of ``material`` in this simulation (registered on first use)."""
        if not isinstance(material, Material):
            raise ValueError(f"material must be a grainscale.Material, got {material!r}")
        for k, m in enumerate(self._materials):
            if m == material:
                return k
        k = self._level.add_material(
            material.density, material.youngs_modulus, material.poisson_ratio
        )
        self._materials.append(material)
        return int(k)

    def particle_material_index(self, material: Material, owner: str) -> int:
        """``material_index`` for particles: a rigid wall material is refused (``owner`` names
        the caller in the message)."""
        if isinstance(material, Material) and material.rigid:
            raise ValueError(
                f"{owner}.material must be deformable (finite youngs_modulus), got the rigid "
                f"wall material {material.name!r}"
            )
        return self.material_index(material)

    @property
    def materials(self) -> list[Material]:
        """Registered materials, by index."""
        return list(self._materials)

    def add_particles(
        self,
        position: np.ndarray | Sequence[Sequence[float]],
        radius: float | np.ndarray,
        material: Material,
        velocity: np.ndarray | Sequence[float] | None = None,
        angular_velocity: np.ndarray | Sequence[float] | None = None,
        check_placement: bool = True,
    ) -> np.ndarray:
        """Add spheres (discs in 2-D); returns their global ids (int64, never reused).

        Args:
            position: (N, 3) centres, m. Must lie inside the domain on closed axes; in 2-D, z
                must equal ``plane_z`` (v_z, w_x and w_y given are set to zero).
            radius: scalar or (N,) radii, m.
            material: their material.
            velocity: (N, 3) or (3,) m/s, default zero.
            angular_velocity: (N, 3) or (3,) rad/s, default zero.
            check_placement: refuse particles larger than the box, with coordinates float64
                cannot resolve, overlapping a wall by more than 10 % of their radius (or
                behind a plane, rectangle or cylinder), or overlapping each other or the
                particles present by more than 10 % of the smaller radius (grainscale.placement;
                collective under MPI); False accepts them.
        """
        self.engine.check_unseen_writes()
        owner = "Simulation.add_particles"
        parallel.same_arguments(
            self._comm,
            owner,
            position=position,
            radius=radius,
            material=material,
            velocity=velocity,
            angular_velocity=angular_velocity,
            check_placement=check_placement,
        )
        pos = real_array(owner, "position", position, (None, 3), (3,)).reshape(-1, 3)
        n = pos.shape[0]
        rad = real_array(owner, "radius", radius, (), (n,))
        rad = np.ascontiguousarray(np.broadcast_to(rad, (n,)))
        if np.any(rad <= 0):
            i = int(np.argmax(rad <= 0))
            raise ValueError(f"{owner}.radius must be positive (m), got {rad[i]} at index {i}")
        check_masses(owner, rad, material, self.dimension)
        if check_placement:
            check_new_particles(self, owner, pos, rad)
        mat = np.full(n, self.particle_material_index(material, owner), dtype=np.int32)

        def rows(a: Any, name: str) -> np.ndarray | None:
            if a is None:
                return None
            arr = real_array(owner, name, a, (3,), (n, 3))
            return np.ascontiguousarray(np.broadcast_to(arr, (n, 3)))

        first = self._level.add_particles(
            pos, rows(velocity, "velocity"), rows(angular_velocity, "angular_velocity"), rad, mat
        )
        return np.arange(first, first + n, dtype=np.int64)

    # ----------------------------------------------------------------- insertion and outlets
    def insert(self, operation: Pack | Stream) -> Any:
        """Insert particles (see grainscale.insert).

        ``Pack``: places the particles now and returns their global ids (int64 array, largest
        particle first); raises RuntimeError, inserting nothing, if the target is out of reach.
        ``Stream``: registers the stream, which inserts inside run(), and returns its
        :class:`~grainscale.insert.StreamHandle` (requested / inserted / pending mass, counts).
        """
        self.engine.check_unseen_writes()
        parallel.same_arguments(self._comm, "Simulation.insert", operation=operation)
        if isinstance(operation, Pack):
            return operation._insert(self)
        if isinstance(operation, Stream):
            handle = operation._insert(self)
            self._streams.append(handle)
            return handle
        raise ValueError(
            f"Simulation.insert needs a grainscale.insert.Pack or Stream, got {operation!r}"
        )

    def add_outlet(self, outlet: Outlet) -> OutletHandle:
        """Register an outlet (particles inside its region are deleted during run()); returns
        its :class:`~grainscale.insert.OutletHandle` (removed count, mass and history)."""
        parallel.same_arguments(self._comm, "Simulation.add_outlet", outlet=outlet)
        if not isinstance(outlet, Outlet):
            raise ValueError(
                f"Simulation.add_outlet needs a grainscale.insert.Outlet, got {outlet!r}"
            )
        handle = outlet._add(self)
        self._outlets.append(handle)
        return handle

    @property
    def streams(self) -> list[StreamHandle]:
        """Registered streams, in registration order."""
        return list(self._streams)

    @property
    def outlets(self) -> list[OutletHandle]:
        """Registered outlets, in registration order."""
        return list(self._outlets)

    def remove_particles(self, ids: np.ndarray | Sequence[int]) -> int:
        """Delete the particles with these global ids (contact histories of the others are kept);
        ids not present are ignored. Returns the number deleted."""
        self.engine.check_unseen_writes()
        parallel.same_arguments(self._comm, "Simulation.remove_particles", ids=ids)
        a = id_array("Simulation.remove_particles", "ids", ids)
        return int(self._level.remove_particles(a.tolist()))

    # ----------------------------------------------------------------- state
    @property
    def step(self) -> int:
        return int(self._level.step)

    @property
    def time(self) -> float:
        """Simulated time (s)."""
        return float(self._level.time)

    @property
    def num_particles(self) -> int:
        """Particles over all ranks (collective)."""
        return int(self._level.global_count())

    @property
    def num_local_particles(self) -> int:
        """Particles owned by this rank (those ``particles()`` shows)."""
        return int(self._level.num_owned)

    @property
    def lost_particles(self) -> int:
        """Particles removed because they left the domain through a closed axis (collective)."""
        return int(self._level.lost_particles)

    @contextmanager
    def particles(self, writable: bool = True) -> Iterator[ParticleView]:
        """Zero-copy access to the particle arrays, valid only inside the block.

        Under MPI the arrays hold this rank's particles only (see ``gather`` for all of them).
        Changes to position, velocity or angular_velocity are detected on exit: the core then
        rebuilds its lists / re-evaluates forces before the next step.
        """
        self.engine.check_unseen_writes()
        view = ParticleView(self._level, writable)
        before = None
        if writable:
            before = {f: self._level.view(f).copy() for f in WRITABLE_FIELDS}
        try:
            yield view
        finally:
            view._close()
            if before is not None and self.num_local_particles == len(before["position"]):
                if not np.array_equal(before["position"], self._level.view("position")):
                    self._level.mark_positions_changed()
                elif not (
                    np.array_equal(before["velocity"], self._level.view("velocity"))
                    and np.array_equal(
                        before["angular_velocity"], self._level.view("angular_velocity")
                    )
                ):
                    self._level.mark_velocities_changed()
            if writable:
                self.engine.arm_write_watch()

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy (J)."""
        return float(self._level.kinetic_energy())

    def num_contacts(self) -> int:
        """Touching contacts (particle-particle and particle-wall) at the last step."""
        return int(self._level.last_contact_count())

    @property
    def record_contacts(self) -> bool:
        """Whether ``contacts()`` is available (see the constructor argument)."""
        return bool(self._level.record_contacts)

    @record_contacts.setter
    def record_contacts(self, on: bool) -> None:
        self._level.record_contacts = flag("Simulation", "record_contacts", on)

    def contacts(self) -> dict[str, np.ndarray]:
        """Touching contacts at the last step: id_i, id_j (-1 - wall index for walls),
        overlap (m), normal (unit, from j to i), force (N, on i). Under MPI: the contacts this
        rank computed (each contact is computed on one rank).

        Needs ``record_contacts=True`` before the run whose last step is reported.
        """
        if not self.record_contacts:
            raise RuntimeError(
                "Simulation.contacts() needs record_contacts=True (set it before run())"
            )
        return dict(self._level.contacts())

    def neighbor_pairs(self) -> np.ndarray:
        """(M, 2) global ids of the pairs in this rank's current Verlet list, each pair once."""
        self.engine.check_unseen_writes()
        return np.asarray(self._level.neighbor_pairs())

    def _push_interactions(self) -> None:
        """Resolve the interaction properties of every material pair (mixing rules)."""
        if self._interactions_for == len(self._materials):
            return
        bodies: list[tuple[int, Material | None]] = [(-1, None)]
        bodies += list(enumerate(self._materials))
        for a, (i, mi) in enumerate(bodies):
            for j, mj in bodies[a:]:
                if i == -1 and j == -1:
                    continue
                self.contact._apply_pair(self._level, _core, i, j, self.contact.interaction(mi, mj))
        self._interactions_for = len(self._materials)

    def _resolve_defaults(self) -> None:
        self._push_interactions()
        # Streams count as particles to come: their largest diameter for the skin, their
        # smallest particle's Rayleigh time for the time step.
        d_stream = max((2.0 * h.max_radius for h in self._streams), default=0.0)
        n_particles = self.num_particles
        if not self._skin_fixed and (n_particles > 0 or d_stream > 0):
            d_max = d_stream
            if n_particles > 0:
                with self.particles(writable=False) as p:
                    d_local = 2.0 * float(p.radius.max()) if len(p) else 0.0
                if self._comm is not None:
                    from ._optional import mpi

                    MPI = mpi()
                    with parallel.waiting("Simulation.run (largest particle diameter)"):
                        d_local = self._comm.allreduce(d_local, op=MPI.MAX)
                d_max = max(d_max, d_local)
            self._level.set_skin(0.1 * d_max)
            self._skin_fixed = True
        elif not self._skin_fixed:
            self._level.set_skin(1e-3 * float(np.min(self.domain.length)))
        if self._time_step is None:
            if n_particles == 0 and not self._streams:
                raise ValueError(
                    "Simulation.time_step must be given when there are no particles, got None"
                )
            self.time_step = 0.2 * min(
                float(self._level.smallest_rayleigh_time()),
                float(self._level.smallest_insertion_rayleigh_time()),
            )

    def run(
        self, steps: int | None = None, until: float | None = None, progress: bool | None = None
    ) -> None:
        """Advance the simulation by ``steps`` steps or up to simulated time ``until`` (s).

        Args:
            steps: number of steps.
            until: absolute simulated time to reach (s).
            progress: show a progress bar (default: only on an interactive terminal, not in CI).
        """
        if (steps is None) == (until is None):
            raise ValueError(
                f"Simulation.run needs exactly one of steps or until, got steps={steps!r}, "
                f"until={until!r}"
            )
        parallel.same_arguments(self._comm, "Simulation.run", steps=steps, until=until)
        check_run_arguments(steps, until, progress)
        self.engine.check_unseen_writes()
        self._resolve_defaults()
        dt = float(self._time_step)  # type: ignore[arg-type]
        target = self._target_step(steps, until, dt)
        self._note_rayleigh_time()
        if progress is None:
            progress = sys.stderr.isatty() and not os.environ.get("CI")
        progress = progress and self.rank == 0
        bar = None
        if progress and target > self.step:
            from tqdm.auto import tqdm

            bar = tqdm(total=target - self.step, unit="step", leave=False)
        self._rate_clock = (_time.perf_counter(), self.step)
        with self._logged_run(target):
            self._run_to(target, dt, bar)

    def _run_to(self, target: int, dt: float, bar: Any) -> None:
        """The run loop: chunks of steps in C++, outputs and thermo lines between them."""
        self._python_step(lambda: self._start_outputs(dt))
        try:
            while self.step < target:
                stop = target
                for _, due in self._outputs:
                    stop = min(stop, due)
                if self.thermo_every:
                    stop = min(stop, (self.step // self.thermo_every + 1) * self.thermo_every)
                n = min(stop - self.step, self._chunk)
                # Contact statistics slow the step that gathers them (and are summed over the
                # ranks): only where they are read (the end of the run, a thermo line, an output).
                stats = n == stop - self.step
                t0 = _time.perf_counter()
                self._run_chunk(n, stats)
                self._chunk = next_chunk(self._chunk, n, _time.perf_counter() - t0, self._comm)
                if bar is not None:
                    bar.update(n)
                # Outputs, then thermo (its reductions are collective): each step agreed on.
                self._python_step(lambda: self._write_due_outputs(dt))
                if self.thermo_every and self.step % self.thermo_every == 0:
                    self._python_step(lambda: self._log_thermo(print_line=not self.quiet, bar=bar))
        finally:
            if bar is not None:
                bar.close()
        if not self.thermo_log or self.thermo_log[-1]["step"] != self.step:
            self._log_thermo(print_line=False, log_line=False)

    def _target_step(self, steps: int | None, until: float | None, dt: float) -> int:
        """The step a run of ``steps`` steps or up to time ``until`` ends at (arguments checked
        by check_run_arguments); refused beyond MAX_STEP, where the run would never end."""
        return target_step(self.step, self.time, steps, until, dt)

    def _python_step(self, work: Any) -> None:
        """Runs one Python part between chunks; an error on one rank is raised on all (a part
        must not start a collective call after something that can fail on one rank only)."""
        error: BaseException | None = None
        try:
            work()
        except Exception as err:
            error = err
        parallel.agree(self._comm, error)
