"""The resolved reference of the silo demo (:mod:`grainscale.examples.silo_demo`), shipped as
``examples/data/silo_reference.json`` with its provenance, and how it was made.

The file holds one entry per case (``default``: the demo's case, ``quick``: its ``--quick``
case), each with the case's parameters (a reference applies only to the same case), the seeds,
the discharge rate W per seed and their mean, the discharged mass against time of one seed, its
particle count, the wall-clock and CPU time of one resolved run, and ``provenance``: a list of
what produced the entry (command, code version and commit, date, machine).

Made with (from the repository root; the exact commands are in the file's provenance)::

    python -m grainscale.examples.silo_reference run --quick --seeds 1 2 3
    python -m grainscale.examples.silo_reference from-study studies/mlcg_jam/results.json \\
        --commit b8c2bc729d5030afdb85bfb69dcbd316be84a197 --date 2026-12-06 \\
        --command "python -m grainscale.examples.mlcg_jam --seeds 1 2 3 4 5 6 ..." \\
        --rerun-seed 1

``from-study`` converts the resolved runs of studies/mlcg_jam (same case, six seeds) and reruns
one seed with this module's code, recording whether it reproduces the study's history exactly
and its timing; ``run`` runs the resolved case for the seeds given. Both write into the file
given by ``--file`` (default: the packaged one), replacing that case's entry.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

import grainscale as gs

PACKAGED = Path(__file__).resolve().parent / "data" / "silo_reference.json"


def load(name: str, case: Any, path: Path = PACKAGED) -> dict[str, Any] | None:
    """The reference entry ``name`` ("default" or "quick") of ``path`` if it was made for
    ``case`` (a silo_demo.SiloCase; the seed aside), else None."""
    if not path.is_file():
        return None
    entry = json.loads(path.read_text()).get("cases", {}).get(name)
    if entry is None or entry["case"] != _jsonable(case.comparable()):
        return None
    return dict(entry)


def _jsonable(value: Any) -> Any:
    return json.loads(json.dumps(value))


def code_version() -> dict[str, str]:
    """grainscale's version and, in a git checkout, the commit (with "+ uncommitted changes"
    when the tree differs from it)."""
    here = Path(__file__).resolve().parent
    out = {"version": gs.__version__, "commit": "unknown (not a git checkout)"}
    try:
        head = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=here, capture_output=True, text=True, check=True
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=here,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        out["commit"] = head + (" + uncommitted changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        pass
    return out


def _machine() -> str:
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "?"
    return (
        f"{platform.machine()}, {os.cpu_count()} cores, {platform.platform()}, python "
        f"{platform.python_version()}; load average {load} at the end"
    )


def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


_VERSION: dict[str, str] = {}  # code_version() when the command started


def _step(command: str, what: str, **extra: Any) -> dict[str, Any]:
    version = _VERSION or code_version()
    return {
        "what": what,
        "command": command,
        **version,
        "date": _now(),
        "machine": _machine(),
        **extra,
    }


def _rates(rates: Sequence[float]) -> dict[str, Any]:
    mean = float(np.mean(rates))
    scatter = float(np.std(rates, ddof=1) / mean) if len(rates) > 1 else None
    return {"rates": [float(r) for r in rates], "rate": mean, "scatter": scatter}


def run_entry(case: Any, seeds: Sequence[int], command: str) -> dict[str, Any]:
    """A reference entry from live resolved runs of ``case`` for ``seeds`` (the history and
    particle count of the first seed, the timing of each)."""
    from grainscale.examples import silo_demo

    runs = []
    for seed in seeds:
        r = silo_demo.run_single(dataclasses.replace(case, seed=seed), 1.0, print)
        print(
            f"  seed {seed}: W = {r.rate * 1e3:.3f} g/s, {r.wall_clock:.0f} s wall-clock, "
            f"{r.cpu_time:.0f} s CPU",
            flush=True,
        )
        runs.append(r)
    first = runs[0]
    return {
        "case": _jsonable(case.comparable()),
        "seeds": list(seeds),
        **_rates([r.rate for r in runs]),
        "history_seed": seeds[0],
        "history": first.history,
        "particles": first.particles[0],
        "timing": [_timing(seed, r) for seed, r in zip(seeds, runs, strict=True)],
        "provenance": [_step(command, f"resolved runs of seeds {list(seeds)}")],
    }


def _timing(seed: int, r: Any) -> dict[str, Any]:
    return {"seed": seed, "wall_clock": r.wall_clock, "cpu_time": r.cpu_time, "live": True}


def study_entry(
    results: Path, case: Any, commit: str, date: str, study_command: str, command: str
) -> dict[str, Any]:
    """A reference entry from the resolved runs of a studies/mlcg_jam results.json (made for
    ``case``; its history is of its first seed; its wall-clock a mean per seed)."""
    data = json.loads(Path(results).read_text())
    study_case = {k: v for k, v in data["case"].items() if k != "seed"}
    mine = _jsonable(case.comparable())
    differ = [k for k in mine if study_case.get(k) != mine[k]]
    if differ:
        raise ValueError(f"{results} was made for another case: {differ} differ")
    res, seeds = data["runs"]["resolved"], list(data["seeds"])
    entry = {
        "case": mine,
        "seeds": seeds,
        **_rates(res["rates"]),
        "history_seed": seeds[0],
        "history": res["history"],
        "particles": res["particles"],
        "timing": [
            {
                "seeds": seeds,
                "wall_clock": res["wall_clock"],
                "cpu_time": None,
                "live": False,
                "note": "mean per seed, two runs at a time on two cores",
            }
        ],
        "provenance": [
            {
                "what": f"studies/mlcg_jam resolved runs, seeds {seeds}",
                "command": study_command,
                "commit": commit,
                "date": date,
            },
            _step(command, f"converted from {results}"),
        ],
    }
    if "mlcg" in data["runs"]:  # the study's hierarchy over the same seeds, for context
        m = data["runs"]["mlcg"]
        entry["mlcg"] = {"seeds": seeds, **_rates(m["rates"]), "rate_ratio": m["rate_ratio"]}
    return entry


def rerun_check(entry: dict[str, Any], case: Any, seed: int, command: str) -> None:
    """Rerun the resolved case for ``seed`` (the entry's history seed) with this code; record
    its timing and whether it reproduces the entry's rate and history exactly."""
    from grainscale.examples import silo_demo

    r = silo_demo.run_single(dataclasses.replace(case, seed=seed), 1.0, print)
    k = entry["seeds"].index(seed)
    same = seed == entry["history_seed"] and np.array_equal(
        np.asarray(r.history), np.asarray(entry["history"])
    )
    entry["timing"].insert(0, _timing(seed, r))
    entry["provenance"].append(
        _step(
            command,
            f"resolved seed {seed} rerun with grainscale.examples.silo_demo",
            rate=r.rate,
            rate_recorded=entry["rates"][k],
            history_identical=bool(same),
        )
    )
    print(
        f"  seed {seed}: W = {r.rate * 1e3:.4f} g/s (recorded {entry['rates'][k] * 1e3:.4f}), "
        f"history identical: {same}; {r.wall_clock:.0f} s wall, {r.cpu_time:.0f} s CPU"
    )


def save(name: str, entry: dict[str, Any], path: Path) -> None:
    """Write ``entry`` as case ``name`` of the reference file ``path`` (others kept)."""
    data = json.loads(path.read_text()) if path.is_file() else {}
    data.setdefault(
        "description",
        "Resolved reference runs of the silo demo (grainscale.examples.silo_demo): discharge "
        "rate W (kg/s) per seed and their mean, discharged mass (kg) against time after the "
        "opening (s) of one seed, with provenance; made by grainscale.examples.silo_reference.",
    )
    data.setdefault("cases", {})[name] = entry
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1) + "\n")


def main(argv: Sequence[str] | None = None) -> int:
    from grainscale.examples import silo_demo

    parser = argparse.ArgumentParser(
        prog="python -m grainscale.examples.silo_reference", description=__doc__.split("\n\n")[0]
    )
    parser.add_argument("--file", type=Path, default=PACKAGED, help="reference file to update")
    sub = parser.add_subparsers(dest="how", required=True)
    live = sub.add_parser("run", help="run the resolved case for the seeds given")
    live.add_argument("--quick", action="store_true", help="the demo's --quick case")
    live.add_argument("--seeds", nargs="+", type=int, default=[1])
    study = sub.add_parser("from-study", help="convert a studies/mlcg_jam results.json")
    study.add_argument("results", type=Path)
    study.add_argument("--commit", required=True, help="commit the study ran at")
    study.add_argument("--date", required=True, help="date of the study's runs")
    study.add_argument("--command", required=True, help="the study's command")
    study.add_argument("--rerun-seed", type=int, default=None, help="rerun this seed as a check")
    args = parser.parse_args(argv)
    _VERSION.update(code_version())  # before the runs: the code that ran
    command = "python -m grainscale.examples.silo_reference " + " ".join(
        sys.argv[1:] if argv is None else argv
    )
    if args.how == "run":
        case = silo_demo.QUICK if args.quick else silo_demo.JAM
        name, entry = ("quick" if args.quick else "default"), run_entry(case, args.seeds, command)
    else:
        case, name = silo_demo.JAM, "default"
        entry = study_entry(args.results, case, args.commit, args.date, args.command, command)
        if args.rerun_seed is not None:
            rerun_check(entry, case, args.rerun_seed, command)
    save(name, entry, args.file)
    print(f"{args.file}: case {name!r}, W = {entry['rate'] * 1e3:.2f} g/s over {entry['seeds']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
