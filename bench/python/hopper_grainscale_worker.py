"""grainscale side of the 'hopper' benchmark; hopper.py runs it in a separate process.

Running it alone keeps its peak memory (ru_maxrss) separate from the driver and from LIGGGHTS.
It reads the case parameters (JSON), the initial positions/velocities (.npz) and the hopper STL
written by the driver, builds the same case as the LIGGGHTS input (see hopper_case.py), runs it
in chunks of ``sample_every`` steps (the LIGGGHTS thermo interval) and samples particle count,
kinetic energy and mean height between chunks. Only the ``Simulation.run`` calls are timed
(wall clock and process CPU time). ``--guards off`` switches the run-time guards off
(``Simulation(guards=False)``) and ``--lost-particles`` sets the report of the discharged
particles (lost through the box floor); guards_cost.py compares the two settings.
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
from hopper_case import HopperCase
from settle_grainscale_worker import add_guard_options, liggghts_matched_simulation, load_state


def run(
    case: HopperCase,
    state_file: Path,
    stl_file: Path,
    deletion: str,
    guards: bool = True,
    lost_particles: str = "warn",
) -> dict[str, Any]:
    """Build the case with the grainscale API, run it and return timings and observables."""
    import grainscale as gs  # imported here so that import time is outside the timed section

    core_mtime = Path(gs._core.__file__).stat().st_mtime  # tells whether a reinstall happened
    position, velocity = load_state(state_file)
    rss_before_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    t_setup = time.perf_counter()
    lo, hi = case.box_lo, case.box_hi
    sim, mat = liggghts_matched_simulation(
        gs, case, lo, hi, position, velocity, guards, lost_particles
    )
    mesh = gs.geometry.Mesh.from_stl(stl_file, material=mat)  # hopper of the particle material
    sim.add_wall(mesh)
    outlet = None
    if deletion.startswith("outlet"):
        # a slab at the box floor: particles are deleted as soon as their centre is within 1 mm
        # of the floor (checked every `every` steps) instead of at the next list rebuild
        every = int(deletion.partition(":")[2] or 1)
        region = gs.Box(lo=(lo[0], lo[1], lo[2] - 1.0), hi=(hi[0], hi[1], lo[2] + 1.0e-3))
        outlet = sim.add_outlet(gs.insert.Outlet(region, every=every))
    setup_seconds = time.perf_counter() - t_setup

    samples: list[dict[str, float]] = [_sample(sim)]
    run_seconds = cpu_seconds = 0.0
    while sim.step < case.steps:
        n = min(case.sample_every, case.steps - sim.step)
        t0, c0 = time.perf_counter(), time.process_time()
        sim.run(steps=n, progress=False)
        run_seconds += time.perf_counter() - t0
        cpu_seconds += time.process_time() - c0
        samples.append(_sample(sim))

    last = samples[-1]
    return {
        "version": getattr(gs, "__version__", "unknown"),
        "core_module": gs._core.__file__,
        "core_module_mtime": core_mtime,  # at import
        "run_seconds": run_seconds,
        "cpu_seconds": cpu_seconds,
        "setup_seconds": setup_seconds,
        "guards": bool(sim.guards.enabled),
        "lost_particles_policy": sim.lost_particles_policy,
        "steps": int(sim.step),
        "n_triangles": int(len(mesh.triangles)),
        "n_vertices": int(len(mesh.vertices)),
        "n_final": int(last["atoms"]),
        "lost_particles": sim.lost_particles,
        "outlet_removed": None if outlet is None else outlet.removed_count,
        "ke_trans_final": last["ke"],
        "ke_rot_final": last["rke"],
        "mean_z_final": last["zmean"],
        "contacts_final": int(sim.num_contacts()),
        "neighbor_builds": sim.engine.diagnostics()["rebuilds"],
        "rebuild_seconds": sim.engine.diagnostics()["rebuild_seconds"],
        "samples": samples,
        "rss_before_sim_kib": rss_before_kib,
    }


def _sample(sim: Any) -> dict[str, float]:
    """The quantities of the LIGGGHTS thermo line: step atoms ke c_rke v_zmean."""
    ke_total = float(sim.kinetic_energy())
    with sim.particles(writable=False) as p:
        n = len(p)
        if n == 0:
            return {"Step": sim.step, "atoms": 0, "ke": 0.0, "rke": 0.0, "zmean": float("nan")}
        mass = np.asarray(p.mass, dtype=np.float64)
        vel = np.asarray(p.velocity, dtype=np.float64)
        ke_trans = float(0.5 * np.sum(mass * np.einsum("ij,ij->i", vel, vel)))
        zmean = float(np.sum(mass * p.position[:, 2]) / np.sum(mass))  # = LIGGGHTS xcm(all,z)
    return {
        "Step": sim.step,
        "atoms": n,
        "ke": ke_trans,
        "rke": ke_total - ke_trans,
        "zmean": zmean,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--case", type=Path, required=True, help="case parameters (JSON)")
    parser.add_argument("--state", type=Path, required=True, help="initial state (.npz)")
    parser.add_argument("--stl", type=Path, required=True, help="hopper mesh (STL)")
    parser.add_argument(
        "--deletion",
        default="domain",
        help="'domain' (lost at the box floor, as LIGGGHTS) or 'outlet[:every]' (gs Outlet)",
    )
    parser.add_argument("--output", type=Path, required=True, help="result file (JSON)")
    add_guard_options(parser)
    args = parser.parse_args(argv)
    if not (args.deletion == "domain" or args.deletion.startswith("outlet")):
        parser.error(f"--deletion must be 'domain' or 'outlet[:every]', got {args.deletion!r}")
    case = HopperCase(**json.loads(args.case.read_text()))
    result = run(
        case, args.state, args.stl, args.deletion, args.guards == "on", args.lost_particles
    )
    args.output.write_text(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
