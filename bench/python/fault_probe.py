"""Fault probe (issue 25): bad input and faults tried through the public API, as a new user would,
each in a subprocess of its own, and what grainscale made of each.

Every case (fault_cases*.py: constructors and their parameters, particles, walls, insertion,
runs, output, checkpoints, STL files, particle views, run guards, hierarchies, MPI on 2 ranks)
is classified:

- clear: raised ValueError / TypeError / RuntimeError (or the case's documented type) whose
  message contains what the case expects (the parameter or thing, and the offending value), or,
  where a warning is the documented response, issued the expected warning;
- unclear: raised, but the message lacks what was expected, or a raw exception (numpy, h5py,
  KeyError, AttributeError, ...);
- crash: the process died by a signal or without a Python result (segfault, abort);
- hang: no end within the timeout (default 60 s);
- silent: no error and no warning where one was owed, or a wrong result.

A case whose own set-up failed (before the fault) is a probe error, listed but not counted.

    PYTHONPATH=python .venv/bin/python bench/python/fault_probe.py            # all, 2 at a time
    ... fault_probe.py --list | --case NAME [--case NAME ...] | --output results.json
"""

from __future__ import annotations

import argparse
import concurrent.futures
import datetime as dt
import fnmatch
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_common import machine_info, single_thread_env  # noqa: E402 - puts the root on the path

RESULT = "fault_probe_result_rank{}.json"  # in the case's work directory, one per rank
OUTCOMES = ("clear", "unclear", "crash", "hang", "silent")
SEVERITY = {"clear": 0, "unclear": 1, "silent": 2, "hang": 3, "crash": 4, "probe_error": 5}
CRASH_TEXT = re.compile(r"exited on signal|Segmentation fault|core dumped|Aborted|signal \d+ \(")
DEFAULT_OUTPUT = Path(tempfile.gettempdir()) / "grainscale_fault_probe.json"


def load_cases() -> dict[str, Any]:
    """The case table (importing the case modules registers their cases)."""
    import fault_cases
    import fault_cases_checkpoints  # noqa: F401
    import fault_cases_run  # noqa: F401
    import fault_cases_setup  # noqa: F401

    order = {g: k for k, g in enumerate(fault_cases.GROUPS)}
    ranked = sorted(fault_cases.CASES.values(), key=lambda c: order.get(c.group, len(order)))
    return {c.name: c for c in ranked}


# ---------------------------------------------------------------------------------------------
# the worker: one case, in this process (one rank of it under mpirun)


def worker(name: str, work: Path) -> int:
    """Runs case ``name`` and writes its result to a file in ``work`` (one per rank)."""
    import warnings

    rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")))
    record: dict[str, Any] = {"rank": rank, "entered": False, "raised": None, "mro": []}
    record |= {"message": "", "warnings": [], "seconds": 0.0}
    out = work / RESULT.format(rank)
    try:
        cases = load_cases()
        from fault_cases import Probe
    except BaseException as err:  # grainscale not importable (being rebuilt?)
        record["message"] = f"import failed: {type(err).__name__}: {err}"
        out.write_text(json.dumps(record))
        return 3
    c = cases[name]
    error: BaseException | None = None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        probe = Probe(work, caught)
        start = time.perf_counter()
        try:
            note = c.run(probe)
            if note:
                record["note"] = str(note)
        except BaseException as err:
            error = err
            if not probe.entered:
                record["trace"] = traceback.format_exc(limit=-4)
        record["seconds"] = time.perf_counter() - start
        record["warnings"] = [
            [w.category.__name__, str(w.message)] for w in caught[probe.warnings_from :]
        ]
    record["entered"] = probe.entered
    if error is not None:
        record["raised"] = type(error).__name__
        record["mro"] = [k.__name__ for k in type(error).__mro__]
        record["message"] = str(error)
    out.write_text(json.dumps(record))
    if c.uncaught and error is not None and record["raised"] not in ("Silent", "Fine"):
        raise error  # as the user's script would end
    return 0


# ---------------------------------------------------------------------------------------------
# the parent: subprocesses, timeouts, classification


def matches(c: Any, text: str) -> bool:
    low = text.lower()
    found = all(any(alt.lower() in low for alt in item.split("|")) for item in c.expect)
    return found and not any(r.lower() in low for r in c.reject)


def judge_rank(c: Any, r: dict[str, Any]) -> tuple[str, str]:
    """Outcome and what happened, for one rank's result."""
    raised, message = r["raised"], r["message"]
    warned = [f"{cat}: {text}" for cat, text in r["warnings"]]
    if raised == "Silent":
        return "silent", message + (f" [warnings: {' | '.join(warned)}]" if warned else "")
    if raised == "Fine":
        return "clear", message
    if raised is not None:
        ok_type = any(t in r["mro"] for t in c.types)
        outcome = "clear" if ok_type and matches(c, message) else "unclear"
        return outcome, f"{raised}: {message}"
    if c.response in ("warning", "either"):
        for cat, text in r["warnings"]:
            if matches(c, text):
                return "clear", f"{cat}: {text}"
    said = f"; warnings: {' | '.join(warned)}" if warned else ", no warning"
    return "silent", "no error" + said + (f" ({r['note']})" if r.get("note") else "")


def judge(
    c: Any, results: list[dict[str, Any]], rc: int, timed_out: float | None, stderr: str
) -> tuple[str, str]:
    """Outcome and what happened, for the whole case (every rank); ``timed_out``: the limit (s)
    the case exceeded, None if it ended."""
    tail = " / ".join(stderr.strip().splitlines()[-3:])
    if timed_out is not None:
        told = "; ".join(f"rank {r['rank']}: {judge_rank(c, r)[1]}" for r in results)
        ended = f"; {len(results)} of {c.ranks} rank(s) had ended" if c.ranks > 1 else ""
        return "hang", f"no end within {timed_out:g} s{ended}" + (f" ({told})" if told else "")
    if rc < 0:
        return "crash", f"killed by {signal.Signals(-rc).name}: {tail}"
    if c.ranks > 1 and rc != 0 and CRASH_TEXT.search(stderr) and not c.uncaught:
        return "crash", f"mpirun exit code {rc}: {tail}"
    if not results:
        return "crash", f"exit code {rc} without a result: {tail}"
    if any(r["message"].startswith("import failed") and not r["entered"] for r in results):
        return "probe_error", results[0]["message"]
    if any(not r["entered"] for r in results):
        bad = next(r for r in results if not r["entered"])
        return "probe_error", f"set-up failed: {bad['raised']}: {bad['message']}"
    if len(results) < c.ranks and not c.uncaught:
        return "crash", f"{c.ranks - len(results)} rank(s) ended without a result: {tail}"
    verdicts = [judge_rank(c, r) for r in sorted(results, key=lambda r: r["rank"])]
    worst = max(verdicts, key=lambda v: SEVERITY[v[0]])[0]
    if c.ranks == 1:
        return verdicts[0]
    missing = c.ranks - len(results)
    text = " || ".join(f"rank {r['rank']}: {v[1]}" for r, v in zip(results, verdicts, strict=True))
    if missing:
        text += f" || {missing} rank(s) ended by mpirun (exit code {rc})"
    return worst, text


def mpirun() -> str | None:
    return shutil.which("mpirun")


def kill_group(proc: subprocess.Popen[str]) -> None:
    """Ends the case's process group (started in a session of its own): TERM, then KILL."""
    for sig, wait in ((signal.SIGTERM, 3.0), (signal.SIGKILL, 10.0)):
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            return
        try:
            proc.wait(timeout=wait)
            return
        except subprocess.TimeoutExpired:
            continue


def run_case(c: Any, timeout: float, env: dict[str, str]) -> dict[str, Any]:
    """Runs one case in a subprocess (under mpirun for an MPI case); its result record."""
    limit = c.timeout if c.timeout is not None else timeout
    record: dict[str, Any] = {"name": c.name, "group": c.group, "what": c.what, "ranks": c.ranks}
    # the case's name stays out of the path: messages that name the file must not match by it
    work = Path(tempfile.mkdtemp(prefix="grainscale_fault_"))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", c.name, "--work", str(work)]
    if c.ranks > 1:
        launcher = mpirun()
        if launcher is None:
            shutil.rmtree(work, ignore_errors=True)
            return record | {"outcome": "probe_error", "detail": "mpirun not found", "seconds": 0}
        cmd = [launcher, "-np", str(c.ranks), "--oversubscribe", *cmd]
    start = time.perf_counter()
    proc = subprocess.Popen(
        cmd,
        cwd=work,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    try:
        out, err = proc.communicate(timeout=limit)
        timed_out: float | None = None
    except subprocess.TimeoutExpired:
        kill_group(proc)
        out, err = proc.communicate()
        timed_out = limit
    results = [json.loads(p.read_text()) for p in sorted(work.glob(RESULT.format("*")))]
    shutil.rmtree(work, ignore_errors=True)
    outcome, detail = judge(c, results, proc.returncode, timed_out, err)
    return record | {
        "outcome": outcome,
        "detail": detail,
        "seconds": round(time.perf_counter() - start, 2),
        "exit_code": proc.returncode,
        "expect": list(c.expect),
        "response": c.response,
        "results": results,
        "stdout_tail": out[-1000:],
        "stderr_tail": err[-2000:],
    }


def run_all(cases: list[Any], jobs: int, timeout: float) -> list[dict[str, Any]]:
    """Serial cases ``jobs`` at a time, then the MPI cases one at a time; a line per case."""
    env = single_thread_env()
    env["CI"] = "1"  # no progress bars
    serial = [c for c in cases if c.ranks == 1]
    parallel = [c for c in cases if c.ranks > 1]
    done: list[dict[str, Any]] = []

    def report(res: dict[str, Any]) -> None:
        done.append(res)
        print(
            f"[{len(done):3d}/{len(cases)}] {res['outcome']:<11s} {res['name']} "
            f"({res['seconds']:.1f} s)",
            flush=True,
        )

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        for fut in concurrent.futures.as_completed(
            [pool.submit(run_case, c, timeout, env) for c in serial]
        ):
            report(fut.result())
    for c in parallel:
        report(run_case(c, timeout, env))
    order = {c.name: k for k, c in enumerate(cases)}
    return sorted(done, key=lambda r: order[r["name"]])


# ---------------------------------------------------------------------------------------------
# report


def totals(results: list[dict[str, Any]]) -> dict[str, int]:
    counted = [r for r in results if r["outcome"] != "probe_error"]
    out = {"inputs_tried": len(counted)}
    out |= {o: sum(r["outcome"] == o for r in counted) for o in OUTCOMES}
    out["probe_errors"] = len(results) - len(counted)
    return out


def totals_line(t: dict[str, int]) -> str:
    return (
        f"inputs tried {t['inputs_tried']}, clear {t['clear']}, unclear {t['unclear']}, "
        f"crash {t['crash']}, hang {t['hang']}, silent {t['silent']}"
    )


def print_report(results: list[dict[str, Any]], detail_width: int = 400) -> None:
    groups = list(dict.fromkeys(r["group"] for r in results))
    head = f"{'class':<18s} {'tried':>5s} " + " ".join(f"{o:>7s}" for o in OUTCOMES)
    print("\n" + head + "  probe errors")
    print("-" * len(head) + "--------------")
    for g in [*groups, None]:
        rows = results if g is None else [r for r in results if r["group"] == g]
        t = totals(rows)
        if g is None:
            print("-" * len(head) + "--------------")
        print(
            f"{'total' if g is None else g:<18s} {t['inputs_tried']:5d} "
            + " ".join(f"{t[o]:7d}" for o in OUTCOMES)
            + (f"  {t['probe_errors']}" if t["probe_errors"] else "")
        )
    print("\n" + totals_line(totals(results)))
    others = [r for r in results if r["outcome"] != "clear"]
    if others:
        print(f"\nnot clear ({len(others)}):")
    for outcome in ("crash", "hang", "silent", "unclear", "probe_error"):
        for r in (r for r in others if r["outcome"] == outcome):
            text = r["detail"].replace("\n", " ")
            if len(text) > detail_width:
                text = text[:detail_width] + " ..."
            print(f"- {r['outcome']:<7s} {r['name']} [{r['group']}] {r['what']}\n    {text}")


def write_json(path: Path, results: list[dict[str, Any]], argv: list[str]) -> None:
    import grainscale

    data = {
        "probe": "bench/python/fault_probe.py",
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "grainscale": grainscale.__version__,
        "command": argv,
        "machine": machine_info(),
        "totals": totals(results),
        "totals_line": totals_line(totals(results)),
        "cases": results,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1))


def select(cases: dict[str, Any], patterns: list[str] | None) -> list[Any]:
    if not patterns:
        return list(cases.values())
    chosen = [c for c in cases.values() if any(fnmatch.fnmatch(c.name, p) for p in patterns)]
    unknown = [p for p in patterns if not any(fnmatch.fnmatch(n, p) for n in cases)]
    if unknown:
        raise SystemExit(f"no case named {', '.join(unknown)} (see --list)")
    return chosen


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--list", action="store_true", help="list the cases and exit")
    parser.add_argument("--case", action="append", metavar="NAME",
                        help="run only this case (repeatable; patterns like 'stl_*')")  # fmt: skip
    parser.add_argument("--jobs", type=int, default=2, help="cases run at once (default 2)")
    parser.add_argument("--timeout", type=float, default=60.0,
                        help="seconds before a case counts as a hang (default 60)")  # fmt: skip
    parser.add_argument("--output", type=Path, default=DEFAULT_OUTPUT,
                        help=f"JSON file of the results (default {DEFAULT_OUTPUT})")  # fmt: skip
    parser.add_argument("--worker", metavar="NAME", help=argparse.SUPPRESS)
    parser.add_argument("--work", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        return worker(args.worker, args.work or Path.cwd())
    try:
        cases = load_cases()
    except Exception as err:
        print(f"cannot load the cases (is grainscale importable? it may be being rebuilt; wait a "
              f"minute and re-run): {type(err).__name__}: {err}", file=sys.stderr)  # fmt: skip
        return 2
    if args.list:
        for c in cases.values():
            ranks = f" [{c.ranks} ranks]" if c.ranks > 1 else ""
            print(f"{c.name:<44s} {c.group:<18s} {c.what}{ranks}")
        print(f"{len(cases)} cases")
        return 0
    chosen = select(cases, args.case)
    started = time.perf_counter()
    print(f"fault probe: {len(chosen)} case(s), {args.jobs} at a time", flush=True)
    results = run_all(chosen, args.jobs, args.timeout)
    if args.case:
        for r in results:
            print(f"\n== {r['name']}: {r['outcome']}\n{r['detail']}")
            if r["outcome"] in ("crash", "hang", "probe_error") and r.get("stderr_tail"):
                print(f"--- stderr:\n{r['stderr_tail']}")
    print_report(results)
    write_json(args.output, results, sys.argv)
    print(f"\n{time.perf_counter() - started:.0f} s; results in {args.output}")
    if all(r["outcome"] == "probe_error" for r in results):
        print("every case failed in its set-up: is grainscale importable? (rebuilt?) Re-run.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
