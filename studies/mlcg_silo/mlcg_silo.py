"""Silo discharge through a small orifice: fully resolved, pure coarse grained, and multi-level
(validation/CASES.md F1 and D1; issue 7).

Run it with ``python -m studies.mlcg_silo.mlcg_silo --output out/mlcg``. One square
flat-bottomed silo is simulated four ways from the same reference parameter set:

* ``resolved``: spheres d = 2 mm (h = 1) everywhere;
* ``cg2``, ``cg4``: parcels h d across (``grainscale.scaling``, scheme "cg") everywhere;
* ``mlcg``: a ``gs.Hierarchy`` of h = 2 everywhere and h = 1 in a box around the orifice
  (``--levels 4 2 1`` adds a middle level: the three-level chain).

The silo (W x W, flat floor at z = 0 with a central square orifice D0 x D0, closed by a
shutter) is filled by a stream through its top, the bed settles, the shutter slides away and
the grains fall into an outlet below the floor. The discharge rate W is the slope of the outlet's
removed mass over the measuring window; for the hierarchy, of the finest level's outlet (the
orifice is in its region). Beverloo's law makes pure CG too slow at small D0 / (h d) (CASES D1
ii: the empty annulus is k parcel diameters wide); the multi-level model resolves the orifice.
Also compared: the cell velocity and solid fraction on the exchange cells of the finest
region (time-averaged over the window) against the resolved run on the same cells (L1-relative,
CASES.md section 0), the mass balance of every interface, and wall-clock per simulated second.

Written to the output directory: ``report.md``, ``results.json``, ``discharge.png`` (removed
mass against time for each run) and, with ``--vtk``, per-run VTK output. ``--quick``: a small
silo and short times (the reduced test in tests/studies/test_mlcg_silo.py).
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
from grainscale.examples import silo_demo
from grainscale.hierarchy import describe_balance

G = 9.81


@dataclass(frozen=True)
class SiloCase:
    """The silo and its particles (SI units)."""

    width: float = 0.08  # silo W x W
    orifice: float = 0.02  # D0 (square orifice D0 x D0)
    height: float = 0.11  # silo walls up to here (the pour face just below)
    below: float = 0.02  # the domain extends this far below the floor
    diameter: float = 2e-3  # reference particle diameter d
    spread: float = 0.05  # +-5 % uniform
    density: float = 2500.0
    youngs_modulus: float = 1e7
    poisson_ratio: float = 0.3
    restitution: float = 0.5
    friction: float = 0.5
    fill_mass: float = 0.45  # kg poured
    fill_rate: float = 2.0  # kg/s
    pour_speed: float = 1.0  # m/s, downwards through the pour face
    settle: float = 0.25  # s after the pour
    discharge: float = 0.5  # s after the shutter opened
    transient: float = 0.1  # s after opening before the measuring window
    region_width: float = 2.0  # fine region: region_width x D0 wide,
    region_top: float = 1.25  # up to region_top x D0 above the floor
    cell_size: float = 0.008  # exchange cells (m): 4 parcel diameters at h = 2
    exchange_every: float = 5e-4  # s
    velocity_gain: float = 0.1
    stress_gain: float = 0.5
    boundary_velocity_gain: float = 1.0
    advance: float = 1.0
    seed: int = 1

    @property
    def open_time(self) -> float:
        return self.fill_mass / self.fill_rate + self.settle

    @property
    def end_time(self) -> float:
        return self.open_time + self.discharge


# A silo three orifices wide, the orifice as in the full case (5 parcels across at h = 2): the
# region's boundary must lie where the coarse flow is right, which it does not with 4 parcels
# across (studies/mlcg_silo/NOTES.md, "Transition cells").
QUICK = SiloCase(
    width=0.06,
    orifice=0.02,
    height=0.08,
    fill_mass=0.2,
    fill_rate=1.5,
    settle=0.2,
    discharge=0.3,
    transient=0.08,
)


def reference(case: SiloCase) -> tuple[gs.scaling.ParameterSet, int]:
    """The resolved parameter set and the shutter's wall index: the silo of the demo
    (:func:`grainscale.examples.silo_demo.reference_parameters`) at this case's sizes."""
    names = {f.name for f in dataclasses.fields(silo_demo.SiloCase)}
    shared = {f.name: getattr(case, f.name) for f in dataclasses.fields(case) if f.name in names}
    return silo_demo.reference_parameters(silo_demo.SiloCase(**shared)), silo_demo.SHUTTER


def fine_region(case: SiloCase) -> gs.Box:
    w, d0 = case.width, case.orifice
    half = 0.5 * case.region_width * d0
    return gs.Box(
        lo=(0.5 * w - half, 0.5 * w - half, -case.below),
        hi=(0.5 * w + half, 0.5 * w + half, case.region_top * d0),
    )


def middle_region(case: SiloCase) -> gs.Box:
    w, d0 = case.width, case.orifice
    half = 0.5 * min(case.width, 2 * case.region_width * d0)
    return gs.Box(
        lo=(0.5 * w - half, 0.5 * w - half, -case.below),
        hi=(0.5 * w + half, 0.5 * w + half, 2 * case.region_top * d0),
    )


@dataclass
class Run:
    name: str
    rate: float = math.nan  # kg/s
    particles: int = 0  # peak count over the levels' sum
    wall_clock: float = 0.0
    history: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    fields: dict[str, Any] = dataclasses.field(default_factory=dict)
    mass_balance: dict[str, Any] = dataclasses.field(default_factory=dict)
    clogged: bool = False
    # Hierarchies: per interface, how the parent's outflow from the region follows the child's
    # and how its velocity follows the child's (see follow()); the worst relative unaccounted
    # mass of the books over the samples.
    following: list[dict[str, float]] = dataclasses.field(default_factory=list)
    max_unaccounted: float = 0.0


def _rate(history: list[tuple[float, float]], start: float) -> tuple[float, bool]:
    t = np.array([h[0] for h in history])
    m = np.array([h[1] for h in history])
    keep = t >= start
    if np.count_nonzero(keep) < 3 or m[keep][-1] <= m[keep][0]:
        return 0.0, True
    slope = np.polyfit(t[keep], m[keep], 1)[0]
    return float(slope), False


def _open_shutter(sims: Sequence[gs.Simulation], shutter: int, speed: float) -> None:
    for sim in sims:
        sim.walls[shutter].set_motion(velocity=(speed, 0.0, 0.0))


def _window_average(grid: dict[str, Any], sim: gs.Simulation) -> gs.fields.CellAverages:
    box = gs.Box(
        lo=tuple(grid["origin"]),
        hi=tuple(np.asarray(grid["origin"]) + np.asarray(grid["dims"]) * np.asarray(grid["edge"])),
    )
    e = grid["edge"]
    return gs.fields.CellAverages(sim, box, (float(e[0]), float(e[1]), float(e[2])))


def run_single(case: SiloCase, h: float, grid: dict[str, Any] | None, vtk: Path | None) -> Run:
    """The silo as one Simulation at coarse-graining ratio h (1: resolved)."""
    params, shutter = reference(case)
    scaled = gs.scaling.scale(params, h, "cg").params if h != 1 else params
    sim = gs.scaling.build_simulation(scaled, quiet=True, record_contacts=grid is not None)
    if vtk is not None:
        sim.output(gs.io.VTK(vtk, every=0.02))
    run = Run(name="resolved" if h == 1 else f"cg{h:g}")
    t0 = time.perf_counter()
    sim.run(until=case.open_time, progress=False)
    _open_shutter([sim], shutter, 2.0)
    sim.run(until=case.open_time + 0.03, progress=False)
    _open_shutter([sim], shutter, 0.0)
    avg = _window_average(grid, sim) if grid is not None else None
    outlet = sim.outlets[0]
    dt_sample = 0.01
    while sim.time < case.end_time - 1e-9:
        sim.run(until=min(sim.time + dt_sample, case.end_time), progress=False)
        run.history.append((sim.time - case.open_time, float(outlet.removed_mass)))
        run.particles = max(run.particles, sim.num_particles)
        if avg is not None and sim.time >= case.open_time + case.transient:
            avg.sample()
    run.wall_clock = time.perf_counter() - t0
    run.rate, run.clogged = _rate(run.history, case.transient)
    if avg is not None:
        f = avg.finish()
        run.fields = {"solid_fraction": f["solid_fraction"], "velocity": f["velocity"]}
    return run


def build_hierarchy(case: SiloCase, levels: Sequence[float]) -> tuple[gs.Hierarchy, int]:
    params, shutter = reference(case)
    exchange = gs.Exchange(
        every=case.exchange_every,
        velocity_gain=case.velocity_gain,
        stress_gain=case.stress_gain,
        boundary_velocity_gain=case.boundary_velocity_gain,
        advance=case.advance,
    )
    # The case's cell size is the finest interface's; a middle level's takes the default
    # (its parent's particles are larger).
    finest = dataclasses.replace(exchange, cell_size=case.cell_size)
    spec = [gs.Level(cg=levels[0])]
    if len(levels) == 3:
        spec.append(gs.Level(cg=levels[1], region=middle_region(case)))
    spec.append(gs.Level(cg=levels[-1], region=fine_region(case), exchange=finest))
    hierarchy = gs.Hierarchy(base=params, levels=spec, exchange=exchange)
    return hierarchy, shutter


def run_mlcg(case: SiloCase, levels: Sequence[float], vtk: Path | None) -> Run:
    h, shutter = build_hierarchy(case, levels)
    if vtk is not None:
        h.output(vtk, every=0.02)
    name = "mlcg" if len(levels) == 2 else "mlcg3"
    run = Run(name=name)
    fine = h.level(len(levels) - 1)
    t0 = time.perf_counter()
    h.run(until=case.open_time)
    _open_shutter(h.sims, shutter, 2.0)
    h.run(until=case.open_time + 0.03)
    _open_shutter(h.sims, shutter, 0.0)
    outlet = fine.outlets[0]
    # The same estimator as for the single-level runs: snapshots of the finest level every
    # 0.01 s on the finest interface's cells.
    avg = _window_average(h.couplings[-1].grid, fine)
    removed: list[tuple[float, list[float]]] = []  # every level's outlet, then what each paid
    velocities: list[list[tuple[np.ndarray, np.ndarray]]] = [[] for _ in h.couplings]
    while h.time < case.end_time - 1e-9:
        h.run(until=min(h.time + 0.01, case.end_time))
        t = h.time - case.open_time
        run.history.append((t, float(outlet.removed_mass)))
        run.particles = max(run.particles, sum(s.num_particles for s in h.sims))
        balance = h.mass_balance()
        total = balance["initial"] + balance["inserted"]
        run.max_unaccounted = max(run.max_unaccounted, abs(balance["unaccounted"]) / total)
        levels = [float(s.outlets[0].removed_mass) for s in h.sims]
        removed.append((t, levels + [i["paid"] for i in balance["interfaces"]]))
        if t >= case.transient:
            avg.sample()
            for k, c in enumerate(h.couplings):
                velocities[k].append((c.parent_fields["velocity"], c.child_fields["velocity"]))
    run.wall_clock = time.perf_counter() - t0
    run.rate, run.clogged = _rate(run.history, case.transient)
    f = avg.finish()
    run.fields = {"solid_fraction": f["solid_fraction"], "velocity": f["velocity"]}
    run.mass_balance = h.mass_balance()
    run.following = follow(h, removed, velocities, case.transient)
    return run


def follow(
    h: gs.Hierarchy,
    removed: list[tuple[float, list[float]]],
    velocities: list[list[tuple[np.ndarray, np.ndarray]]],
    start: float,
) -> list[dict[str, float]]:
    """Per interface, over the measuring window: the parent's outflow from the region (its own
    outlet's rate plus the rate at which it paid the child's discharge by removing particles)
    against the child's (its outlet plus what it paid its own child), and the mean vertical
    velocity of both levels over the region cells above the floor (time-averaged cell Favre
    velocities, cells the child fills)."""
    t = np.array([r[0] for r in removed])
    m = np.array([r[1] for r in removed])
    keep = t >= start
    n = len(h.sims)
    rates = [float(np.polyfit(t[keep], m[keep, k], 1)[0]) for k in range(m.shape[1])]
    outflow = list(rates[:n])
    for i, c in enumerate(h.couplings):
        outflow[c.parent] += rates[n + i]
    out = []
    for i, c in enumerate(h.couplings):
        g = c.grid
        dims, origin, edge = np.array(g["dims"]), np.array(g["origin"]), np.array(g["edge"])
        cells = np.arange(int(np.prod(dims)))
        z = origin[2] + (cells // (dims[0] * dims[1]) + 0.5) * edge[2]
        parent = np.mean([v[0] for v in velocities[i]], axis=0)
        child = np.mean([v[1] for v in velocities[i]], axis=0)
        above = (g["inside"] > 0) & (z > 0) & (np.linalg.norm(child, axis=1) > 0)
        out.append(
            {
                "parent_outlet_rate": rates[c.parent],
                "parent_paid_rate": rates[n + i],
                "parent_outflow_rate": outflow[c.parent],
                "child_outflow_rate": outflow[c.child],
                "outflow_ratio": outflow[c.parent] / outflow[c.child] if outflow[c.child] else 0.0,
                "parent_vz": float(parent[above, 2].mean()),
                "child_vz": float(child[above, 2].mean()),
            }
        )
    return out


def field_errors(
    test: dict[str, Any], ref: dict[str, Any], inside: np.ndarray, boundary: np.ndarray
) -> dict[str, float]:
    """L1-relative differences (CASES.md section 0) over the region cells that the resolved
    run fills (solid fraction above 0.1). The ``interior_`` entries are over the region proper,
    inside the transition layer of boundary cells where the fine level is fed and pushed (the
    gate of CASES.md F1); the others include the transition cells."""
    out: dict[str, float] = {}
    for prefix, cells in (("", inside), ("interior_", inside & ~boundary)):
        cells = cells & (ref["solid_fraction"] > 0.1)
        a, b = test["solid_fraction"][cells], ref["solid_fraction"][cells]
        out[prefix + "solid_fraction"] = float(np.sum(np.abs(a - b)) / np.sum(np.abs(b)))
        va, vb = test["velocity"][cells], ref["velocity"][cells]
        out[prefix + "velocity"] = float(
            np.sum(np.linalg.norm(va - vb, axis=1)) / np.sum(np.linalg.norm(vb, axis=1))
        )
        out[prefix + "cells"] = int(np.count_nonzero(cells))
    return out


def load_resolved(path: Path) -> Run:
    """The resolved run of an earlier study's results.json (same case), to compare new runs
    against without simulating it again."""
    r = json.loads(Path(path).read_text())["runs"]["resolved"]
    return Run(
        name="resolved",
        rate=r["rate"],
        particles=r["particles"],
        wall_clock=r["wall_clock"],
        history=[tuple(h) for h in r["history"]],
        fields={k: np.asarray(v) for k, v in r["fields"].items()},
        clogged=r["clogged"],
    )


def study(
    case: SiloCase,
    output: Path,
    runs: Sequence[str],
    vtk: bool = False,
    reference_results: Path | None = None,
) -> dict[str, Any]:
    output.mkdir(parents=True, exist_ok=True)
    hierarchy, _ = build_hierarchy(case, (2, 1))
    grid = hierarchy.couplings[-1].grid
    del hierarchy
    inside = grid["inside"] > 0
    boundary = grid["boundary"] > 0
    results: dict[str, Run] = {}
    if reference_results is not None:
        results["resolved"] = load_resolved(reference_results)
    for name in runs:
        vtk_dir = output / "vtk" / name if vtk else None
        print(f"running {name} ...", flush=True)
        if name == "resolved":
            results[name] = run_single(case, 1, grid, vtk_dir)
        elif name.startswith("cg"):
            results[name] = run_single(case, float(name[2:]), None, vtk_dir)
        elif name == "mlcg":
            results[name] = run_mlcg(case, (2, 1), vtk_dir)
        elif name == "mlcg3":
            results[name] = run_mlcg(case, (4, 2, 1), vtk_dir)
        r = results[name]
        print(
            f"  {name}: W = {r.rate * 1e3:.1f} g/s{' (clogged)' if r.clogged else ''}, "
            f"{r.particles} particles at most, {r.wall_clock:.0f} s",
            flush=True,
        )
    summary = summarize(case, results, inside, boundary)
    (output / "results.json").write_text(json.dumps(summary, indent=1, default=float))
    (output / "report.md").write_text(report(case, summary))
    plot(output / "discharge.png", results)
    return summary


def summarize(
    case: SiloCase, results: dict[str, Run], inside: np.ndarray, boundary: np.ndarray
) -> dict[str, Any]:
    ref = results.get("resolved")
    out: dict[str, Any] = {"case": dataclasses.asdict(case), "runs": {}}
    for name, r in results.items():
        entry: dict[str, Any] = {
            "rate": r.rate,
            "clogged": r.clogged,
            "particles": r.particles,
            "wall_clock": r.wall_clock,
            "wall_clock_per_simulated_second": r.wall_clock / (case.end_time),
            "history": r.history,
            "mass_balance": r.mass_balance,
            "following": r.following,
            "max_unaccounted": r.max_unaccounted,
            "fields": {k: np.asarray(v).tolist() for k, v in r.fields.items()},
        }
        if ref is not None and name != "resolved":
            entry["rate_ratio"] = r.rate / ref.rate if ref.rate > 0 else math.nan
            entry["speed_up"] = ref.wall_clock / r.wall_clock
            entry["particle_ratio"] = ref.particles / max(r.particles, 1)
            if r.fields and ref.fields:
                entry["field_errors"] = field_errors(r.fields, ref.fields, inside, boundary)
        out["runs"][name] = entry
    return out


def report(case: SiloCase, s: dict[str, Any]) -> str:
    lines = [
        "# Silo discharge: resolved, coarse grained and multi-level (CASES.md F1, D1)",
        "",
        f"- silo {case.width * 1e3:g} x {case.width * 1e3:g} mm, flat floor, square orifice "
        f"D0 = {case.orifice * 1e3:g} mm (D0/d = {case.orifice / case.diameter:g}); spheres "
        f"d = {case.diameter * 1e3:g} mm +/- {case.spread:.0%}, rho = {case.density:g} kg/m^3, "
        f"E = {case.youngs_modulus:g} Pa, e = {case.restitution:g}, mu = {case.friction:g}",
        f"- {case.fill_mass * 1e3:g} g poured at {case.fill_rate:g} kg/s, settled, shutter "
        f"opened at t = {case.open_time:.3f} s; W = slope of the removed mass from "
        f"{case.transient:g} s to {case.discharge:g} s after opening",
        f"- fine region of the hierarchy: {case.region_width:g} D0 wide, from below the floor to "
        f"{case.region_top:g} D0 above it; exchange cells "
        + (f"{case.cell_size * 1e3:g} mm" if case.cell_size else "by default"),
        "- L1 (relative, CASES.md section 0) of the time-averaged cell fields of the finest "
        "level against the resolved run, over the region's cells that the resolved run fills "
        "(solid fraction > 0.1): first over the region proper (the cells inside the transition "
        "layer), then over all its cells, the transition cells included (where the fine level is "
        "fed and pushed)",
        "",
        "| run | W (g/s) | W / W_resolved | particles (max) | wall-clock (s) | speed-up | "
        "particle ratio | L1 solid fraction | L1 velocity | all cells: L1 solid fraction | "
        "L1 velocity |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in s["runs"].items():
        fe = r.get("field_errors", {})
        lines.append(
            f"| {name} | {r['rate'] * 1e3:.1f}{' (clogged)' if r['clogged'] else ''} | "
            f"{r.get('rate_ratio', 1.0):.3f} | {r['particles']} | {r['wall_clock']:.0f} | "
            f"{r.get('speed_up', 1.0):.2f} | {r.get('particle_ratio', 1.0):.2f} | "
            f"{fe.get('interior_solid_fraction', math.nan):.3f} | "
            f"{fe.get('interior_velocity', math.nan):.3f} | "
            f"{fe.get('solid_fraction', math.nan):.3f} | {fe.get('velocity', math.nan):.3f} |"
        )
    for name, r in s["runs"].items():
        if r["mass_balance"]:
            lines += [
                f"- {name}, {line}" for line in describe_balance(r["mass_balance"]).split("\n")
            ]
            lines.append(f"- {name}, books closed to {r['max_unaccounted']:.1e} (relative, worst)")
        lines += [f"- {name}, {describe_following(f)}" for f in r.get("following", [])]
    lines.append("")
    return "\n".join(lines)


def describe_following(f: dict[str, float]) -> str:
    """One line of follow(): how a parent level follows its child."""
    return (
        f"parent outflow {f['parent_outflow_rate'] * 1e3:.1f} g/s (outlet "
        f"{f['parent_outlet_rate'] * 1e3:.1f} + paid {f['parent_paid_rate'] * 1e3:.1f}) against "
        f"the child's {f['child_outflow_rate'] * 1e3:.1f} g/s: ratio {f['outflow_ratio']:.3f}; "
        f"mean v_z above the floor {f['parent_vz'] * 1e3:.1f} mm/s (parent) and "
        f"{f['child_vz'] * 1e3:.1f} mm/s (child)"
    )


def plot(path: Path, results: dict[str, Run]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for name, r in results.items():
        t = [h[0] for h in r.history]
        m = [1e3 * h[1] for h in r.history]
        ax.plot(t, m, label=f"{name}: {r.rate * 1e3:.1f} g/s")
    ax.set_xlabel("time after opening (s)")
    ax.set_ylabel("discharged mass (g)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m studies.mlcg_silo.mlcg_silo",
        description=__doc__.split("\n\n")[0],
    )
    parser.add_argument("--output", type=Path, default=Path("out/mlcg"))
    parser.add_argument(
        "--runs", nargs="+", default=["resolved", "cg2", "cg4", "mlcg", "mlcg3"],
        choices=["resolved", "cg2", "cg4", "mlcg", "mlcg3"],
    )  # fmt: skip
    parser.add_argument("--quick", action="store_true", help="a small silo, short times")
    parser.add_argument("--vtk", action="store_true", help="VTK output per run")
    parser.add_argument(
        "--reference", type=Path, default=None, help="results.json holding the resolved run"
    )
    parser.add_argument(
        "--set", nargs="*", default=[], metavar="NAME=VALUE", help="override SiloCase fields"
    )
    args = parser.parse_args(argv)
    case = QUICK if args.quick else SiloCase()
    for item in args.set:
        key, value = item.split("=", 1)
        case = dataclasses.replace(case, **{key: type(getattr(case, key))(value)})
    summary = study(case, args.output, args.runs, args.vtk, args.reference)
    print((args.output / "report.md").read_text())
    del summary
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
