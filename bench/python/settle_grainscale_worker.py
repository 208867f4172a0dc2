"""grainscale side of the 'settle' benchmark; settle.py runs it in a separate process.

Running it alone keeps its peak memory (ru_maxrss) separate from the driver and from LIGGGHTS.
It reads the case parameters (JSON) and the initial positions/velocities (.npz) written by the
driver, builds the same case as the LIGGGHTS input (see settle_case.py), times only the
``Simulation.run`` call (wall clock and process CPU time) and writes a JSON result file. Under
``mpirun -np N`` the simulation is decomposed over the N ranks (ranks synchronised before and
after the timed call) and rank 0 writes the result, with the particle and ghost counts of every
rank. ``--guards off`` switches the run-time guards off (``Simulation(guards=False)``) and
``--lost-particles`` sets the lost-particle report; guards_cost.py compares the two settings.
``--untimed-steps K`` runs K steps before the timed call (dense_bed.py: the settled bed) and
records the state at the start of the timed part; ``--positions PREFIX`` (one process) saves
the positions there and at the end as PREFIX_start.npy and PREFIX_end.npy.
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from settle_case import SettleCase


def run(
    case: SettleCase,
    state_file: Path,
    balance_every: int | None = None,
    guards: bool = True,
    lost_particles: str = "warn",
    untimed_steps: int = 0,
    positions: str | None = None,
) -> dict[str, Any]:
    """Build the case with the grainscale API, run it (``untimed_steps`` untimed steps, then
    ``case.steps`` timed ones) and return timings and observables; ``positions``: the prefix of
    the position files (one process only)."""
    import grainscale as gs  # imported here so that import time is outside the timed section

    position, velocity = load_state(state_file)
    rss_before_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    t_setup = time.perf_counter()
    sim = settle_simulation(gs, case, position, velocity, guards, lost_particles)
    if balance_every is not None and sim.ranks > 1:
        sim.balance(every=balance_every)  # else the engine's default (every 500 steps)
    ke_initial = float(sim.kinetic_energy())
    setup_seconds = time.perf_counter() - t_setup

    start: dict[str, Any] = {}
    if untimed_steps > 0:
        t_untimed = time.perf_counter()
        sim.run(steps=untimed_steps, progress=False)
        start = {
            "untimed_steps": untimed_steps,
            "untimed_seconds": time.perf_counter() - t_untimed,
            "contacts_start": int(sim.num_contacts()),
        }
        start |= {f"{k}_start": v for k, v in observables(sim, positions, "start").items()}

    if sim.comm is not None:
        sim.comm.Barrier()
    t0, c0 = time.perf_counter(), time.process_time()
    sim.run(steps=case.steps, progress=False)
    if sim.comm is not None:
        sim.comm.Barrier()
    run_seconds = time.perf_counter() - t0
    cpu_seconds = time.process_time() - c0  # less sensitive than wall clock to a busy machine

    end = observables(sim, positions, "end")
    ke_total, ke_trans, n_final = end["ke"], end["ke_trans"], end["n"]
    thermo = {k: _plain(v) for k, v in sim.thermo().items()}
    ranks = {
        "ranks": sim.ranks,
        "particles_per_rank": sim.decomposition()["counts"],
        "ghosts_per_rank": gather_all(sim, int(sim.engine.diagnostics()["ghosts"])),
        "halo_seconds_per_rank": gather_all(sim, float(sim.engine.diagnostics()["halo_seconds"])),
        "rebuilds": int(sim.engine.diagnostics()["rebuilds"]),
    }
    return (
        ranks
        | {
            "version": getattr(gs, "__version__", "unknown"),
            "run_seconds": run_seconds,
            "cpu_seconds": cpu_seconds,
            "setup_seconds": setup_seconds,
            "guards": bool(sim.guards.enabled),
            "lost_particles_policy": sim.lost_particles_policy,
            "steps": int(sim.step),
            "n_final": n_final,
            "ke_initial": ke_initial,
            "ke_final": ke_total,
            "ke_trans_final": ke_trans,
            "ke_rot_final": ke_total - ke_trans,
            "mean_z_final": end["mean_z"],
            "contacts_final": int(sim.num_contacts()),
            "thermo": thermo,
            "rss_before_sim_kib": rss_before_kib,
        }
        | start
    )


def observables(sim: Any, positions: str | None = None, tag: str = "") -> dict[str, Any]:
    """Kinetic energy (total and translational), mean height and particle count over every
    rank; with ``positions`` (one process) the positions are saved to ``<positions>_<tag>.npy``.
    Sums over this rank's particles (views, no copies: the peak memory is the engine's), then
    over the ranks."""
    ke_total = float(sim.kinetic_energy())
    with sim.particles(writable=False) as p:
        vel = p.velocity
        local = np.array(
            [
                0.5 * np.sum(p.mass * np.einsum("ij,ij->i", vel, vel)),
                np.sum(p.position[:, 2]),
                len(p),
            ]
        )
        if positions is not None:
            np.save(f"{positions}_{tag}.npy", p.position)
    total = local if sim.comm is None else sim.comm.allreduce(local)
    n = int(total[2])
    return {"ke": ke_total, "ke_trans": float(total[0]), "mean_z": float(total[1] / max(n, 1)),
            "n": n}  # fmt: skip


def settle_simulation(
    gs: Any,
    case: SettleCase,
    position: np.ndarray,
    velocity: np.ndarray,
    guards: bool = True,
    lost_particles: str = "warn",
    contact: Any = None,
) -> Any:
    """The settle case: the particles in a closed box of six one-sided planes of their material
    (normals into the box). ``contact``: another law than the LIGGGHTS-matched Hertz-Mindlin."""
    hi = case.box_hi
    sim, mat = liggghts_matched_simulation(
        gs, case, (0.0, 0.0, 0.0), hi, position, velocity, guards, lost_particles, contact
    )
    walls = [
        ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
        ((hi[0], 0.0, 0.0), (-1.0, 0.0, 0.0)),
        ((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
        ((0.0, hi[1], 0.0), (0.0, -1.0, 0.0)),
        ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
        ((0.0, 0.0, hi[2]), (0.0, 0.0, -1.0)),
    ]
    for point, normal in walls:
        sim.add_wall(gs.geometry.Plane(point=point, normal=normal, material=mat))
    return sim


def gather_all(sim: Any, value: Any) -> list[Any]:
    """``value`` of every rank, in rank order."""
    return [value] if sim.comm is None else sim.comm.allgather(value)


def load_state(state_file: Path) -> tuple[np.ndarray, np.ndarray]:
    """Initial positions and velocities written by the driver."""
    state = np.load(state_file)
    position = np.ascontiguousarray(state["position"], dtype=np.float64)
    velocity = np.ascontiguousarray(state["velocity"], dtype=np.float64)
    return position, velocity


def liggghts_matched_simulation(
    gs: Any,
    case: Any,
    lo: tuple[float, float, float],
    hi: tuple[float, float, float],
    position: np.ndarray,
    velocity: np.ndarray,
    guards: bool = True,
    lost_particles: str = "warn",
    contact: Any = None,
) -> tuple[Any, Any]:
    """A closed box with gravity along -z, the particles, and the material and Hertz-Mindlin law
    set as LIGGGHTS' 'gran model hertz tangential history' (shared by the benchmark workers;
    ``case`` has the fields of SettleCase's physics). ``guards=False`` switches the run-time
    guards off; ``lost_particles`` is the lost-particle policy (both grainscale's defaults
    otherwise); ``contact`` replaces the law. Returns (simulation, material)."""
    mat = gs.Material(
        density=case.density,
        youngs_modulus=case.youngs_modulus,
        poisson_ratio=case.poisson_ratio,
        name="glass",
    )
    law = gs.contact.HertzMindlin(
        restitution=case.restitution,
        friction=case.friction,
        limit_force=False,  # LIGGGHTS default: limitForce off
        tangential_damping=True,  # LIGGGHTS hertz: tangential damping on
        tangential_history="total",  # LIGGGHTS 'tangential history': F_t = -k_t(delta) xi
        spring_rotation=case.spring_rotation,  # "project": as LIGGGHTS' tangential history
    )
    sim = gs.Simulation(
        domain=gs.Box(lo=lo, hi=hi, periodic=(False, False, False)),
        contact=law if contact is None else contact,
        gravity=(0.0, 0.0, -case.gravity),
        time_step=case.time_step,
        skin=case.skin,
        guards=guards,  # True: the default Guards()
        lost_particles=lost_particles,
    )
    sim.add_particles(
        position=position, radius=0.5 * case.diameter, material=mat, velocity=velocity
    )
    return sim, mat


def _plain(value: Any) -> Any:
    """Make numpy scalars JSON-serialisable."""
    return value.item() if isinstance(value, np.generic) else value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--case", type=Path, required=True, help="case parameters (JSON)")
    parser.add_argument("--state", type=Path, required=True, help="initial state (.npz)")
    parser.add_argument("--output", type=Path, required=True, help="result file (JSON)")
    parser.add_argument(
        "--balance-every", type=int, default=None, help="automatic load balancing interval"
    )
    parser.add_argument(
        "--untimed-steps", type=int, default=0, help="steps run before the timed call"
    )
    parser.add_argument(
        "--positions", default=None, help="save the positions as PREFIX_start/_end.npy"
    )
    add_guard_options(parser)
    args = parser.parse_args(argv)
    case = SettleCase(**json.loads(args.case.read_text()))
    result = run(
        case,
        args.state,
        args.balance_every,
        args.guards == "on",
        args.lost_particles,
        args.untimed_steps,
        args.positions,
    )
    from grainscale.parallel import launched_ranks

    if launched_ranks() == 1 or _rank() == 0:
        args.output.write_text(json.dumps(result, indent=1))
    return 0


def add_guard_options(parser: argparse.ArgumentParser) -> None:
    """--guards and --lost-particles (shared with the hopper worker)."""
    parser.add_argument(
        "--guards",
        choices=("on", "off"),
        default="on",
        help="run-time guards: 'on' (grainscale's default) or 'off' (Simulation(guards=False))",
    )
    parser.add_argument(
        "--lost-particles",
        choices=("warn", "error", "ignore"),
        default="warn",
        help="Simulation(lost_particles=...): the report of particles lost (default 'warn')",
    )


def _rank() -> int:
    from mpi4py import MPI

    return MPI.COMM_WORLD.Get_rank()


if __name__ == "__main__":
    sys.exit(main())
