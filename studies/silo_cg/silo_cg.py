"""Coarse-grained silo discharge against the resolved study (validation/CASES.md D1, check ii).

Run it with ``python -m studies.silo_cg.silo_cg --output out/silo_cg``. The resolved study
of ``studies.silo_discharge.silo_discharge`` (its results.json, ``--reference``) fixes everything:
the SiloCase (silo and bed sizing, material, fill, constant head, measuring window) is read
from it, the CG runs only set ``SiloCase.cg = h``, so the silo, the bed and the window are
those of the resolved runs while the particles are parcels h d across whose parameters come
from ``grainscale.scaling.scale(reference, h, scheme="cg")`` (time step and skin x h, material,
restitution, friction and rolling parameters unchanged). Beverloo's law with k acting on the
parcel diameter predicts the coarse-grain deficit (CASES D1 ii, from W = C rho_b sqrt(g)
(D0 - k d)^(5/2); Beverloo, Leniger & van de Velde 1961)

    W_CG / W_ref = ((D0/d - k h) / (D0/d - k))^(5/2),

with k (and C) fitted to the resolved runs with the exponent 2.5. Pass (CASES D1): for h = 2 at
D0 / (h d) = 5-8 the mean measured ratio over >= 3 seeds is within +/- 0.05 of the prediction.

Default runs: h = 2 at D0 = 40, 52, 64 mm and h = 3 at D0 = 52, 64 mm, seeds 1-3. Each run is
stored in ``<output>/runs/`` (summary JSON and outlet history CSV), so studies can be extended
(``--cg``, ``--orifices``, ``--first-seed``) and analysed again without simulating
(``--reanalyse``); runs made with another SiloCase than the reference's are refused.

Written to the output directory: report.md, ratio.png (measured vs predicted ratio, W vs D0),
results.json (every number) and runs/.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from studies.silo_cg.silo_cg_compare import (
    TOLERANCE,
    Reference,
    broken_similarities,
    compare,
    fit_cg,
    load_reference,
)
from studies.silo_cg.silo_cg_report import plot_ratios, report_markdown
from studies.silo_discharge import silo_case, silo_report, silo_run
from studies.silo_discharge import silo_discharge as sd

DEFAULT_REFERENCE = Path("studies/silo_discharge/results.json")
#: h -> orifices (mm): D0 / (h d) = 5, 6.5, 8 at h = 2 (the gated range of CASES D1 ii)
DEFAULT_RUNS: dict[float, tuple[float, ...]] = {2.0: (40.0, 52.0, 64.0), 3.0: (52.0, 64.0)}


# ------------------------------------------------------------------------------------------
# runs
# ------------------------------------------------------------------------------------------


def run_name(h: float, orifice: float, seed: int) -> str:
    return f"h{h:g}_D{orifice * 1e3:g}_s{seed}"


def save_run(directory: Path, case: silo_case.SiloCase, run: silo_run.DischargeResult) -> None:
    """runs/<name>.json (the run's SiloCase and summary) and runs/<name>.csv (its history)."""
    directory.mkdir(parents=True, exist_ok=True)
    name = run_name(run.cg, run.orifice, run.seed)
    data = {"case": dataclasses.asdict(case), "run": run.summary()}
    (directory / f"{name}.json").write_text(
        json.dumps(silo_report.json_ready(data), indent=2) + "\n"
    )
    sd.save_history(directory / f"{name}.csv", run)


def load_runs(directory: Path, reference: Reference) -> list[silo_run.DischargeResult]:
    """Every run stored in ``directory``; ValueError for a run whose SiloCase differs from the
    reference's in anything but cg."""
    runs = []
    for path in sorted(directory.glob("*.json")):
        data = json.loads(path.read_text())
        case = silo_case.SiloCase(**data["case"])
        differ = [
            f.name
            for f in dataclasses.fields(silo_case.SiloCase)
            if f.name != "cg" and getattr(case, f.name) != getattr(reference.case, f.name)
        ]
        if differ:
            raise ValueError(
                f"silo_cg: run {path} was made with another SiloCase than the reference "
                f"{reference.path} (differs in {', '.join(differ)}); use another --output"
            )
        runs.append(sd.load_run(case, data["run"], path.with_suffix(".csv")))
    return sorted(runs, key=lambda r: (r.cg, r.orifice, r.seed))


# ------------------------------------------------------------------------------------------
# the study
# ------------------------------------------------------------------------------------------


def run_study(
    output: str | Path,
    reference: Reference,
    runs: dict[float, Sequence[float]] | None = None,
    seeds: Sequence[int] = (1, 2, 3),
    jobs: int = 1,
    verbose: bool = True,
) -> dict[str, Any]:
    """Run the CG silos ``runs`` (h -> orifices in m; default DEFAULT_RUNS) for every seed,
    store them in ``output``/runs and analyse every run stored there."""
    out = Path(output)
    plan = runs if runs is not None else {h: [v * 1e-3 for v in d] for h, d in DEFAULT_RUNS.items()}
    tasks = []
    for h, orifices in plan.items():
        case = dataclasses.replace(reference.case, cg=float(h))
        for d0 in sorted(orifices, reverse=True):
            reference.index(d0)  # refuse orifices without a resolved rate before running
            tasks += [(case, float(d0), int(s), None) for s in seeds]
    if jobs < 1:
        raise ValueError(f"silo_cg.jobs must be at least 1, got {jobs}")
    say = silo_run.print_flush if verbose else (lambda _s: None)
    say(
        f"grainscale CG silo discharge (CASES D1 ii) against {reference.path}: "
        f"{len(tasks)} runs on {jobs} process(es); output in {out}"
    )
    t0 = time.perf_counter()
    done = silo_run.run_many(tasks, jobs, verbose)
    say(f"{len(done)} runs in {time.perf_counter() - t0:.0f} s")
    cases = {c.cg: c for c, *_ in tasks}
    for r in done:
        save_run(out / "runs", cases[r.cg], r)
    return analyse(out, reference, verbose)


def analyse(output: str | Path, reference: Reference, verbose: bool = True) -> dict[str, Any]:
    """Compare every run in ``output``/runs with the reference; write report.md, ratio.png and
    results.json; return the results."""
    out = Path(output)
    runs = load_runs(out / "runs", reference)
    if not runs:
        raise ValueError(f"silo_cg: no runs in {out / 'runs'}")
    comparisons = compare(reference, runs)
    hs = sorted({c.h for c in comparisons})
    fits = {h: fit_cg(reference, comparisons, h) for h in hs}
    broken = {h: broken_similarities(reference, h, comparisons[0].orifice) for h in hs}
    gated = [c for c in comparisons if c.gated]
    result = {
        "reference": str(reference.path),
        "case": dataclasses.asdict(reference.case),
        "reference_fit": {"c": reference.c, "k": reference.k, "exponent": 2.5},
        "tolerance": TOLERANCE,
        "passed": bool(gated) and all(c.passed for c in gated),
        "comparisons": [dataclasses.asdict(c) for c in comparisons],
        "cg_fits": {
            f"{h:g}": None if f is None else dataclasses.asdict(f) for h, f in fits.items()
        },
        "broken_similarities": {f"{h:g}": b for h, b in broken.items()},
        "runs": [dict(r.summary(), name=run_name(r.cg, r.orifice, r.seed)) for r in runs],
    }
    (out / "results.json").write_text(json.dumps(silo_report.json_ready(result), indent=2) + "\n")
    plot_ratios(out / "ratio.png", reference, comparisons)
    text = report_markdown(reference, comparisons, fits, broken, runs, result["passed"])
    (out / "report.md").write_text(text)
    if verbose:
        silo_run.print_flush(text)
    return result


# ------------------------------------------------------------------------------------------
# command line
# ------------------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m studies.silo_cg.silo_cg",
        description="Coarse-grained silo discharge against a resolved silo_discharge study "
        "(validation/CASES.md D1 ii). Lengths in mm.",
    )
    parser.add_argument(
        "--output", default="out/silo_cg", help="output directory (default: %(default)s)"
    )
    parser.add_argument(
        "--reference",
        default=str(DEFAULT_REFERENCE),
        help="results.json of the resolved study (default: %(default)s)",
    )
    parser.add_argument(
        "--cg",
        type=float,
        nargs="+",
        default=None,
        metavar="H",
        help="coarse-graining ratios (default: "
        + ", ".join(
            f"{h:g} at D0 = {' '.join(f'{v:g}' for v in d)}" for h, d in DEFAULT_RUNS.items()
        )
        + ")",
    )
    parser.add_argument(
        "--orifices",
        type=float,
        nargs="+",
        default=None,
        metavar="MM",
        help="orifice diameters in mm for every --cg (default: as above; each must be in the "
        "reference)",
    )
    parser.add_argument("--seeds", type=int, default=3, help="seeds per run (default 3)")
    parser.add_argument(
        "--first-seed", type=int, default=1, help="seeds are first-seed, ... (default 1)"
    )
    parser.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument(
        "--reanalyse",
        action="store_true",
        help="no simulation: compare the runs stored in --output with the reference again",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        reference = load_reference(args.reference)
        if args.reanalyse:
            analyse(args.output, reference)
            return 0
        if args.seeds < 1:
            raise ValueError(f"--seeds must be at least 1, got {args.seeds}")
        hs = args.cg if args.cg is not None else list(DEFAULT_RUNS)
        plan: dict[float, Sequence[float]] = {}
        for h in hs:
            mm = args.orifices if args.orifices is not None else DEFAULT_RUNS.get(h)
            if mm is None:
                raise ValueError(f"--orifices must be given for --cg {h:g} (no default)")
            plan[h] = [v * 1e-3 for v in mm]
        seeds = range(args.first_seed, args.first_seed + args.seeds)
        run_study(args.output, reference, plan, seeds=seeds, jobs=args.jobs)
    except ValueError as err:
        parser.error(str(err))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
