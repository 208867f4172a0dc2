"""Bin filling with a resolved window (validation/CASES.md F2; issue 7): the stress coupling.

Run it with ``python -m studies.mlcg_bin_fill.mlcg_bin_fill --output out/bin_fill``. A narrow bin
(walls on every side, open top) is filled by a stream from above and the bed settles. Three runs
from one reference parameter set: ``resolved`` (d = 2 mm everywhere), ``cg2`` (parcels of
4 mm everywhere) and ``mlcg``: a ``gs.Hierarchy`` of h = 2 in the whole bin and h = 1 in a window
at its bottom, which receives its particles through the window's top face and feels the weight
of the coarse bed above it only through the stress boundary condition (the PI controller that
pushes the window's top layer so that its normal stress follows the coarse cells'; velocity
feedback off, as in the reference set-up of CASES F2). Compared, once the bed is at rest: the
cell stress sigma_zz and the solid fraction in the window's cells against the resolved run
(L1-relative, CASES.md section 0; pass within 10 %), and the mass balance of the interface.

Written to the output directory: ``report.md``, ``results.json`` and ``bin_fill.png`` (sigma_zz
and solid fraction against height in the window). ``--quick``: a shallower bed (the reduced
test in tests/studies/test_mlcg_bin_fill.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs
from grainscale.hierarchy import describe_balance


@dataclass(frozen=True)
class BinCase:
    width: float = 0.04  # x
    depth: float = 0.02  # y
    height: float = 0.12  # walls up to here (open top)
    window_top: float = 0.03  # the resolved window: the whole bin cross-section, z in [0, top]
    diameter: float = 2e-3
    spread: float = 0.05
    density: float = 2500.0
    youngs_modulus: float = 1e7
    poisson_ratio: float = 0.35
    restitution: float = 0.6
    friction: float = 0.3
    wall_friction: float = 0.5
    fill_mass: float = 0.08  # kg
    fill_rate: float = 0.25  # kg/s
    settle: float = 0.35  # s after the stream stops
    samples: int = 10  # cell-average samples over the last 0.05 s
    cell_size: float = 0.01  # exchange cells (m): 2.4 parcel diameters
    seed: int = 3

    @property
    def end_time(self) -> float:
        return self.fill_mass / self.fill_rate + self.settle


QUICK = BinCase(fill_mass=0.05, fill_rate=0.25, settle=0.3)


def reference(case: BinCase) -> gs.scaling.ParameterSet:
    glass = gs.Material(
        density=case.density,
        youngs_modulus=case.youngs_modulus,
        poisson_ratio=case.poisson_ratio,
        name="glass",
    )
    # The walls: the same elastic properties, their own friction with the grains.
    wall = dataclasses.replace(glass, name="wall")
    box = gs.Box(lo=(0, 0, 0), hi=(case.width, case.depth, case.height))
    walls = tuple(w for w in gs.geometry.box_walls(box, wall) if w.normal[2] >= 0)  # open top
    r = 0.5 * case.diameter
    size = gs.dist.Uniform(r * (1 - case.spread), r * (1 + case.spread))
    margin = 2.5 * case.diameter  # room for the parcels (h = 2)
    stream = gs.insert.Stream(
        gs.insert.RectangleFace(
            corner=(margin, margin, case.height - 0.01),
            edge1=(case.width - 2 * margin, 0, 0),
            edge2=(0, case.depth - 2 * margin, 0),
        ),
        mass_rate=case.fill_rate,
        radius=size,
        material=glass,
        velocity=(0, 0, -1.0),
        seed=case.seed,
        stop=case.fill_mass / case.fill_rate,
    )
    law = gs.contact.HertzMindlin(
        restitution=case.restitution,
        friction=case.friction,
        pairs={(glass, wall): gs.contact.Pair(friction=case.wall_friction)},
    )
    return gs.scaling.ParameterSet(
        domain=box, contact=law, walls=walls, insertions=(stream,), size=size
    )


def window(case: BinCase) -> gs.Box:
    return gs.Box(lo=(0, 0, 0), hi=(case.width, case.depth, case.window_top))


def run_single(case: BinCase, h: float) -> dict[str, Any]:
    params = reference(case)
    scaled = gs.scaling.scale(params, h, "cg").params if h != 1 else params
    sim = gs.scaling.build_simulation(scaled, quiet=True, record_contacts=True)
    t0 = time.perf_counter()
    sim.run(until=case.end_time - 0.05, progress=False)
    avg = gs.fields.CellAverages(sim, window(case), case.cell_size)
    for k in range(case.samples):
        sim.run(until=case.end_time - 0.05 * (1 - (k + 1) / case.samples), progress=False)
        avg.sample()
    f = avg.finish()
    return {
        "wall_clock": time.perf_counter() - t0,
        "particles": sim.num_particles,
        "stress_zz": f["stress"][:, 2, 2],
        "solid_fraction": f["solid_fraction"],
        "dims": avg.dims,
        "kinetic_energy": sim.kinetic_energy(),
    }


def run_mlcg(case: BinCase) -> dict[str, Any]:
    exchange = gs.Exchange(every=5e-4, cell_size=case.cell_size, velocity_gain=0.0)
    h = gs.Hierarchy(
        base=reference(case),
        levels=[gs.Level(cg=2), gs.Level(cg=1, region=window(case))],
        exchange=exchange,
    )
    t0 = time.perf_counter()
    h.run(until=case.end_time - 0.05)
    # The same estimator as for the single-level runs, on the fine level.
    avg = gs.fields.CellAverages(h.level(1), window(case), case.cell_size)
    for k in range(case.samples):
        h.run(until=case.end_time - 0.05 * (1 - (k + 1) / case.samples))
        avg.sample()
    f = avg.finish()
    grid = h.couplings[0].grid
    if tuple(int(n) for n in grid["dims"]) != tuple(avg.dims):
        raise RuntimeError(f"exchange grid {grid['dims']} and averaging grid {avg.dims} differ")
    return {
        "wall_clock": time.perf_counter() - t0,
        "particles": sum(s.num_particles for s in h.sims),
        "stress_zz": f["stress"][:, 2, 2],
        "solid_fraction": f["solid_fraction"],
        "dims": avg.dims,
        "boundary": (np.asarray(grid["boundary"]) > 0).tolist(),
        "mass_balance": h.mass_balance(),
        "pressure": h.fields(0)["pressure"],
        "kinetic_energy": h.level(1).kinetic_energy(),
    }


def l1(test: np.ndarray, ref: np.ndarray) -> float:
    return float(np.sum(np.abs(test - ref)) / np.sum(np.abs(ref)))


def _seed_mean(runs: list[dict[str, Any]]) -> dict[str, Any]:
    """The runs of one configuration over the seeds: mean cell fields, summed wall-clock, the
    per-seed mass balances."""
    out = dict(runs[0])
    for key in ("stress_zz", "solid_fraction"):
        out[key] = np.mean([np.asarray(r[key]) for r in runs], axis=0)
    out["wall_clock"] = float(np.mean([r["wall_clock"] for r in runs]))
    out["particles"] = int(np.mean([r["particles"] for r in runs]))
    if "mass_balance" in out:
        out["mass_balance"] = [r["mass_balance"] for r in runs]
    out.pop("pressure", None)
    return out


def study(
    case: BinCase, output: Path, runs: Sequence[str], seeds: Sequence[int] | None = None
) -> dict[str, Any]:
    """Every run of ``runs`` once per seed (default: the case's); the cell fields compared are
    the means over the seeds (in a bed at rest, time averaging does not smooth the force chains;
    seeds do)."""
    output.mkdir(parents=True, exist_ok=True)
    seeds = list(seeds) if seeds else [case.seed]
    per_seed: dict[str, list[dict[str, Any]]] = {name: [] for name in runs}
    for seed in seeds:
        c = dataclasses.replace(case, seed=seed)
        for name in runs:
            print(f"running {name}, seed {seed} ...", flush=True)
            if name == "resolved":
                r = run_single(c, 1)
            elif name == "cg2":
                r = run_single(c, 2)
            else:
                r = run_mlcg(c)
            per_seed[name].append(r)
            print(f"  {name}: {r['wall_clock']:.0f} s", flush=True)
    results = {name: _seed_mean(rs) for name, rs in per_seed.items()}
    ref = results.get("resolved")
    # The window proper: the cells inside the hierarchy's transition layer (all runs alike).
    boundary = next((r["boundary"] for r in results.values() if "boundary" in r), None)
    inner = ~np.asarray(boundary, bool) if boundary is not None else None
    summary: dict[str, Any] = {"case": dataclasses.asdict(case), "seeds": seeds, "runs": {}}
    for name, r in results.items():
        entry = {
            k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.items() if k != "dims"
        }
        entry["dims"] = list(r["dims"])
        if ref is not None and name != "resolved" and tuple(r["dims"]) == tuple(ref["dims"]):
            entry["l1_stress_zz"] = l1(r["stress_zz"], ref["stress_zz"])
            entry["l1_solid_fraction"] = l1(r["solid_fraction"], ref["solid_fraction"])
            if inner is not None:
                entry["interior_l1_stress_zz"] = l1(r["stress_zz"][inner], ref["stress_zz"][inner])
                entry["interior_l1_solid_fraction"] = l1(
                    r["solid_fraction"][inner], ref["solid_fraction"][inner]
                )
        summary["runs"][name] = entry
    # The scatter of the reference itself: one resolved seed against the mean of the others.
    resolved = per_seed.get("resolved", [])
    if len(resolved) >= 2 and inner is not None:
        scatter = []
        for k, r in enumerate(resolved):
            others = np.mean([o["stress_zz"] for j, o in enumerate(resolved) if j != k], axis=0)
            scatter.append(l1(np.asarray(r["stress_zz"])[inner], others[inner]))
        summary["resolved_seed_scatter_interior_l1_stress_zz"] = scatter
    (output / "results.json").write_text(json.dumps(summary, indent=1, default=float))
    (output / "report.md").write_text(report(case, summary))
    plot(output / "bin_fill.png", summary)
    return summary


def _profile(values: list[float], dims: Sequence[int]) -> np.ndarray:
    """Mean over each horizontal layer of cells (cell c = ix + nx (iy + ny iz))."""
    return np.asarray(values).reshape(dims[2], -1).mean(axis=1)


def report(case: BinCase, s: dict[str, Any]) -> str:
    lines = [
        "# Bin filling with a resolved window (CASES.md F2)",
        "",
        f"- bin {case.width * 1e3:g} x {case.depth * 1e3:g} mm, {case.fill_mass * 1e3:g} g of "
        f"d = {case.diameter * 1e3:g} mm spheres poured at {case.fill_rate:g} kg/s, settled "
        f"until t = {case.end_time:g} s; window z in [0, {case.window_top * 1e3:g}] mm, cells "
        f"{case.cell_size * 1e3:g} mm; averages over the last 0.05 s ({case.samples} samples) "
        f"and over the seeds {', '.join(str(k) for k in s.get('seeds', [case.seed]))}",
        "",
        "L1-relative against the resolved run over the window proper (the cells below its "
        "transition layer, where the controller pushes) and over all its cells:",
        "",
        "| run | particles | wall-clock (s) | L1 sigma_zz | L1 solid fraction | "
        "all cells: L1 sigma_zz | L1 solid fraction |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, r in s["runs"].items():
        lines.append(
            f"| {name} | {r['particles']} | {r['wall_clock']:.0f} | "
            f"{r.get('interior_l1_stress_zz', math.nan):.3f} | "
            f"{r.get('interior_l1_solid_fraction', math.nan):.3f} | "
            f"{r.get('l1_stress_zz', math.nan):.3f} | {r.get('l1_solid_fraction', math.nan):.3f} |"
        )
    lines += ["", "sigma_zz (Pa) per layer of cells, bottom first:", ""]
    for name, r in s["runs"].items():
        prof = _profile(r["stress_zz"], r["dims"])
        lines.append(f"- {name}: " + ", ".join(f"{v:.0f}" for v in prof))
    scatter = s.get("resolved_seed_scatter_interior_l1_stress_zz")
    if scatter:
        lines.append(
            "- the reference's own scatter: one resolved seed against the mean of the others, "
            "L1 sigma_zz over the window proper: " + ", ".join(f"{v:.3f}" for v in scatter)
        )
    for b in s["runs"].get("mlcg", {}).get("mass_balance", []):
        lines += [f"- mass balance, {line}" for line in describe_balance(b).split("\n")]
    lines.append("")
    return "\n".join(lines)


def plot(path: Path, s: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 4))
    for name, r in s["runs"].items():
        dims = r["dims"]
        z = (np.arange(dims[2]) + 0.5) * s["case"]["window_top"] / dims[2] * 1e3
        a.plot(_profile(r["stress_zz"], dims), z, marker="o", label=name)
        b.plot(_profile(r["solid_fraction"], dims), z, marker="o", label=name)
    a.set_xlabel("sigma_zz (Pa)")
    b.set_xlabel("solid fraction")
    a.set_ylabel("z (mm)")
    a.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m studies.mlcg_bin_fill.mlcg_bin_fill", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--output", type=Path, default=Path("out/bin_fill"))
    parser.add_argument(
        "--runs",
        nargs="+",
        default=["resolved", "cg2", "mlcg"],
        choices=["resolved", "cg2", "mlcg"],
    )
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--seeds", type=int, nargs="+", default=None, help="default: 3 4 5")
    args = parser.parse_args(argv)
    case = QUICK if args.quick else BinCase()
    seeds = args.seeds or ([case.seed] if args.quick else [3, 4, 5])
    study(case, args.output, args.runs, seeds)
    print((args.output / "report.md").read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
