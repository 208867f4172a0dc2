"""The silo demo's report (grainscale.examples.silo_demo runs the case): the comparison of the
runs with the reference, the summary it prints and writes (``summary.txt``, ``summary.json``),
the plots (``discharge.png``, ``levels.png``) and the VTK series of the material as the
hierarchy represents it (``levels.pvd``: each level where it is the finest, with ``level``)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import grainscale as gs
from grainscale.hierarchy import describe_balance, in_cells

if TYPE_CHECKING:
    from grainscale.examples.silo_demo import DemoResult, Run, SiloCase

COLOURS = ("tab:blue", "tab:orange", "tab:green")  # per level, coarsest first
RUN_COLOURS = {"cg": "tab:red", "mlcg": "tab:blue", "resolved": "black"}


# ------------------------------------------------------------------------------------------
# particles of the levels
# ------------------------------------------------------------------------------------------


@dataclass
class Snapshot:
    """Every level's particles at one time: per level position (n, 3) m, radius (n,) m,
    velocity (n, 3) m/s, id (n,), and ``finest`` (n,) bool: the particle lies where its level
    is the finest (outside its children's region cells; its other particles are the shadow of
    the finer level's material)."""

    title: str
    levels: list[dict[str, np.ndarray]]
    cg: list[float]
    regions: list[tuple[np.ndarray, np.ndarray]]  # the finer levels' region boxes (lo, hi), m


def _particles_of(sim: gs.Simulation) -> dict[str, np.ndarray]:
    return sim.gather(("position", "radius", "velocity"))


def snapshot(h: gs.Hierarchy, title: str) -> Snapshot:
    """Collective: the particles of every level of ``h`` (on every rank)."""
    levels = []
    for k, sim in enumerate(h.sims):
        p = _particles_of(sim)
        finest = np.ones(len(p["radius"]), bool)
        for c in h.couplings:
            if c.parent == k:
                finest &= ~in_cells(c.grid, p["position"])
        levels.append({**p, "finest": finest})
    regions = []
    for lv in h.levels[1:]:
        lo, hi = lv.region._to_core("Level").bounds()  # type: ignore[union-attr]
        regions.append((np.asarray(lo, float), np.asarray(hi, float)))
    return Snapshot(title, levels, [lv.cg for lv in h.levels], regions)


def single_snapshot(sim: gs.Simulation, cg: float, title: str) -> Snapshot:
    """Collective: the particles of a one-level run at coarse-graining ratio ``cg``."""
    p = _particles_of(sim)
    return Snapshot(title, [{**p, "finest": np.ones(len(p["radius"]), bool)}], [cg], [])


class LevelSeries:
    """``<directory>/levels.pvd`` + ``levels_<k>.vtp``: the material as the hierarchy represents
    it, each level's particles where it is the finest, with point data ``radius`` (m),
    ``velocity`` (m/s), ``id`` and ``level`` (0: the coarsest). Rank 0 writes."""

    def __init__(self, directory: Path) -> None:
        self.directory = Path(directory)
        self.pvd = gs.io.PVDSeries(self.directory / "levels.pvd")

    def write(self, h: gs.Hierarchy) -> None:
        """Collective: add a snapshot of ``h`` at its current time."""
        snap = snapshot(h, "")
        if h.sims[0].rank != 0:
            return
        parts = [{k: v[lv["finest"]] for k, v in lv.items()} for lv in snap.levels]
        level = [np.full(len(p["radius"]), k, dtype=np.int32) for k, p in enumerate(parts)]
        name = f"levels_{len(self.pvd.entries):04d}.vtp"
        self.directory.mkdir(parents=True, exist_ok=True)
        gs.io.write_vtp(
            self.directory / name,
            np.concatenate([p["position"] for p in parts]),
            {
                "radius": np.concatenate([p["radius"] for p in parts]),
                "velocity": np.concatenate([p["velocity"] for p in parts]),
                "id": np.concatenate([p["id"] for p in parts]),
                "level": np.concatenate(level),
            },
        )
        self.pvd.add(h.time, name)


# ------------------------------------------------------------------------------------------
# the comparison
# ------------------------------------------------------------------------------------------


def compare(result: DemoResult) -> None:
    """The reference (the live resolved run with --full, else the shipped one), each run's
    error against it and the hierarchy's speed-up over it (CPU time: the engine is
    single-threaded, so it does not depend on what else the machine runs)."""
    ref = result.runs.get("resolved", result.shipped)
    result.reference = ref
    if ref is None:
        return
    for name, r in result.runs.items():
        if name != "resolved":
            result.errors[name] = r.rate / ref.rate - 1.0
    mlcg = result.runs["mlcg"]
    if math.isfinite(ref.cpu_time) and mlcg.cpu_time > 0:
        result.speed_up = ref.cpu_time / mlcg.cpu_time
    elif mlcg.wall_clock > 0:
        result.speed_up = ref.wall_clock / mlcg.wall_clock


def _pct(x: float) -> str:
    return f"{100 * x:+.1f} %"


def setup_text(case: SiloCase, full: bool) -> str:
    """What the demo prints before it runs."""
    mm = 1e3
    return (
        f"grainscale demo: a {case.width * mm:g} x {case.width * mm:g} mm silo, square orifice "
        f"D0 = {case.orifice * mm:g} mm = {case.orifice / case.diameter:g} d "
        f"= {case.orifice / (case.coarse * case.diameter):g} parcels at h = {case.coarse:g}; "
        f"{case.fill_mass * mm:g} g of d = {case.diameter * mm:g} mm spheres (seed {case.seed}), "
        f"discharged for {case.discharge:g} s.\nRuns: pure CG h = {case.coarse:g}, MLCG "
        f"{case.coarse:g} -> 1"
        + (
            ", resolved (--full)"
            if full
            else "; the resolved reference is read from the shipped file (--full runs it)"
        )
    )


def jammed_at(r: Run) -> float | None:
    """When the discharge stopped (s after opening: the last sample whose discharged mass
    grew), if it stopped before the last quarter of the run; else None."""
    t = np.array([0.0] + [x[0] for x in r.history])
    m = np.array([0.0] + [x[1] for x in r.history])
    grew = np.nonzero(np.diff(m) > 0)[0]
    last = float(t[grew[-1] + 1]) if len(grew) else 0.0
    return last if last < 0.75 * t[-1] else None


def _jam(r: Run) -> str:
    t = jammed_at(r)
    return "" if t is None else f"jammed at {t:.2f} s"


def run_line(r: Run) -> str:
    """One line per finished run."""
    state = f" ({_jam(r)})" if _jam(r) else ""
    return (
        f"  -> {r.label}: W = {r.rate * 1e3:.2f} g/s{state}, {sum(r.particles)} particles, "
        f"{r.wall_clock:.1f} s wall-clock, {r.cpu_time:.1f} s CPU"
    )


def _particles(r: Run, case: SiloCase) -> str:
    if len(r.particles) == 1:
        return f"{r.particles[0]}"
    ratios = [case.coarse, 1.0]
    per = ", ".join(f"h={h:g}: {n}" for h, n in zip(ratios, r.particles, strict=True))
    return f"{sum(r.particles)} ({per})"


def table(result: DemoResult) -> list[str]:
    """The runs' table: W, error, particles, wall-clock, CPU time."""
    rows = [("run", "W (g/s)", "vs reference", "particles", "wall-clock", "CPU time")]
    runs = list(result.runs.values())
    if "resolved" not in result.runs and result.shipped is not None:
        runs.append(result.shipped)
    for r in runs:
        err = result.errors.get(r.name)
        vs = "reference" if r is result.reference else "-" if err is None else _pct(err)
        note = "" if r.live else " *"
        rows.append(
            (
                r.label,
                f"{r.rate * 1e3:.2f}",
                f"{vs}, {_jam(r)}" if _jam(r) else vs,
                _particles(r, result.case),
                f"{r.wall_clock:.1f} s{note}",
                f"{r.cpu_time:.1f} s{note}" if math.isfinite(r.cpu_time) else "-",
            )
        )
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [
        "  ".join(
            c.rjust(w) if i else c.ljust(w)
            for i, (c, w) in enumerate(zip(row, widths, strict=True))
        )
        for row in rows
    ]


def reference_lines(result: DemoResult) -> list[str]:
    """Where the reference comes from."""
    ref, shipped = result.reference, result.shipped
    if ref is None:
        return [
            "- no reference for this case (the shipped one is for the default and --quick "
            "cases): run with --full"
        ]
    lines = []
    if ref.live:
        lines.append(f"- reference: the resolved run above (seed {result.case.seed}), run now")
    if shipped is not None:
        e = shipped.extra
        made = e["provenance"][0]
        scatter = f", scatter {e['scatter']:.1%} per seed" if e.get("scatter") else ""
        lines.append(
            f"- {'shipped ' if ref.live else ''}reference: silo_reference.json, W = "
            f"{shipped.rate * 1e3:.2f} g/s, mean of seeds {e['seeds']}{scatter}; discharged "
            f"mass of seed {e['history_seed']}; {made['what']} at commit {made['commit'][:10]} "
            f"({made['date'][:10]})"
        )
        checks = [p for p in e["provenance"] if p.get("history_identical")]
        if checks:
            lines.append(
                f"  (seed {e['history_seed']} rerun by this demo's code at commit "
                f"{checks[-1]['commit'][:10]} ({checks[-1]['date'][:10]}): the same discharge, "
                "sample for sample)"
            )
        if "mlcg" in e:
            m = e["mlcg"]
            lines.append(
                f"- one seed of MLCG scatters: over seeds {m['seeds']} (studies/mlcg_jam) MLCG "
                f"2 -> 1 ran {_pct(min(m['rates']) / shipped.rate - 1)} to "
                f"{_pct(max(m['rates']) / shipped.rate - 1)}, mean {_pct(m['rate_ratio'] - 1)}"
            )
    return lines


def speed_lines(result: DemoResult) -> list[str]:
    """The speed-up of the hierarchy over the resolved run, and the particle ratio."""
    ref, mlcg = result.reference, result.runs["mlcg"]
    if ref is None or result.speed_up is None:
        return []
    fewer = f"{ref.particles[0] / sum(mlcg.particles):.2f} x fewer particles"
    if not math.isfinite(ref.cpu_time):
        return [
            f"- speed-up of {mlcg.label} over the resolved run: {result.speed_up:.2f} x in "
            f"wall-clock (recorded with the reference); {fewer}"
        ]
    if ref.live:
        wall = ref.wall_clock / mlcg.wall_clock
        return [
            f"- speed-up of {mlcg.label} over the resolved run (both run now): "
            f"{result.speed_up:.2f} x in CPU time, {wall:.2f} x in wall-clock; {fewer}"
        ]
    t = ref.extra["timing"][0]
    runs = [p for p in ref.extra["provenance"] if "rerun" in p["what"] or "runs" in p["what"]]
    at = f", commit {runs[-1]['commit'][:10]}" if runs else ""
    return [
        f"- speed-up of {mlcg.label} over the resolved run: {result.speed_up:.2f} x in CPU time "
        f"(the resolved run not run now: its CPU time recorded with the reference, seed "
        f"{t.get('seed', '?')}{at}; the engine is single-threaded, so on an idle machine the "
        f"wall-clock ratio is about the same); {fewer}"
    ]


def books_lines(r: Run) -> list[str]:
    """The hierarchy's books and how the coarse level followed the fine one."""
    b = r.mass_balance
    lines = ["- books of the material (Hierarchy.mass_balance):"]
    lines += [f"    {line}" for line in describe_balance(b).split("\n")]
    lines.append(
        f"- unaccounted mass: {b['unaccounted']:.1e} kg at the end, at most "
        f"{r.max_unaccounted:.1e} of the material over the discharge (sampled every 0.01 s)"
    )
    for i in b["interfaces"]:
        g = 1e3
        lines.append(
            f"- the coarse level followed the fine one's discharge ({i['child_removed'] * g:.1f} "
            f"g): {i['parent_removed'] * g:.1f} g through its own outlet, "
            f"{i['paid'] * g:.1f} g removed above the orifice, owing {i['debt'] * g:.2f} g"
        )
    return lines


def summary(result: DemoResult, total: float) -> str:
    """summary.txt: the case, the table, the reference, the speed-up, the books, the files."""
    c = result.case
    mm = 1e3
    lines = [
        f"# grainscale demo: a silo whose orifice jams coarse graining (seed {c.seed})",
        "",
        f"- silo {c.width * mm:g} x {c.width * mm:g} mm, flat floor, square orifice D0 = "
        f"{c.orifice * mm:g} mm: {c.orifice / c.diameter:g} resolved diameters (d = "
        f"{c.diameter * mm:g} mm +/- {c.spread:.0%}), {c.orifice / (c.coarse * c.diameter):g} "
        f"parcels at h = {c.coarse:g}; {result.runs['mlcg'].inserted * mm:.1f} g poured, settled, "
        f"shutter opened at t = {c.open_time:.2f} s, discharged for {c.discharge:g} s; W = slope "
        f"of the discharged mass from {c.transient:g} s after opening",
        f"- MLCG {c.coarse:g} -> 1: h = {c.coarse:g} everywhere, resolved in a box "
        f"{c.region_width * c.orifice * mm:g} mm wide around the orifice, from below the floor to "
        f"{c.region_top * c.orifice * mm:g} mm above it; exchange every "
        f"{c.exchange_every * 1e3:g} ms",
        "",
        *table(result),
        "",
        *reference_lines(result),
        *speed_lines(result),
        *books_lines(result.runs["mlcg"]),
    ]
    if result.reference is not None and not result.reference.live:
        lines.append("- *: recorded with the reference, not measured now")
    out = result.output
    lines += [
        f"- plots: {out / 'discharge.png'}, {out / 'levels.png'}",
        (
            f"- ParaView: {out / 'levels.pvd'} (each level where it is the finest, colour by "
            f"`level`), {out / 'level0.pvd'} and {out / 'level1.pvd'} (every particle of each "
            f"level, with `level`), {out / 'cells0.pvd'} (exchange cells)"
        )
        if result.vtk
        else "- ParaView: not written (--no-vtk)",
        f"- summary: {out / 'summary.txt'}, {out / 'summary.json'}; demo wall-clock {total:.0f} s",
        "",
    ]
    return "\n".join(lines)


def _run_json(r: Run) -> dict[str, Any]:
    return {
        "label": r.label,
        "rate": r.rate,
        "clogged": r.clogged,
        "particles": r.particles,
        "wall_clock": r.wall_clock,
        "cpu_time": r.cpu_time if math.isfinite(r.cpu_time) else None,
        "live": r.live,
        "history": r.history,
        "mass_balance": r.mass_balance or None,
        "max_unaccounted": r.max_unaccounted,
    }


def summary_json(result: DemoResult, total: float) -> dict[str, Any]:
    """summary.json: the case, every run (the reference too), the errors, the speed-up."""
    import dataclasses

    runs = {name: _run_json(r) for name, r in result.runs.items()}
    if result.shipped is not None:
        runs["reference"] = _run_json(result.shipped)
        runs["reference"]["provenance"] = result.shipped.extra["provenance"]
    return {
        "case": dataclasses.asdict(result.case),
        "runs": runs,
        "reference": None
        if result.reference is None
        else result.reference.name
        if result.reference.live
        else "reference",
        "errors": result.errors,
        "speed_up": result.speed_up,
        "demo_wall_clock": total,
    }


def finish(result: DemoResult, snapshots: list[Snapshot], total: float, lead: bool) -> None:
    """Compare, then (rank 0) write the summary and the plots."""
    compare(result)
    result.summary_text = summary(result, total)
    if not lead:
        return
    out = result.output
    (out / "summary.txt").write_text(result.summary_text)
    (out / "summary.json").write_text(json.dumps(summary_json(result, total), indent=1) + "\n")
    plot_discharge(out / "discharge.png", result)
    plot_levels(out / "levels.png", result.case, snapshots)


# ------------------------------------------------------------------------------------------
# plots
# ------------------------------------------------------------------------------------------


def plot_discharge(path: Path, result: DemoResult) -> None:
    """discharge.png: discharged mass (g) against time after the opening (s) for pure CG, the
    hierarchy and the reference, with their rates."""
    from .._optional import pyplot

    plt = pyplot()
    c = result.case
    fig, ax = plt.subplots(figsize=(7.0, 4.5), dpi=150)
    runs = [result.runs["cg"], result.runs["mlcg"]]
    if result.reference is not None:
        runs.append(result.reference)
    for r in runs:
        t = [0.0] + [x[0] for x in r.history]  # nothing has left at the opening
        m = [0.0] + [1e3 * x[1] for x in r.history]
        err = result.errors.get(r.name)
        note = f" ({_pct(err)})" if err is not None else ""
        if r is result.reference:
            note = " (reference)"
        if not r.live:
            note = f", mean of seeds {r.extra['seeds']}; seed {r.extra['history_seed']} shown"
        ax.plot(
            t,
            m,
            color=RUN_COLOURS[r.name],
            linestyle="--" if not r.live else "-",
            label=f"{r.label}: {r.rate * 1e3:.2f} g/s{note}",
        )
    ax.axvspan(0.0, c.transient, color="0.9", zorder=0)
    ax.text(
        0.5 * c.transient,
        0.97,
        "transient",
        transform=ax.get_xaxis_transform(),
        ha="center",
        va="top",
        fontsize=7,
        color="0.4",
    )
    ax.set_xlim(0.0, c.discharge)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("time after opening (s)")
    ax.set_ylabel("discharged mass (g)")
    ax.set_title(
        f"Silo, orifice D0 = {c.orifice / c.diameter:g} d = "
        f"{c.orifice / (c.coarse * c.diameter):g} parcels at h = {c.coarse:g} (seed {c.seed})",
        fontsize=10,
    )
    ax.legend(fontsize=7.5, loc="lower right")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def plot_levels(path: Path, case: SiloCase, snapshots: list[Snapshot]) -> None:
    """levels.png: the section of the particles by the vertical plane through the orifice's
    centre (y = width / 2), coloured by level, at each snapshot; the coarse level's shadow in
    the resolved region as outlines, the region dashed."""
    from .._optional import pyplot

    plt = pyplot()
    fig, axes = plt.subplots(
        1, len(snapshots), figsize=(3.8 * len(snapshots), 5.0), dpi=150, sharey=True, squeeze=False
    )
    top = max(
        float(np.max(lv["position"][:, 2] + lv["radius"], initial=0.0))
        for snap in snapshots
        for lv in snap.levels
    )
    for ax, snap in zip(axes[0], snapshots, strict=True):
        _section(ax, case, snap)
        ax.set_xlim(-1.0, case.width * 1e3 + 1.0)
        ax.set_ylim(-case.below * 1e3, top * 1e3 + 3.0)
        ax.set_aspect("equal")
        ax.set_xlabel("x (mm)")
        ax.set_title(snap.title, fontsize=9)
    axes[0][0].set_ylabel("z (mm)")
    cgs = max((snap.cg for snap in snapshots), key=len)
    handles = [
        plt.matplotlib.patches.Patch(color=COLOURS[k], label=f"level {k}: h = {h:g}")
        for k, h in enumerate(cgs)
    ]
    handles.append(
        plt.matplotlib.patches.Patch(
            facecolor="none", edgecolor="0.5", label="level 0 in the region (its shadow)"
        )
    )
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle(
        "Section by the vertical plane through the orifice, coloured by level", fontsize=11
    )
    fig.tight_layout(rect=(0, 0.07, 1, 0.97))
    fig.savefig(path)
    plt.close(fig)


def _section(ax: Any, case: SiloCase, snap: Snapshot) -> None:
    """One panel of plot_levels (mm)."""
    from matplotlib.collections import EllipseCollection
    from matplotlib.patches import Rectangle

    mm, yc = 1e3, 0.5 * case.width
    for k, lv in enumerate(snap.levels):
        dy = lv["position"][:, 1] - yc
        cut = np.abs(dy) < lv["radius"]
        r = np.sqrt(lv["radius"][cut] ** 2 - dy[cut] ** 2) * mm
        xz = lv["position"][cut][:, [0, 2]] * mm
        finest = lv["finest"][cut]
        styles = ((finest, COLOURS[k], "none", 2 + k), (~finest, "none", "0.6", 1))
        for sel, face, edge, z in styles:
            if np.any(sel):
                ax.add_collection(
                    EllipseCollection(
                        2 * r[sel],
                        2 * r[sel],
                        np.zeros(np.count_nonzero(sel)),
                        units="xy",
                        offsets=xz[sel],
                        offset_transform=ax.transData,
                        facecolors=face,
                        edgecolors=edge,
                        linewidths=0.4,
                        zorder=z,
                    )
                )
    w, d0, h = case.width * mm, case.orifice * mm, case.height * mm
    lo, hi = 0.5 * (w - d0), 0.5 * (w + d0)
    for xs, zs in (([0, lo], [0, 0]), ([hi, w], [0, 0]), ([0, 0], [0, h]), ([w, w], [0, h])):
        ax.plot(xs, zs, color="black", linewidth=2, zorder=5)
    for lo_r, hi_r in snap.regions:
        ax.add_patch(
            Rectangle(
                (lo_r[0] * mm, lo_r[2] * mm),
                (hi_r[0] - lo_r[0]) * mm,
                (hi_r[2] - lo_r[2]) * mm,
                fill=False,
                linestyle="--",
                edgecolor="0.2",
                linewidth=1,
                zorder=6,
            )
        )
    ax.axhspan(-case.below * mm, -0.5 * case.below * mm, color="0.92", zorder=0)
