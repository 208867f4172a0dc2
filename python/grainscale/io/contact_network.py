"""The contact and force network at each output step: VTK lines for ParaView and an HDF5
table for numpy/h5py.

:class:`ContactNetwork` is an output operation of ``Simulation.output()``. It turns on
``record_contacts`` when registered and, at each snapshot, writes every touching contact of
the last step (the contacts ``sim.contacts()`` reports) as

* ``<prefix>_<step:08d>.vtp``: one line per contact between the two centres (for a wall
  contact, from the centre to the touching point on the wall), listed in ``<prefix>.pvd``;
* ``<prefix>_<step:08d>.h5``: the same contacts as a table (one row per contact), read back
  with :func:`read_contacts`.

Conventions (as ``Simulation.contacts()``): particle i is the one this rank owns, j its
partner (``id_j = -1 - wall index`` for a wall); the normal is the unit vector from j to i; the
force is the force on i (j receives its opposite). Columns / cell arrays:

========================  ==========  =============================================
``id_i``, ``id_j``        int64       global ids (``id_j < 0``: wall ``-1 - id_j``)
``wall``                  int32       wall index, -1 for a particle pair
``overlap``               m           r_i + r_j - |x_i - x_j| (wall: r_i - distance)
``normal``                (3,)        unit, from j to i
``force``                 (3,) N      on i
``normal_force``          N           force . normal (positive: pushing apart)
``force_normal``          (3,) N      (force . normal) normal
``force_tangential``      (3,) N      force - force_normal
``point``                 (3,) m      contact point x_i - (r_i - overlap / 2) normal
``position_i``            (3,) m      centre of i
``position_j``            (3,) m      centre of j as i touches it (its periodic image
                                      across a periodic side), or the touching point on
                                      the wall
========================  ==========  =============================================

The table has the attributes ``step``, ``time`` (s) and ``contacts`` (the number of rows).
Under MPI every rank writes the contacts it computed (each contact once, on one rank) as
``<prefix>_<step:08d>_r<rank>.vtp`` / ``.h5`` pieces; rank 0 writes the ``.pvtp`` index that
the .pvd lists and the ``.h5`` index that :func:`read_contacts` joins.

A snapshot is written only at a step whose contacts were recorded: at the step where the
output is attached after a restart (or after a run made without ``record_contacts``) the last
step's contacts are unknown, and that snapshot is skipped (the run that wrote the checkpoint
wrote it).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from .. import parallel
from .._validate import flag
from .h5snapshot import read_snapshot, snapshot_files, write_snapshot
from .paths import make_directory, output_directory
from .schedule import Schedule
from .vtk import PVDSeries, write_pvtp, write_vtp_lines
from .vtk_output import check_prefix

FORMAT = "grainscale-contacts"


def _lookup(ids: np.ndarray, order: np.ndarray, wanted: np.ndarray) -> tuple[np.ndarray, ...]:
    """Index into ``ids`` of every ``wanted`` id (``order`` sorts ``ids``), and which exist."""
    if len(ids) == 0:
        return np.zeros(len(wanted), dtype=np.int64), np.zeros(len(wanted), dtype=bool)
    pos = np.minimum(np.searchsorted(ids, wanted, sorter=order), len(ids) - 1)
    index = order[pos]
    return index, ids[index] == wanted


def _partner_radii(sim: Any, wanted: np.ndarray, ids: np.ndarray, radius: np.ndarray) -> Any:
    """Radii of the particles ``wanted`` (ids); those another rank owns are asked for
    (collective under MPI)."""
    order = np.argsort(ids, kind="stable")
    index, found = _lookup(ids, order, wanted)
    out = np.where(found, radius[index] if len(ids) else 0.0, np.nan)
    comm = getattr(sim, "comm", None)
    if comm is None:
        if not found.all():
            raise RuntimeError(f"ContactNetwork: partner {wanted[~found][0]} not found")
        return out
    with parallel.waiting("ContactNetwork (partners' radii)"):
        asked = np.unique(np.concatenate(comm.allgather(np.unique(wanted[~found]))))
        mine_index, mine = _lookup(ids, order, asked)
        answers = comm.allgather((asked[mine], radius[mine_index[mine]]))
    known_ids = np.concatenate([a for a, _ in answers]).astype(np.int64)
    known_r = np.concatenate([r for _, r in answers]).astype(np.float64)
    k_order = np.argsort(known_ids, kind="stable")
    k_index, k_found = _lookup(known_ids, k_order, wanted[~found])
    if not k_found.all():
        raise RuntimeError(f"ContactNetwork: partner {wanted[~found][~k_found][0]} not found")
    out[~found] = known_r[k_index]
    return out


def network(sim: Any, walls: bool = True) -> dict[str, np.ndarray]:
    """The contact table (module docstring) of this rank's recorded contacts; collective under
    MPI. ``walls``: include the particle-wall contacts."""
    c = sim.contacts()
    keep = np.ones(len(c["id_i"]), dtype=bool) if walls else c["id_j"] >= 0
    id_i = np.asarray(c["id_i"], dtype=np.int64)[keep]
    id_j = np.asarray(c["id_j"], dtype=np.int64)[keep]
    overlap = np.asarray(c["overlap"], dtype=np.float64)[keep]
    normal = np.asarray(c["normal"], dtype=np.float64).reshape(-1, 3)[keep]
    force = np.asarray(c["force"], dtype=np.float64).reshape(-1, 3)[keep]
    with sim.particles(writable=False) as p:
        ids, pos, rad = np.array(p.id), np.array(p.position), np.array(p.radius)
    order = np.argsort(ids, kind="stable")
    index, found = _lookup(ids, order, id_i)
    if not found.all():
        raise RuntimeError(f"ContactNetwork: particle {id_i[~found][0]} is not on this rank")
    x_i, r_i = pos[index], rad[index]
    pair = id_j >= 0
    r_j = np.zeros(len(id_j))
    r_j[pair] = _partner_radii(sim, id_j[pair], ids, rad)
    reach = np.where(pair, r_i + r_j - overlap, r_i - overlap)  # from x_i along -normal
    normal_force = np.einsum("ij,ij->i", force, normal)
    force_normal = normal_force[:, None] * normal
    return {
        "id_i": id_i,
        "id_j": id_j,
        "wall": np.where(pair, -1, -1 - id_j).astype(np.int32),
        "overlap": overlap,
        "normal": normal,
        "force": force,
        "normal_force": normal_force,
        "force_normal": force_normal,
        "force_tangential": force - force_normal,
        "point": x_i - (r_i - 0.5 * overlap)[:, None] * normal,
        "position_i": x_i,
        "position_j": x_i - reach[:, None] * normal,
    }


class ContactNetwork:
    """Contact and force network snapshots: VTK lines and an HDF5 table (module docstring).

    Register with ``sim.output(gs.io.ContactNetwork("out/contacts", every=0.01))``; this turns
    on ``sim.record_contacts``.

    Args:
        directory: where the files go (created when needed).
        every, every_steps: the schedule, exactly one of a simulated-time interval (s) or a
            step interval, as for :class:`~grainscale.io.VTK`.
        prefix: file name prefix.
        vtk: write the ``.vtp`` lines (and the ``.pvd`` series).
        table: write the ``.h5`` table.
        walls: include the particle-wall contacts (False: particle pairs only).
        binary, appended: the VTK encoding (grainscale.io.vtk).
        resume: continue the ``.pvd`` series found in ``directory`` (as VTK's ``resume``).

    Example (a sphere resting on a floor; files in a temporary directory):
        >>> import tempfile, grainscale as gs
        >>> out = tempfile.mkdtemp()
        >>> sim = gs.Simulation(domain=gs.Box(lo=(0, 0, 0), hi=(0.01, 0.01, 0.01)), quiet=True)
        >>> glass = gs.Material(density=2500, youngs_modulus=5e7, poisson_ratio=0.3)
        >>> floor = sim.add_wall(gs.Plane(point=(0, 0, 0), normal=(0, 0, 1)))
        >>> _ = sim.add_particles(position=[[0.005, 0.005, 0.000999]], radius=1e-3,
        ...                       material=glass)
        >>> sim.output(gs.io.ContactNetwork(out, every_steps=100))
        >>> sim.run(steps=2000, progress=False)
        >>> t = gs.io.read_contacts(out)[-1]
        >>> t["wall"].tolist(), round(float(t["normal_force"][0] / -floor.force[2]), 12)
        ([0], 1.0)
    """

    def __init__(
        self,
        directory: str | os.PathLike[str],
        every: float | None = None,
        every_steps: int | None = None,
        prefix: str = "contacts",
        vtk: bool = True,
        table: bool = True,
        walls: bool = True,
        binary: bool = True,
        appended: bool = False,
        resume: bool = True,
    ) -> None:
        self._schedule = Schedule("ContactNetwork", every, every_steps)
        check_prefix("ContactNetwork", prefix)
        for name, value in (("vtk", vtk), ("table", table), ("walls", walls), ("binary", binary),
                            ("appended", appended), ("resume", resume)):  # fmt: skip
            flag("ContactNetwork", name, value)
        if not (vtk or table):
            raise ValueError("ContactNetwork needs vtk=True or table=True, got both False")
        if appended and not binary:
            raise ValueError("ContactNetwork.appended=True requires binary=True, got binary=False")
        self.directory = output_directory("ContactNetwork.directory", directory)
        self.prefix = prefix
        self.vtk, self.table, self.walls = bool(vtk), bool(table), bool(walls)
        self.binary, self.appended, self.resume = bool(binary), bool(appended), bool(resume)
        self.pvd = PVDSeries(self.directory / f"{prefix}.pvd")
        self.files: list[Path] = []  # the .h5 tables (else the .vtp / .pvtp) written
        self.skipped: list[int] = []  # steps whose contacts were not recorded
        self._pvd_started = False

    def __repr__(self) -> str:
        sched = self._schedule.describe()
        return f"ContactNetwork({str(self.directory)!r}, {sched}, prefix={self.prefix!r})"

    def attach(self, sim: Any) -> None:
        """Called by ``Simulation.output``: turns on ``record_contacts``."""
        sim.record_contacts = True

    def next_step(self, step: int, time: float, time_step: float) -> int:
        """Smallest step >= ``step`` at which to write (the output protocol, as VTK's)."""
        return self._schedule.next_step(step, time, time_step)

    def write(self, sim: Any) -> Path | None:
        """Write the network of ``sim``'s last step (collective under MPI); returns the table
        (else the VTK file), or None when the step's contacts were not recorded."""
        step, time = int(sim.step), float(sim.time)
        self._schedule.done(step, time, sim.time_step)
        sim.record_contacts = True
        sim.engine.evaluate_forces()  # a pending set-up evaluation records the contacts
        recorded = sim.sum_over_ranks(len(sim.contacts()["id_i"]))
        if recorded != sim.num_contacts():
            self.skipped.append(step)
            return None
        data = network(sim, self.walls)
        rank, ranks = int(sim.rank), int(sim.ranks)
        stem = f"{self.prefix}_{step:08d}"
        path = None
        if self.vtk:
            path = self._write_vtk(data, stem, time, rank, ranks)
        if self.table:
            attrs = {"step": step, "time": time, "contacts": int(len(data["id_i"]))}
            path = write_snapshot(self.directory, stem, FORMAT, data, attrs, rank, ranks)
        assert path is not None
        self.files.append(path)
        return path

    def _write_vtk(
        self,
        data: dict[str, np.ndarray],
        stem: str,
        time: float,
        rank: int,
        ranks: int,
    ) -> Path:
        make_directory("ContactNetwork.directory", self.directory)
        n = len(data["id_i"])
        points = np.concatenate([data["position_i"], data["position_j"]])
        segments = np.stack([np.arange(n), np.arange(n, 2 * n)], axis=1).astype(np.int64)
        cells = {k: v for k, v in data.items() if not k.startswith("position_")}
        name = f"{stem}.vtp" if ranks == 1 else f"{stem}_r{rank}.vtp"
        write_vtp_lines(
            self.directory / name,
            points,
            segments,
            cell_data=cells,
            binary=self.binary,
            appended=self.appended,
        )
        if ranks > 1 and rank == 0:
            name = f"{stem}.pvtp"
            pieces = [f"{stem}_r{r}.vtp" for r in range(ranks)]
            write_pvtp(self.directory / name, pieces, {}, cell_data=cells)
        if rank == 0:
            if not self._pvd_started and self.resume:
                self.pvd.resume(time)  # the series of the run this one continues
            self._pvd_started = True
            self.pvd.add(time, name)
        return self.directory / name


def read_contacts(
    path: str | os.PathLike[str], prefix: str = "contacts"
) -> dict[str, Any] | list[dict[str, Any]]:
    """Read contact tables written by :class:`ContactNetwork`.

    Args:
        path: a table file (``<prefix>_<step>.h5``; under MPI the index, whose pieces are
            joined in rank order) -> a dict of its columns (module docstring) plus ``step``
            and ``time`` (s); or a directory -> the list of its tables in step order.
        prefix: the tables' file prefix when ``path`` is a directory.

    Raises:
        ValueError: naming the file: not a contact table, or a piece missing.
    """
    where = Path(path)
    if where.is_dir():
        files = snapshot_files(where, prefix)
        if not files:
            raise ValueError(
                f"read_contacts: no contact tables {prefix}_<step>.h5 in {os.fspath(where)!r}"
            )
        return [_read_one(f) for f in files]
    if not where.is_file():
        raise ValueError(
            f"read_contacts.path must be a contact table or a directory, got {os.fspath(path)!r}"
        )
    return _read_one(where)


def _read_one(path: Path) -> dict[str, Any]:
    arrays, attrs = read_snapshot(path, FORMAT)
    out: dict[str, Any] = dict(arrays)
    out["step"], out["time"] = int(attrs["step"]), float(attrs["time"])
    return out
