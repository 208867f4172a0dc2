"""Multi-level coarse graining at industrial scale (issue 28): a silo 0.40 m across whose bed,
resolved, would hold about 10^7 spheres of 2 mm, discharging for 10 s through a 20 mm orifice.

Run the whole study on both cores with::

    mpirun -np 2 python -m studies.silo_industrial.silo_industrial --runs mlcg --output out/ind
    mpirun -np 2 python -m studies.silo_industrial.silo_industrial --runs cg --output out/ind
    python -m studies.silo_industrial.silo_industrial --runs resolved_0 --output out/ind &
    python -m studies.silo_industrial.silo_industrial --runs resolved_1 --output out/ind
    python -m studies.silo_industrial.silo_industrial --report --output out/ind

Runs (each written to ``<output>/runs/<name>.json``; the report merges what is there):

* ``mlcg``: the hierarchy (``SiloCase.ratios``, default h = 8 -> 4 -> 2 -> 1) nested around the
  orifice by :func:`grainscale.nested_levels`, every level decomposed over the ranks and
  balancing its own work; fill, settle, open, discharge; a checkpoint half-way through the
  discharge and a restart from it that must continue bit-identically;
* ``cg``: pure coarse graining of the same silo at the coarsest ratio (the orifice is then
  D0 / (h d) = 1.25 parcels across: it must miss);
* ``resolved_0``, ``resolved_1``: fully resolved silos of the same orifice, particles and
  material, ``SiloCase.reference_widths`` x D0 across (narrow enough to run here): the rate
  must no longer depend on the width.

``--report`` writes ``results.json`` (top-level keys ``resolved_equivalent_particles``,
``wall_clock_s``, ``discharge_duration_s``, ``W_kg_s``, ``W_reference_kg_s``,
``W_pure_cg_kg_s``, ``mass_unaccounted_kg``, ``ranks``, then every run), ``report.md`` and
``discharge.png``. ``--vtk`` writes the hierarchy's levels for ParaView (``<output>/vtk``).
``--quick``: a small silo (the reduced test, tests/studies/test_silo_industrial.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from studies.silo_industrial import silo_report
from studies.silo_industrial.silo_case import QUICK, SiloCase, describe
from studies.silo_industrial.silo_runs import nan_to_none, run_hierarchy, run_single

RUNS = ("mlcg", "cg", "resolved_0", "resolved_1")


def _world() -> Any:
    from mpi4py import MPI

    return MPI.COMM_WORLD


def run(case: SiloCase, name: str, output: Path, vtk: bool = False) -> dict[str, Any]:
    """One run of the study (collective under mpirun), written by rank 0 to
    ``output/runs/<name>.json``; returns its dict."""
    comm = _world()
    rank0 = comm.rank == 0
    output.mkdir(parents=True, exist_ok=True)
    (output / "runs").mkdir(exist_ok=True)

    def say(text: str) -> None:
        if rank0:
            print(text, flush=True)

    say(f"running {name} on {comm.size} rank(s) ...")
    if name == "mlcg":
        result = run_hierarchy(case, comm, output, say, vtk)
    elif name == "cg":
        result = run_single(case, case.ratios[0], comm, say)
    elif name.startswith("resolved_"):
        ref = case.references()[int(name.split("_")[1])]
        result = run_single(ref, 1.0, comm, say)
        result["case"] = describe(ref)
    else:
        raise ValueError(f"run must be one of {RUNS}, got {name!r}")
    result["name"] = name
    if rank0:
        path = output / "runs" / f"{name}.json"
        path.write_text(json.dumps(nan_to_none(result), indent=1, default=float))
    say(f"  {name}: W = {result['rate'] * 1e3:.2f} g/s, {result['wall_clock_s']:.0f} s")
    return result


def report(case: SiloCase, output: Path) -> dict[str, Any]:
    """Merges the runs found in ``output/runs`` into results.json, report.md, discharge.png."""
    runs = {}
    for name in RUNS:
        path = output / "runs" / f"{name}.json"
        if path.exists():
            runs[name] = json.loads(path.read_text())
    results = silo_report.summarize(describe(case), runs)
    (output / "results.json").write_text(json.dumps(nan_to_none(results), indent=1))
    (output / "report.md").write_text(silo_report.markdown(results))
    silo_report.plot(output / "discharge.png", runs)
    return results


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m studies.silo_industrial.silo_industrial",
        description=(__doc__ or "").split("\n\n")[0],
    )
    parser.add_argument("--output", type=Path, default=Path("out/silo_industrial"))
    parser.add_argument("--runs", nargs="*", default=[], choices=RUNS)
    parser.add_argument("--report", action="store_true", help="merge the runs into the report")
    parser.add_argument("--quick", action="store_true", help="a small silo, short times")
    parser.add_argument("--vtk", action="store_true", help="VTK output of the hierarchy")
    parser.add_argument(
        "--set", nargs="*", default=[], metavar="NAME=VALUE", help="override SiloCase fields"
    )
    args = parser.parse_args(argv)
    case = QUICK if args.quick else SiloCase()
    for item in args.set:
        key, value = item.split("=", 1)
        case = dataclasses.replace(case, **{key: type(getattr(case, key))(value)})
    for name in args.runs:
        run(case, name, args.output, args.vtk)
    if args.report and _world().rank == 0:
        print(silo_report.markdown(report(case, args.output)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
