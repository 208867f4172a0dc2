"""Cross-check of the silo discharge rate: grainscale against LIGGGHTS 3.8 from the same bed.

Question: is the discharge rate's growth with the orifice diameter D0 (the free Beverloo
exponent of the silo study, studies/silo_discharge/NOTES.md) a property of the contact
physics, or something of grainscale's? Both codes discharge the same settled bed and the ratio
W(D0_a) / W(D0_b) is compared.

Per orifice D0 (mm, default 24, 40 and 64): grainscale fills the silo of the study
(``SiloCase`` with ``height_ratio`` 1.0 by default: a bed about as deep as the silo is wide, so
that half of it can drain at a nearly constant rate) by pouring and lets it settle, shutter
closed. The settled bed (positions, radii, velocities, spins) is written once and both codes
start from it with the orifice open and no shutter: cylinder (LIGGGHTS: ``zcylinder``
primitive), the annulus floor from the same binary STL, Hertz-Mindlin with tangential history
and EPSD rolling friction (LIGGGHTS ``rolling_friction epsd``), the study's material (walls of
the particle material), time step and skin. One known difference in the law: LIGGGHTS keeps the
EPSD rolling spring as accumulated (rolling_model_epsd.h), grainscale turns it with the contact
normal. Contact histories of the settled bed are not carried
over (LIGGGHTS cannot read them), in either code. Both codes run concurrently, one core each.

Discharged mass = initial mass - mass above the floor plane (LIGGGHTS ``mass(all,above)``, the
same sum in grainscale), sampled every ``--sample`` s; W = slope of a linear fit between
``--window`` fractions of the inventory (default 10-30 %). Each code's exponent between
successive orifices, ln(W_b / W_a) / ln(D0_b / D0_a), is printed with the ratio W_gs / W_lig.

Usage: python bench/python/silo_crosscheck.py [--orifices 24 40 64] [--seed 1]
                                              [--height-ratio 1.0] [--spring-rotation project]
                                              [--friction 0.5] [--rolling-friction 0.05]
Results: bench/results/silo_crosscheck.json (``--output`` to change).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from bench_common import (
    add_spring_rotation_option,
    ensure_liggghts,
    machine_info,
    parse_liggghts_log,
    single_thread_env,
)
from hopper_case import write_binary_stl, write_granular_data
from settle_case import liggghts_preamble

import grainscale as gs
from studies.silo_discharge import silo_beverloo, silo_case, silo_run

RESULTS = Path(__file__).resolve().parents[1] / "results" / "silo_crosscheck.json"


@dataclasses.dataclass
class Bed:
    """A settled bed and the silo it sits in (SI units)."""

    orifice: float
    params: gs.scaling.ParameterSet  # the silo's set (walls 0: cylinder, 1: floor, 2: shutter)
    position: np.ndarray
    radius: np.ndarray
    velocity: np.ndarray
    spin: np.ndarray
    mass: np.ndarray
    fill_seconds: float


def settled_bed(case: silo_case.SiloCase, orifice: float, seed: int) -> Bed:
    """Pour and settle the silo of ``case`` with grainscale, shutter closed."""
    t0 = time.perf_counter()
    setup = silo_run.silo_setup(case, orifice, seed)
    sim = gs.scaling.build_simulation(setup.params, quiet=True)
    notes = silo_run.pour_and_settle(sim, case, setup)
    for note in notes:
        print(f"  note: {note}", flush=True)
    with sim.particles(writable=False) as p:
        arrays = [np.array(a) for a in (p.position, p.radius, p.velocity, p.angular_velocity)]
        mass = np.array(p.mass)
    return Bed(orifice, setup.params, *arrays, mass, time.perf_counter() - t0)


def sample_steps(bed: Bed, sample: float) -> int:
    return max(1, round(sample / float(bed.params.time_step)))


def run_steps(
    bed: Bed, case: silo_case.SiloCase, window: tuple[float, float], sample: float
) -> int:
    """Steps long enough to pass the window's upper end at 0.75 x Beverloo's rate (C = 0.58,
    k = 1.5, rho_b = 0.6 rho_p): the study's rates are 0.82-0.95 x that."""
    w = float(silo_beverloo.beverloo_rate(bed.orifice, case.diameter, 0.6 * case.density))
    seconds = 0.15 + (window[1] + 0.05) * bed.mass.sum() / (0.75 * w)
    n = sample_steps(bed, sample)
    return n * math.ceil(seconds / float(bed.params.time_step) / n)


# ---------------------------------------------------------------------------------------------
# LIGGGHTS


def write_liggghts_case(
    workdir: Path, bed: Bed, case: silo_case.SiloCase, steps: int, every: int
) -> str:
    """Data file, floor STL and input script in ``workdir``; returns the script's name."""
    params = bed.params
    floor = params.walls[1]
    write_binary_stl(workdir / "floor.stl", floor.vertices, floor.triangles, "silo floor")
    density = bed.mass / (4.0 / 3.0 * math.pi * bed.radius**3)
    title = f"grainscale silo cross-check, D0 = {bed.orifice!r} m, N = {len(bed.position)}"
    box = (params.domain.lo, params.domain.hi)
    write_granular_data(
        workdir / "bed.data", title, box, 2 * bed.radius, density, bed.position, bed.velocity,
        bed.spin,
    )  # fmt: skip
    law = params.contact
    rolling = law.rolling
    assert rolling is not None
    mu_r, eta_r = rolling.rolling_friction, rolling.rolling_damping
    silo_radius = params.walls[0].radius
    models = "model hertz tangential history" + (" rolling_friction epsd" if mu_r > 0 else "")
    rolling_lines = (
        f"fix m5 all property/global coefficientRollingFriction peratomtypepair 1 {mu_r!r}\n"
        f"fix m6 all property/global coefficientRollingViscousDamping peratomtypepair 1 {eta_r!r}\n"
        if mu_r > 0
        else ""
    )
    preamble = liggghts_preamble(title, "../bed.data", params.skin)
    script = f"""\
{preamble}
fix m1 all property/global youngsModulus peratomtype {case.youngs_modulus!r}
fix m2 all property/global poissonsRatio peratomtype {case.poisson_ratio!r}
fix m3 all property/global coefficientRestitution peratomtypepair 1 {law.restitution!r}
fix m4 all property/global coefficientFriction peratomtypepair 1 {law.friction!r}
{rolling_lines}
pair_style      gran {models}
pair_coeff      * *
timestep        {float(params.time_step)!r}

fix gravi all gravity {silo_beverloo.G!r} vector 0.0 0.0 -1.0
fix floor all mesh/surface file ../floor.stl type 1
fix floorwall all wall/gran {models} mesh n_meshes 1 meshes floor
fix cylinder all wall/gran {models} primitive type 1 zcylinder {silo_radius!r} 0.0 0.0
fix integr all nve/sphere

region          above block INF INF INF INF 0.0 INF units box
variable        mabove equal mass(all,above)
thermo_style    custom step atoms v_mabove
thermo_modify   lost ignore norm no format float %.10g
thermo          {every}
run             {steps}
"""
    (workdir / "in.silo").write_text(script)
    return "in.silo"


def start_liggghts(exe: str, workdir: Path, script: str) -> subprocess.Popen[bytes]:
    rundir = workdir / "liggghts"
    rundir.mkdir()
    out = (rundir / "stdout.txt").open("wb")
    return subprocess.Popen(
        [exe, "-in", f"../{script}", "-log", "log.liggghts"],
        cwd=rundir,
        env=single_thread_env(),
        stdout=out,
        stderr=subprocess.STDOUT,
    )


def liggghts_history(workdir: Path, dt: float, m0: float) -> tuple[np.ndarray, np.ndarray, float]:
    """(time, discharged mass, loop seconds) from the LIGGGHTS log."""
    log = parse_liggghts_log((workdir / "liggghts" / "log.liggghts").read_text(errors="replace"))
    steps = np.array([row["Step"] for row in log["thermo"]])
    above = np.array([row["mabove"] for row in log["thermo"]])
    return steps * dt, m0 - above, log["loop_seconds"]


# ---------------------------------------------------------------------------------------------
# grainscale


def grainscale_history(
    bed: Bed, spring_rotation: str, steps: int, every: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """(time, discharged mass, run seconds) of grainscale from the bed, orifice open."""
    glass = bed.params.walls[0].material
    law = dataclasses.replace(bed.params.contact, spring_rotation=spring_rotation)
    params = dataclasses.replace(
        bed.params,
        contact=law,
        walls=bed.params.walls[:2],  # no shutter
        insertions=(),
        particles=(
            gs.scaling.Particles(
                position=bed.position,
                radius=bed.radius,
                material=glass,
                velocity=bed.velocity,
                angular_velocity=bed.spin,
            ),
        ),
    )
    sim = gs.scaling.build_simulation(params, quiet=True)
    m0 = float(bed.mass.sum())
    times, discharged, seconds = [0.0], [0.0], 0.0
    for _ in range(steps // every):
        t0 = time.perf_counter()
        sim.run(steps=every)
        seconds += time.perf_counter() - t0
        with sim.particles(writable=False) as p:
            above = float(np.asarray(p.mass)[np.asarray(p.position)[:, 2] > 0.0].sum())
        times.append(float(sim.time))
        discharged.append(m0 - above)
    return np.array(times), np.array(discharged), seconds


# ---------------------------------------------------------------------------------------------
# driver


def exponents(orifices: list[float], rates: list[float]) -> list[float]:
    return [
        math.log(rates[i + 1] / rates[i]) / math.log(orifices[i + 1] / orifices[i])
        for i in range(len(rates) - 1)
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--orifices", type=float, nargs="+", default=[24.0, 40.0, 64.0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--height-ratio", type=float, default=1.0)
    parser.add_argument("--window", type=float, nargs=2, default=[0.1, 0.3])
    parser.add_argument("--sample", type=float, default=0.005, help="s between samples")
    parser.add_argument("--output", type=Path, default=RESULTS, help="results JSON")
    parser.add_argument("--friction", type=float, default=silo_case.SiloCase.friction)
    parser.add_argument(
        "--rolling-friction", type=float, default=silo_case.SiloCase.rolling_friction
    )
    add_spring_rotation_option(parser, "project")
    args = parser.parse_args(argv)
    if not 0 <= args.window[0] < args.window[1] < 1:
        raise SystemExit(f"--window must be two fractions 0 <= a < b < 1, got {args.window}")
    exe = ensure_liggghts()
    case = silo_case.SiloCase(
        height_ratio=args.height_ratio,
        constant_head=False,
        friction=args.friction,
        rolling_friction=args.rolling_friction,
    )
    window = (args.window[0], args.window[1])
    runs: list[dict[str, Any]] = []
    for mm in sorted(args.orifices):
        orifice = mm * 1e-3
        bed = settled_bed(case, orifice, args.seed)
        m0 = float(bed.mass.sum())
        dt = float(bed.params.time_step)
        every, steps = sample_steps(bed, args.sample), run_steps(bed, case, window, args.sample)
        print(
            f"D0 = {mm:g} mm: {len(bed.position)} particles, {m0:.4g} kg settled in "
            f"{bed.fill_seconds:.0f} s; both codes run {steps} steps ({steps * dt:.3g} s)",
            flush=True,
        )
        workdir = Path(tempfile.mkdtemp(prefix=f"silo_x_{mm:g}_"))
        try:
            script = write_liggghts_case(workdir, bed, case, steps, every)
            proc = start_liggghts(exe, workdir, script)
            t_gs, m_gs, s_gs = grainscale_history(bed, args.spring_rotation, steps, every)
            if proc.wait() != 0:
                logs = [workdir / "liggghts" / name for name in ("stdout.txt", "log.liggghts")]
                out = "\n".join(f.read_text(errors="replace")[-2000:] for f in logs if f.exists())
                raise SystemExit(f"LIGGGHTS failed (exit {proc.returncode}):\n{out}")
            t_lg, m_lg, s_lg = liggghts_history(workdir, dt, m0)
        finally:
            shutil.rmtree(workdir, ignore_errors=True)
        entry: dict[str, Any] = {"orifice_mm": mm, "particles": len(bed.position), "mass": m0}
        for code, t, m, sec in (("grainscale", t_gs, m_gs, s_gs), ("liggghts", t_lg, m_lg, s_lg)):
            w, w1, w2, r2 = silo_run.measure_rate(t, m, m0, window)
            entry[code] = {"W": w, "W_first_half": w1, "W_second_half": w2, "r_squared": r2}
            entry[code] |= {"seconds": sec, "discharged_at_end": float(m[-1] / m0)}
        ratio = entry["grainscale"]["W"] / entry["liggghts"]["W"]
        entry["ratio"] = ratio
        runs.append(entry)
        print(
            f"  W = {entry['grainscale']['W']:.4g} kg/s (grainscale, {s_gs:.0f} s), "
            f"{entry['liggghts']['W']:.4g} kg/s (LIGGGHTS, {s_lg:.0f} s): ratio {ratio:.4f}",
            flush=True,
        )
    d = [r["orifice_mm"] for r in runs]
    codes = ("grainscale", "liggghts")
    table = {code: exponents(d, [r[code]["W"] for r in runs]) for code in codes}
    for code, values in table.items():
        print(f"local exponents {code}: " + ", ".join(f"{v:.3f}" for v in values))
    result = {
        "case": dataclasses.asdict(case),
        "seed": args.seed,
        "window": window,
        "spring_rotation": args.spring_rotation,
        "runs": runs,
        "local_exponents": table,
        "machine": machine_info(),
        "command": " ".join([Path(sys.argv[0]).name, *(argv or sys.argv[1:])]),
    }
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(result, indent=1, default=float) + "\n")
    print(f"results: {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
