"""The VTK output operation of ``Simulation.output()``: particle snapshots for ParaView (with a
choice of per-particle fields and user arrays), the walls, and the .pvd series that a restarted
run continues. The file writers are in :mod:`grainscale.io.vtk`."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .._validate import flag
from .particle_fields import Extra, check_extra, choose_fields, extra_arrays, field_arrays
from .paths import make_directory, output_directory
from .schedule import Schedule
from .vtk import PathLike, PVDSeries, write_pvtp, write_vtp, write_vtp_mesh
from .wall_surfaces import wall_surfaces

#: the per-particle arrays a snapshot holds by default (torque when the particles have it)
DEFAULT_FIELDS = (
    "radius",
    "velocity",
    "angular_velocity",
    "force",
    "torque",
    "id",
    "material",
    "mass",
)


class VTK:
    """Particle snapshots for ParaView: ``<directory>/<prefix>_<step:08d>.vtp`` + ``<prefix>.pvd``.

    Register with ``sim.output(gs.io.VTK("out/", every=0.01))``. Each snapshot holds, per
    particle: position (points, m) and by default ``radius`` (m), ``velocity`` (m/s),
    ``angular_velocity`` (rad/s), ``force`` (N, with gravity), ``torque`` (N m, when available),
    ``id`` (int64), ``material`` (int32) and ``mass`` (kg). In ParaView open the .pvd and apply
    Glyph (Sphere, scale by ``radius``, scale factor 2) to see the grains.

    Args:
        directory: where the files go (created when needed).
        every, every_steps: the schedule, exactly one of: a simulated-time interval (s;
            snapshots at the first step whose time reaches each multiple of ``every``) or a
            step interval (the steps that are multiples of ``every_steps``). The first
            scheduled call writes at once (the step when the writer is attached).
        prefix: file name prefix.
        binary, appended: encoding (grainscale.io.vtk: base64 inline, raw appended, or ASCII).
        level: the level of a :class:`~grainscale.Hierarchy` the simulation is (written as an
            int32 ``level`` array, to colour the levels in ParaView).
        fields: the particle fields to write, in order, among ``position``, ``velocity``,
            ``angular_velocity``, ``force``, ``torque``, ``radius``, ``mass``, ``id``,
            ``material`` (None: the default list above). The positions are always the points.
        extra: user arrays, name -> callable receiving the open read-only particle view of this
            rank's particles and returning one value or row per particle in its order
            (grainscale.io.particle_fields), e.g. ``{"speed": lambda p:
            np.linalg.norm(p.velocity, axis=1)}``. Evaluated at every snapshot.
        resume: continue the ``.pvd`` series found in ``directory`` (keep its entries before
            this writer's first snapshot, see :meth:`grainscale.io.PVDSeries.resume`): a run
            restarted from a checkpoint into the same directory extends the series. False
            starts a new one.

    Example (files in a temporary directory):
        >>> import tempfile, numpy as np, grainscale as gs
        >>> out = tempfile.mkdtemp()
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), quiet=True)
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> _ = sim.add_particles(position=[[0.005, 0.005, 0.005]], radius=1e-3, material=glass)
        >>> vtk = gs.io.VTK(out, every_steps=5, fields=["radius", "id"],
        ...                 extra={"speed": lambda p: np.linalg.norm(p.velocity, axis=1)})
        >>> sim.output(vtk)
        >>> sim.run(steps=10, progress=False)
        >>> [f.name for f in vtk.files]
        ['particles_00000000.vtp', 'particles_00000005.vtp', 'particles_00000010.vtp']

    Under MPI every rank writes its particles as ``<prefix>_<step:08d>_r<rank>.vtp`` (with a
    ``rank`` array) and rank 0 writes the parallel index ``<prefix>_<step:08d>.pvtp``, which
    the .pvd lists. Rank 0 writes the walls, every type where it is at the snapshot (planes
    clipped to the domain, rectangles, cylinders, meshes; grainscale.io.wall_surfaces), as
    ``<prefix>_walls_<step:08d>.vtp`` with a cell array ``wall`` (the wall's index), listed in
    ``<prefix>_walls.pvd``; once if no wall moves, else at every snapshot.

    Protocol used by the Simulation: ``next_step(step, time, time_step)`` returns the next step
    at which to call ``write(sim)``; call it again after each write and whenever the time step
    changes (it depends only on its arguments and on the last write).
    """

    def __init__(
        self,
        directory: PathLike,
        every: float | None = None,
        every_steps: int | None = None,
        prefix: str = "particles",
        binary: bool = True,
        appended: bool = False,
        level: int | None = None,
        fields: Sequence[str] | None = None,
        extra: Mapping[str, Extra] | None = None,
        resume: bool = True,
    ) -> None:
        if level is not None and (isinstance(level, bool) or not isinstance(level, int)):
            raise ValueError(f"VTK.level must be an integer or None, got {level!r}")
        self.level = level
        self._schedule = Schedule("VTK", every, every_steps)
        check_prefix("VTK", prefix)
        binary, appended = flag("VTK", "binary", binary), flag("VTK", "appended", appended)
        resume = flag("VTK", "resume", resume)
        if appended and not binary:
            raise ValueError("VTK.appended=True requires binary=True, got binary=False")
        self.fields = choose_fields("VTK", fields, DEFAULT_FIELDS)
        self._optional = ("torque",) if fields is None else ()
        reserved = ["rank", "level", *self.fields]
        self.extra = check_extra("VTK", extra, reserved)
        self.directory = output_directory("VTK.directory", directory)
        self.prefix = prefix
        self.binary = bool(binary)
        self.appended = bool(appended)
        self.resume = bool(resume)
        self.files: list[Path] = []  # snapshot files written, in order
        self.pvd = PVDSeries(self.directory / f"{prefix}.pvd")
        self.walls_pvd: PVDSeries | None = None
        self._walls_written = False
        self._pvd_started = False

    @property
    def every(self) -> float | None:
        """Simulated-time interval, s (None with ``every_steps``)."""
        return self._schedule.every

    @property
    def every_steps(self) -> int | None:
        """Step interval (None with ``every``)."""
        return self._schedule.every_steps

    def __repr__(self) -> str:
        sched = self._schedule.describe()
        return f"VTK({str(self.directory)!r}, {sched}, prefix={self.prefix!r})"

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step >= ``step`` at which to write.

        Args:
            step: current step number.
            time: simulated time at ``step``, s.
            time_step: integration time step, s (assumed constant until the returned step).
        """
        return self._schedule.next_step(step, time, time_step)

    def _write_walls(self, sim: Any, step: int, time: float) -> None:
        """Every wall (planes clipped to the domain, rectangles, cylinders, meshes): one .vtp
        per snapshot (cell data ``wall``, the wall's index) in ``<prefix>_walls.pvd``; written
        once when no wall moves."""
        if not getattr(sim, "walls", None) or getattr(sim, "rank", 0) != 0:
            return
        surfaces = wall_surfaces(sim)
        if not surfaces.moving and self._walls_written:
            return
        if len(surfaces.triangles) == 0:
            return
        name = f"{self.prefix}_walls_{step:08d}.vtp"
        write_vtp_mesh(
            self.directory / name,
            surfaces.vertices,
            surfaces.triangles,
            cell_data={"wall": surfaces.wall},
            binary=self.binary,
            appended=self.appended,
        )
        if self.walls_pvd is None:
            self.walls_pvd = PVDSeries(self.directory / f"{self.prefix}_walls.pvd")
            if self.resume:
                self.walls_pvd.resume(time)
        self.walls_pvd.add(time, name)
        self._walls_written = True

    def write(self, sim: Any) -> Path:
        """Write the snapshot of ``sim`` at its current step and add it to the .pvd index.

        ``sim`` must provide ``step``, ``time`` (s) and the ``particles()`` context manager.
        Returns the path of the .vtp file (the .pvtp index under MPI).
        """
        step = int(sim.step)
        time = float(sim.time)
        make_directory("VTK.directory", self.directory)
        rank, ranks = int(getattr(sim, "rank", 0)), int(getattr(sim, "ranks", 1))
        name = f"{self.prefix}_{step:08d}.vtp"
        if ranks > 1:
            name = f"{self.prefix}_{step:08d}_r{rank}.vtp"
        path = self.directory / name
        with sim.particles(writable=False) as p:
            n = len(p.position)
            point_data = field_arrays("VTK", p, self.fields, self._optional)
            if ranks > 1:
                point_data["rank"] = np.full(n, rank, dtype=np.int32)
            if self.level is not None:
                point_data["level"] = np.full(n, self.level, dtype=np.int32)
            point_data.update(extra_arrays("VTK", p, self.extra, n))
            write_vtp(path, p.position, point_data, binary=self.binary, appended=self.appended)
            if ranks > 1 and rank == 0:
                index = f"{self.prefix}_{step:08d}.pvtp"
                pieces = [f"{self.prefix}_{step:08d}_r{r}.vtp" for r in range(ranks)]
                write_pvtp(self.directory / index, pieces, point_data)
                name, path = index, self.directory / index
        if rank == 0:
            if not self._pvd_started and self.resume:
                self.pvd.resume(time)  # the series of the run this one continues
            self._pvd_started = True
            self.pvd.add(time, name)
        if not self.files or self.files[-1] != path:
            self.files.append(path)
        self._write_walls(sim, step, time)
        dt = self._schedule.time_step
        if dt is None:
            dt = getattr(sim, "time_step", 0)
        self._schedule.done(step, time, dt)
        return path


def check_prefix(owner: str, prefix: object) -> None:
    """A file name prefix: a non-empty string without path separators."""
    if not isinstance(prefix, str) or not prefix or "/" in prefix or os.sep in prefix:
        raise ValueError(
            f"{owner}.prefix must be a non-empty file name without path separators, got {prefix!r}"
        )
