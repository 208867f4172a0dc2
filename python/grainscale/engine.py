"""Engine: what the package's modules may ask of a simulation's compiled level.

Simulation owns a ``_core.Level`` and hands the modules around it (insertion and outlets,
checkpoints, field averages, hierarchies, diagnostics) this one narrow interface as
``sim.engine``, so that none of them reaches into Simulation's attributes and the list of what
they use is in one place. Package-internal: its methods may change without notice.

``core`` is the compiled level itself, for the compiled objects that work on a level (a
hierarchy's ``_core.Interface``, ``_core.CellAverager``); everything else is a named method.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from . import _core
from .particle_view import WriteWatch


class Engine:
    """The package-internal interface to one simulation's compiled level."""

    def __init__(self, level: _core.Level, comm: Any = None) -> None:
        self.core = level
        self.comm = comm
        self._watch = WriteWatch()

    # ----------------------------------------------------------- writes after a block
    def arm_write_watch(self) -> None:
        """At the end of a writable ``with sim.particles()`` block (see WriteWatch)."""
        self._watch.arm(self.core)

    def check_unseen_writes(self) -> None:
        """Collective, before anything that touches the particle arrays (a run, a block, an
        insertion, a removal, a checkpoint, a hierarchy's exchange): RuntimeError on every rank
        if they were written after their block ended (see WriteWatch)."""
        self._watch.check(self.core, self.comm)

    # ------------------------------------------------------------ insertion and outlets
    def pack(
        self,
        region: _core.Region,
        radius: _core.SizeDistribution,
        count: int,
        volume_fraction: float,
        material: int,
        velocity: Sequence[float],
        seed: int,
        max_attempts: int,
    ) -> tuple[int, int]:
        """Packs particles without overlaps (collective); (first global id, count)."""
        first, n = self.core.pack(
            region, radius, count, volume_fraction, material, velocity, seed, max_attempts
        )
        return int(first), int(n)

    def add_stream(self, face: _core.Face, radius: _core.SizeDistribution, **spec: Any) -> int:
        """Registers a stream inserter (keyword arguments as ``_core.Level.add_stream``)."""
        return int(self.core.add_stream(face, radius, **spec))

    def stream_status(self, index: int) -> dict[str, Any]:
        return dict(self.core.stream_status(index))

    def stream_slab(self, index: int) -> _core.Region:
        return self.core.stream_slab(index)

    def add_outlet(self, region: _core.Region, every: int) -> int:
        return int(self.core.add_outlet(region, every))

    def outlet_status(self, index: int) -> dict[str, Any]:
        return dict(self.core.outlet_status(index))

    def outlet_history(self, index: int) -> tuple[Any, Any, Any]:
        t, m, c = self.core.outlet_history(index)
        return t, m, c

    # ------------------------------------------------------------------- checkpoints
    def save_state(self) -> dict[str, Any]:
        """This rank's part of the level's state (collective)."""
        return self.core.save_state()

    def load_state(self, parts: Sequence[dict[str, Any]], exact: bool) -> None:
        """Restores a checkpoint's rank parts (collective): ``exact``, this rank's part saved
        under the same ranks and continued bit-identically (``parts[0]``); else every rank's part
        of another decomposition, of which this rank keeps what lies in its subdomain."""
        if exact:
            self.core.load_state(parts[0])
        else:
            self.core.load_redistributed(list(parts))

    def check_state(self, part: dict[str, Any], exact: bool, n_materials: int) -> None:
        """Every check a load makes on a checkpoint's rank part, changing nothing (RuntimeError
        naming the damage)."""
        self.core.check_state(part, exact, n_materials)

    def processor_grid(self) -> tuple[int, int, int]:
        """The (px, py, pz) ranks along x, y, z."""
        px, py, pz = self.core.decomposition()["grid"]
        return int(px), int(py), int(pz)

    # --------------------------------------------------------------- hierarchy coupling
    def add_coupling(self, interface: _core.Interface, layer: float, fade: float) -> int:
        """Registers an interface's per-step coupling forces on this level; their index."""
        return int(self.core.add_coupling(interface, layer, fade))

    def add_region_outlet(self, interface: _core.Interface, every: int, band: float) -> int:
        """Registers the outlet that removes a child level's particles leaving its region."""
        return int(self.core.add_region_outlet(interface, every, band))

    @property
    def lost_mass(self) -> float:
        """Mass of the particles lost through closed sides, kg (collective)."""
        return float(self.core.lost_mass)

    def clear_lost_log(self) -> None:
        self.core.clear_lost_log()

    # ------------------------------------------------------------------------ outputs
    def evaluate_forces(self) -> None:
        """Collective: completes a pending list build and set-up force evaluation (as the first
        step of the next run would, with the same result: nothing else changes), recording the
        contacts when ``record_contacts`` is on; nothing when the forces are current."""
        self.core.run(0, True)

    # ------------------------------------------------------------------- diagnostics
    def diagnostics(self) -> dict[str, float]:
        """This rank's counters (tests and benchmarks): ``rebuilds`` (neighbour-list builds),
        ``rebuild_seconds`` and ``halo_seconds`` (wall-clock in rebuilds and in the per-step
        ghost exchanges and reductions), ``ghosts`` (ghost particles held), ``walls``."""
        lv = self.core
        return {
            "rebuilds": int(lv.rebuilds),
            "rebuild_seconds": float(lv.rebuild_seconds),
            "halo_seconds": float(lv.halo_seconds),
            "ghosts": int(lv.num_ghosts),
            "walls": int(lv.num_walls()),
        }
