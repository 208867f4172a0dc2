"""Fingerprints of the engine's behaviour, to show that a change of structure changed none of it.

Runs seven cases and prints, per case, the SHA-256 of the arrays it ends with (particles sorted by
id, float64 bytes as computed): the settle case (20 000 spheres, 2000 steps), the same case with
10 000 spheres for 10 000 steps (0.1 s: the bed forms) under three laws with rolling resistance
(Hertz-Mindlin + EPSD, linear + CDT with the incremental spring, EEPA + EPSD2), the hopper demo
(``--quick``: its history and its last particle snapshot), and the quick MLCG silo as 2 -> 1 and
4 -> 2 -> 1 (each level's particles, the discharge history, the books). Run it before and after
a redesign on the same machine and build; equal lines mean identical results bit for bit (a
different compiler or flags may change the last bits of every case)::

    PYTHONPATH=python python bench/python/identity.py --output before.json
    PYTHONPATH=python python bench/python/identity.py --compare before.json

It is not a timed benchmark: each case takes seconds to a few minutes on one core.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import bench_common  # noqa: F401  (puts the repository root, for the studies, on the path)
import numpy as np
from settle_case import SettleCase, initial_state
from settle_grainscale_worker import settle_simulation

import grainscale as gs


def digest(arrays: dict[str, Any]) -> str:
    """SHA-256 over the arrays in key order (names, shapes and bytes)."""
    h = hashlib.sha256()
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(f"{key}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def particles(sim: Any) -> dict[str, np.ndarray]:
    with sim.particles(writable=False) as p:
        order = np.argsort(p.id)
        fields = ("id", "position", "velocity", "angular_velocity", "force", "torque", "radius")
        return {k: getattr(p, k)[order].copy() for k in fields}


def settle() -> str:
    case = SettleCase(n_particles=20_000, steps=2000)
    position, velocity = initial_state(case)
    sim = settle_simulation(gs, case, position, velocity)
    sim.run(steps=case.steps, progress=False)
    return digest(particles(sim))


def settle_rolling(law: str) -> str:
    case = SettleCase(n_particles=10_000, steps=10_000)
    position, velocity = initial_state(case)
    contact = {
        "hertz+epsd": gs.contact.HertzMindlin(rolling=gs.contact.EPSD(rolling_friction=0.1)),
        "linear+cdt": gs.contact.Linear(
            rolling=gs.contact.CDT(rolling_friction=0.1), tangential_history="incremental"
        ),
        "eepa+epsd2": gs.contact.EEPA(
            rolling=gs.contact.EPSD2(rolling_friction=0.1),
            adhesive_stiffness=50.0,
            pull_off_force=-1e-4,
        ),
    }[law]
    sim = settle_simulation(gs, case, position, velocity, contact=contact)
    sim.run(steps=case.steps, progress=False)
    return digest(particles(sim))


def hopper() -> str:
    from grainscale.examples import hopper_demo

    with tempfile.TemporaryDirectory() as tmp:
        args = argparse.Namespace(quick=True, particles=None, duration=None, seed=1)
        r = hopper_demo.run(tmp, hopper_demo.case_from_args(args), progress=False, verbose=False)
        files = {"history": r.history.read_bytes()}
        # particles_<step>.vtp, the step zero-padded: the last in name order is the last written
        snapshots = sorted(Path(tmp).glob("particles_[0-9]*.vtp"))
        files["last_snapshot"] = snapshots[-1].read_bytes()
        return digest({k: np.frombuffer(v, np.uint8) for k, v in files.items()})


def mlcg(levels: tuple[float, ...]) -> str:
    from studies.mlcg_silo import mlcg_silo

    r = mlcg_silo.run_mlcg(mlcg_silo.QUICK, levels, None)
    arrays: dict[str, Any] = {"history": np.asarray(r.history, float)}
    arrays.update({f"field_{k}": np.asarray(v) for k, v in r.fields.items()})
    b = r.mass_balance
    arrays["books"] = np.array([b["initial"], b["inserted"], b["discharged"], b["unaccounted"]])
    return digest(arrays)


CASES = {
    "settle 20k, 2000 steps": settle,
    "settle 10k, hertz+epsd": lambda: settle_rolling("hertz+epsd"),
    "settle 10k, linear+cdt, incremental": lambda: settle_rolling("linear+cdt"),
    "settle 10k, eepa+epsd2": lambda: settle_rolling("eepa+epsd2"),
    "hopper demo --quick": hopper,
    "quick MLCG silo 2 -> 1": lambda: mlcg((2, 1)),
    "quick MLCG silo 4 -> 2 -> 1": lambda: mlcg((4, 2, 1)),
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", type=Path, help="write the fingerprints (JSON)")
    parser.add_argument("--compare", type=Path, help="compare with fingerprints written before")
    parser.add_argument("--only", nargs="+", choices=list(CASES), help="run only these cases")
    args = parser.parse_args(argv)
    got = {}
    for name, run in CASES.items():
        if args.only and name not in args.only:
            continue
        got[name] = run()
        print(f"{name}: {got[name]}", flush=True)
    if args.output:
        args.output.write_text(json.dumps(got, indent=1))
    if args.compare:
        before = json.loads(args.compare.read_text())
        differ = [k for k in got if before.get(k) != got[k]]
        for k in got:
            print(f"{k}: {'identical' if k not in differ else 'DIFFERS'}")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
