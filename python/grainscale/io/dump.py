"""Particle dumps in HDF5 for post-processing with numpy and h5py, and their reader.

:class:`Dump` is an output operation of ``Simulation.output()`` that writes one HDF5 file per
snapshot, ``<directory>/<prefix>_<step:08d>.h5``; :func:`read_dump` reads one snapshot (a file)
or the whole series (a directory) back as arrays sorted by particle id.

One file per snapshot, not one growing file: each is written to a temporary file and renamed,
so a run that is killed leaves every finished snapshot readable (an HDF5 file open for appending
can be left unreadable by a crash); a restarted run simply writes the next files (rewriting a
snapshot at the same step replaces it whole); snapshots can be copied or deleted one by one, and
a reader can open the finished ones while the run goes on.

File layout (grainscale.io.h5snapshot): attributes ``format`` = ``"grainscale-dump"``,
``version``, ``step``, ``time`` (s), ``time_step`` (s), ``dimension``, ``ranks``,
``materials`` (JSON list of the materials by index: name, density kg/m^3, youngs_modulus Pa,
poisson_ratio); datasets (first axis: the particles, in the order of ``sim.particles()``)
``position`` (N, 3) m, ``velocity`` (N, 3) m/s, ``angular_velocity`` (N, 3) rad/s, ``radius``
(N,) m, ``id`` (N,) int64, ``material`` (N,) int32 index, plus the chosen fields and user
arrays. Under MPI every rank writes its particles to ``<prefix>_<step:08d>_r<rank>.h5`` and
rank 0 the index ``<prefix>_<step:08d>.h5`` (with HDF5 external links ``rank_<r>`` to the
pieces); :func:`read_dump` joins them.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .h5snapshot import read_snapshot, snapshot_files, write_snapshot
from .particle_fields import Extra, check_extra, choose_fields, extra_arrays, field_arrays
from .paths import output_directory
from .schedule import Schedule
from .vtk_output import check_prefix

FORMAT = "grainscale-dump"

#: the particle fields a dump holds by default
DEFAULT_FIELDS = ("position", "velocity", "angular_velocity", "radius", "id", "material")


@dataclasses.dataclass
class DumpSnapshot:
    """One snapshot read back: its step, time (s) and arrays (sorted by particle id).

    ``snapshot["position"]`` is ``snapshot.arrays["position"]``; ``attrs`` holds the file's
    other attributes (``time_step``, ``dimension``, ``ranks``, ``materials``).
    """

    step: int
    time: float
    arrays: dict[str, np.ndarray]
    attrs: dict[str, Any]
    path: Path

    def __getitem__(self, name: str) -> np.ndarray:
        return self.arrays[name]

    def __contains__(self, name: object) -> bool:
        return name in self.arrays

    def __iter__(self) -> Iterator[str]:
        return iter(self.arrays)

    def keys(self) -> Any:
        return self.arrays.keys()

    def __len__(self) -> int:
        return len(self.arrays["id"])


class Dump:
    """Particle dumps in HDF5: ``<directory>/<prefix>_<step:08d>.h5``, one file per snapshot.

    Register with ``sim.output(gs.io.Dump("out/dumps", every=0.01))``; read back with
    :func:`read_dump`. See the module docstring for the file layout and why one file per
    snapshot.

    Args:
        directory: where the files go (created when needed).
        every, every_steps: the schedule, exactly one of a simulated-time interval (s) or a
            step interval, as for :class:`~grainscale.io.VTK` (the first scheduled call writes
            at once).
        prefix: file name prefix.
        fields: the particle fields to write, among ``position``, ``velocity``,
            ``angular_velocity``, ``force``, ``torque``, ``radius``, ``mass``, ``id``,
            ``material`` (None: position, velocity, angular_velocity, radius, id, material);
            ``id`` is always written.
        extra: user arrays, name -> callable receiving the open read-only particle view and
            returning one value or row per particle (grainscale.io.particle_fields).

    Example (files in a temporary directory):
        >>> import tempfile, grainscale as gs
        >>> out = tempfile.mkdtemp()
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), quiet=True)
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> _ = sim.add_particles(position=[[0.005, 0.005, 0.005]], radius=1e-3, material=glass)
        >>> sim.output(gs.io.Dump(out, every_steps=10))
        >>> sim.run(steps=20, progress=False)
        >>> snaps = gs.io.read_dump(out)
        >>> [s.step for s in snaps], snaps[-1]["position"].shape
        ([0, 10, 20], (1, 3))
        >>> bool(snaps[-1]["velocity"][0, 2] < 0)   # falling
        True
    """

    def __init__(
        self,
        directory: str | os.PathLike[str],
        every: float | None = None,
        every_steps: int | None = None,
        prefix: str = "dump",
        fields: Sequence[str] | None = None,
        extra: Mapping[str, Extra] | None = None,
    ) -> None:
        self._schedule = Schedule("Dump", every, every_steps)
        check_prefix("Dump", prefix)
        chosen = choose_fields("Dump", fields, DEFAULT_FIELDS)
        self.fields = chosen if "id" in chosen else [*chosen, "id"]
        self.extra = check_extra("Dump", extra, self.fields)
        self.directory = output_directory("Dump.directory", directory)
        self.prefix = prefix
        self.files: list[Path] = []  # snapshot files written (the index files under MPI)

    def __repr__(self) -> str:
        return f"Dump({str(self.directory)!r}, {self._schedule.describe()}, prefix={self.prefix!r})"

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step >= ``step`` at which to write (the output protocol, as VTK's)."""
        return self._schedule.next_step(step, time, time_step)

    def write(self, sim: Any) -> Path:
        """Write the snapshot of ``sim`` now; returns the snapshot file (the index under MPI)."""
        step, time = int(sim.step), float(sim.time)
        with sim.particles(writable=False) as p:
            arrays = {k: np.array(v) for k, v in field_arrays("Dump", p, self.fields).items()}
            arrays.update(extra_arrays("Dump", p, self.extra, len(arrays["id"])))
        attrs = {
            "step": step,
            "time": time,
            "time_step": float(sim.time_step or 0.0),
            "dimension": int(getattr(sim, "dimension", 3)),
            "materials": [dataclasses.asdict(m) for m in getattr(sim, "materials", [])],
        }
        path = write_snapshot(
            self.directory,
            f"{self.prefix}_{step:08d}",
            FORMAT,
            arrays,
            attrs,
            int(getattr(sim, "rank", 0)),
            int(getattr(sim, "ranks", 1)),
        )
        self.files.append(path)
        self._schedule.done(step, time, sim.time_step)
        return path


def _read_one(path: Path) -> DumpSnapshot:
    arrays, attrs = read_snapshot(path, FORMAT)
    if "id" in arrays:
        order = np.argsort(arrays["id"], kind="stable")
        arrays = {k: v[order] for k, v in arrays.items()}
    step, time = int(attrs.pop("step")), float(attrs.pop("time"))
    for key in ("format", "version"):
        attrs.pop(key, None)
    return DumpSnapshot(step, time, arrays, attrs, path)


def read_dump(
    path: str | os.PathLike[str], prefix: str = "dump"
) -> DumpSnapshot | list[DumpSnapshot]:
    """Read particle dumps written by :class:`Dump`.

    Args:
        path: a snapshot file (``<prefix>_<step>.h5``; under MPI the index, whose per-rank
            pieces are read with it) -> one :class:`DumpSnapshot`; or a directory -> the list
            of its snapshots ``<prefix>_*.h5`` in step order.
        prefix: the snapshots' file prefix when ``path`` is a directory.

    Every snapshot's arrays are sorted by particle id (as ``Simulation.gather`` returns them),
    whatever the number of ranks that wrote it.

    Raises:
        ValueError: naming the file: not a dump, or a piece missing; a directory without dumps.
    """
    where = Path(path)
    if where.is_dir():
        files = snapshot_files(where, prefix)
        if not files:
            raise ValueError(f"read_dump: no dump files {prefix}_<step>.h5 in {os.fspath(where)!r}")
        return [_read_one(f) for f in files]
    if not where.is_file():
        raise ValueError(
            f"read_dump.path must be a dump file or directory, got {os.fspath(path)!r}"
        )
    return _read_one(where)
