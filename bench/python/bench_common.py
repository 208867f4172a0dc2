"""What the side-by-side benchmarks (settle.py, hopper.py) share: finding or installing
LIGGGHTS, running a code in its own measured subprocess, reading a LIGGGHTS log, the
round-robin driver and the results file.

Each code runs in a temporary directory of its own so that its peak RSS (``ru_maxrss`` from
``os.wait4``, or its own high-water mark where that is the driver's: see run_measured) and CPU
time are measured alone; the codes alternate for several rounds because
the machine is shared and noisy.
"""

from __future__ import annotations

import argparse
import datetime as dt
import functools
import json
import os
import platform
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

# The studies (studies/, outside the wheel) import from the repository root.
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

CODES = ("grainscale", "liggghts")

LOOP_RE = re.compile(
    r"Loop time of\s+([0-9.eE+-]+)\s+on\s+(\d+)\s+procs\s+"
    r"for\s+(\d+)\s+steps\s+with\s+(\d+)\s+atoms"
)


class BenchmarkError(RuntimeError):
    pass


class Run(Protocol):
    """What the round-robin driver prints of a run (settle's and hopper's RunResult)."""

    code: str
    round: int
    ns_per_particle_step: float
    run_seconds: float
    maxrss_kib: int
    warnings: list[str]


# ---------------------------------------------------------------------------------------------
# set-up


def add_spring_rotation_option(parser: argparse.ArgumentParser, default: str) -> None:
    """--spring-rotation: how grainscale's tangential spring follows the contact normal."""
    parser.add_argument(
        "--spring-rotation",
        choices=("project", "rescale"),
        default=default,
        help="grainscale's tangential spring rotation: 'project' as LIGGGHTS' tangential history "
        "(default), 'rescale' grainscale's default law",
    )


def ensure_liggghts() -> str:
    """Path of the ``liggghts`` executable; installs the Debian package when it is missing."""
    exe = shutil.which("liggghts")
    if exe:
        return exe
    prefix = ["env", "DEBIAN_FRONTEND=noninteractive"]
    if os.geteuid() != 0:
        prefix = ["sudo", *prefix]
    install = [*prefix, "apt-get", "install", "-y", "liggghts"]
    print("liggghts not found, installing the Debian package:", " ".join(install), flush=True)
    if subprocess.run(install).returncode != 0:
        subprocess.run([*prefix, "apt-get", "update"], check=True)
        subprocess.run(install, check=True)
    exe = shutil.which("liggghts")
    if not exe:
        raise BenchmarkError("apt-get install liggghts succeeded but 'liggghts' is not on PATH")
    return exe


# Prints grainscale._core.build_info() as JSON (a core older than build_info: kind unknown).
BUILD_PROBE = (
    "import json, grainscale._core as c; print(json.dumps(c.build_info() "
    "if hasattr(c, 'build_info') else {'kind': 'unknown', 'instruction_sets': []}))"
)


@functools.cache
def grainscale_build() -> dict[str, Any]:
    """How the grainscale core that this interpreter imports was built: ``_core.build_info()``
    (kind ``native`` or ``portable (x86-64-v2)``, instruction sets, MPI, compiler), asked in a
    subprocess as the workers import it; kind ``not importable`` without grainscale."""
    proc = subprocess.run([sys.executable, "-c", BUILD_PROBE], capture_output=True, text=True)
    if proc.returncode != 0:
        return {"kind": "not importable", "instruction_sets": [], "error": proc.stderr.strip()}
    return dict(json.loads(proc.stdout))


def build_label(build: dict[str, Any]) -> str:
    """``native: sse4.2 avx avx2 fma avx512f`` or ``portable (x86-64-v2): sse4.2``."""
    isa = " ".join(build.get("instruction_sets", [])) or "-"
    return f"{build['kind']}: {isa}"


def check_grainscale() -> dict[str, Any]:
    """Fails unless grainscale is importable; prints and returns how its core was built (the
    benchmark notes, bench/README.md, say which build a figure is of)."""
    build = grainscale_build()
    if build["kind"] == "not importable":
        raise BenchmarkError(
            f"grainscale is not importable by {sys.executable} (run 'make install' first, or "
            f"use --only liggghts):\n{build['error']}"
        )
    print(f"grainscale build measured: {build_label(build)} ({sys.executable})", flush=True)
    return build


def single_thread_env() -> dict[str, str]:
    env = dict(os.environ)
    env["OMP_NUM_THREADS"] = "1"
    # mpirun as root (the development VM and CI run as root).
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    return env


def launcher(ranks: int) -> list[str]:
    """Command prefix that starts ``ranks`` MPI processes (none for one: the plain process)."""
    if ranks == 1:
        return []
    mpirun = shutil.which("mpirun")
    if not mpirun:
        raise BenchmarkError("mpirun not found (make install installs openmpi-bin)")
    # Up to the core count Open MPI binds each rank to a core (measured faster than unbound);
    # beyond it the ranks share cores.
    extra = ["--oversubscribe"] if ranks > (os.cpu_count() or 1) else []
    return [mpirun, "-np", str(ranks), *extra]


def machine_info() -> dict[str, Any]:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "logical_cpus": os.cpu_count(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "omp_num_threads": 1,
        "grainscale_build": grainscale_build(),
    }


# ---------------------------------------------------------------------------------------------
# running one code


def run_measured(
    cmd: list[str], cwd: Path, env: dict[str, str], single_process: bool = True
) -> tuple[int, int, float]:
    """Run ``cmd`` with stdout/stderr to files in ``cwd``; return (exit code, peak RSS in KiB,
    CPU seconds (user + system) of the process).

    On Linux a child's ``ru_maxrss`` is never below the peak RSS its parent had when it was
    started (exec keeps the high-water mark of the memory it replaces), so on its own it cannot
    show a child smaller than this driver. For one process (``single_process``; not mpirun) the
    child's own high-water mark (VmHWM of /proc/<pid>/status, polled every 20 ms) is taken
    where ``ru_maxrss`` does not exceed the driver's peak; above it, ``ru_maxrss`` is exact."""
    hwm = 0
    with (cwd / "stdout.txt").open("wb") as out, (cwd / "stderr.txt").open("wb") as err:
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=out, stderr=err)
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG if single_process else 0)
            if pid != 0:
                break
            hwm = max(hwm, _vm_hwm_kib(proc.pid))
            time.sleep(0.02)
        proc.returncode = os.waitstatus_to_exitcode(status)
    rss = int(usage.ru_maxrss)  # KiB on Linux
    if single_process and hwm > 0 and rss <= resource.getrusage(resource.RUSAGE_SELF).ru_maxrss:
        rss = hwm
    return proc.returncode, rss, usage.ru_utime + usage.ru_stime


def _vm_hwm_kib(pid: int) -> int:
    """VmHWM (peak RSS of the current program) of a running process, 0 if unavailable."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        pass
    return 0


def _tail(path: Path, lines: int = 25) -> str:
    if not path.exists():
        return ""
    return "\n".join(path.read_text(errors="replace").splitlines()[-lines:])


def failure(code: str, rc: int, rundir: Path, *files: str) -> BenchmarkError:
    parts = [f"{code} failed with exit code {rc} in {rundir}"]
    parts += [f"--- {name}:\n{_tail(rundir / name)}" for name in files if (rundir / name).exists()]
    return BenchmarkError("\n".join(parts))


def run_liggghts_log(
    exe: str, workdir: Path, script: str, log_name: str, ranks: int = 1
) -> dict[str, Any]:
    """Run LIGGGHTS (on ``ranks`` MPI processes) on ``workdir/script`` in a fresh sub-directory;
    return the parsed log with ``text`` (the whole log), ``maxrss_kib``, ``cpu_seconds`` and
    ``loadavg_1min`` added."""
    rundir = Path(tempfile.mkdtemp(prefix="liggghts_", dir=workdir))
    try:
        load = os.getloadavg()[0]
        cmd = [*launcher(ranks), exe, "-in", f"../{script}", "-log", log_name]
        rc, rss, cpu = run_measured(cmd, rundir, single_thread_env(), ranks == 1)
        if rc != 0:
            raise failure("liggghts", rc, rundir, log_name, "stdout.txt", "stderr.txt")
        text = (rundir / log_name).read_text(errors="replace")
    finally:
        shutil.rmtree(rundir, ignore_errors=True)
    return parse_liggghts_log(text) | {
        "text": text,
        "maxrss_kib": rss,
        "cpu_seconds": cpu,
        "loadavg_1min": load,
    }


def run_grainscale_worker(
    worker: Path, workdir: Path, options: Sequence[str], ranks: int = 1
) -> tuple[dict[str, Any], int, float, list[str]]:
    """Run a grainscale worker script (``--output result.json`` is appended; on ``ranks`` MPI
    processes) in a fresh sub-directory; return (its result.json, peak RSS in KiB, 1-min load at
    the start, the warning lines of its stderr)."""
    rundir = Path(tempfile.mkdtemp(prefix="grainscale_", dir=workdir))
    try:
        load = os.getloadavg()[0]
        cmd = [*launcher(ranks), sys.executable, str(worker), *options, "--output", "result.json"]
        rc, rss, _ = run_measured(cmd, rundir, single_thread_env(), ranks == 1)
        if rc != 0 or not (rundir / "result.json").exists():
            raise failure("grainscale", rc, rundir, "stdout.txt", "stderr.txt")
        res: dict[str, Any] = json.loads((rundir / "result.json").read_text())
        stderr = (rundir / "stderr.txt").read_text(errors="replace")
    finally:
        shutil.rmtree(rundir, ignore_errors=True)
    warnings = [ln.strip() for ln in stderr.splitlines() if "warn" in ln.lower()]
    return res, rss, load, warnings


def parse_liggghts_log(text: str) -> dict[str, Any]:
    """Loop time (of the first and of every run command), last thermo block, warnings and a
    few diagnostics from a LIGGGHTS log."""
    match = LOOP_RE.search(text)
    if not match:
        raise BenchmarkError("no 'Loop time' line in the LIGGGHTS log:\n" + text[-2000:])
    lines = text.splitlines()
    header: list[str] = []
    rows: list[dict[str, float]] = []
    for line in lines:
        words = line.split()
        if words[:1] == ["Step"]:
            header, rows = [w.removeprefix("c_").removeprefix("v_") for w in words], []
        elif header and len(words) == len(header) and _all_numbers(words):
            rows.append(dict(zip(header, map(float, words), strict=True)))
        elif line.startswith("Loop time"):
            header = []
    if not rows:
        raise BenchmarkError("no thermo output in the LIGGGHTS log")

    def first_number(pattern: str) -> float | None:
        m = re.search(pattern, text)
        return float(m.group(1)) if m else None

    loops = [(float(m.group(1)), int(m.group(3))) for m in LOOP_RE.finditer(text)]
    return {
        "loop_seconds": float(match.group(1)),  # of the first run command
        # (seconds, steps) of every run command, in order (a benchmark with an untimed run
        # before the timed one reads the last)
        "loops": loops,
        "procs": int(match.group(2)),
        "steps": int(match.group(3)),
        "atoms": int(match.group(4)),
        "thermo": rows,
        "warnings": [ln.strip() for ln in lines if "WARNING" in ln or "ERROR" in ln],
        "version": lines[0].strip() if lines else "",
        "memory_mbytes": first_number(r"Memory usage per processor = ([0-9.eE+-]+)"),
        "neighbor_builds": first_number(r"Neighbor list builds = (\d+)"),
        "dangerous_builds": first_number(r"Dangerous builds = (\d+)"),
    }


def _all_numbers(words: list[str]) -> bool:
    try:
        for w in words:
            float(w)
    except ValueError:
        return False
    return True


# ---------------------------------------------------------------------------------------------
# driver and results file


def run_rounds(
    name: str,
    n_particles: int,
    codes: Sequence[str],
    repeats: int,
    keep: bool,
    prepare: Callable[[Path], None],
    run: Callable[[str, Path, int], Run],
    describe: Callable[[Run], str] = lambda _r: "",
) -> tuple[list[Run], str]:
    """Prepare the inputs in a temporary directory, then run the codes in turn for ``repeats``
    rounds (``run(code, workdir, round)``), printing one line per run; return the runs and the
    UTC time stamp of the start."""
    stamp = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    workdir = Path(tempfile.mkdtemp(prefix=f"grainscale_{name}_{n_particles}_"))
    runs: list[Run] = []
    try:
        prepare(workdir)
        for rnd in range(repeats):
            for code in codes:
                print(f"  round {rnd + 1}/{repeats}: {code:<10s} ... ", end="", flush=True)
                res = run(code, workdir, rnd)
                runs.append(res)
                print(
                    f"{res.ns_per_particle_step:8.1f} ns/particle-step{describe(res)}, "
                    f"{res.run_seconds:7.2f} s, peak RSS {res.maxrss_kib / 1024:7.1f} MiB"
                    + (f", {len(res.warnings)} warning line(s)" if res.warnings else ""),
                    flush=True,
                )
    finally:
        if keep:
            print(f"  inputs kept in {workdir}")
        else:
            shutil.rmtree(workdir, ignore_errors=True)
    return runs, stamp


def paired_ratios(runs: Sequence[Any], attribute: str) -> list[float]:
    """grainscale / LIGGGHTS of ``attribute`` for every round in which both codes ran."""
    by_round: dict[int, dict[str, Any]] = {}
    for r in runs:
        by_round.setdefault(r.round, {})[r.code] = r
    return [
        getattr(d["grainscale"], attribute) / getattr(d["liggghts"], attribute)
        for d in by_round.values()
        if len(d) == 2
    ]


def ratio_summary(runs: Sequence[Any], attribute: str) -> dict[str, Any] | None:
    """Per-round grainscale / LIGGGHTS ratios of ``attribute`` and their median; None when no
    round ran both codes."""
    ratios = paired_ratios(runs, attribute)
    return {"per_round": ratios, "median": statistics.median(ratios)} if ratios else None


def per_round(ratio: dict[str, Any]) -> str:
    """The rounds of a :func:`ratio_summary`, as printed beside its median."""
    return ", ".join(f"{v:.3f}" for v in ratio["per_round"])


def print_warnings(entry: dict[str, Any]) -> None:
    """Every distinct warning the runs of one size reported."""
    for w in sorted({w for run in entry["runs"] for w in run["warnings"]}):
        print(f"  warning: {w}")


def prepare_codes(only: str | None, codes: Sequence[str]) -> tuple[list[str], str | None]:
    """The codes to run (``only`` or all) and the LIGGGHTS executable (installed if missing);
    checks and prints the grainscale build when it runs."""
    chosen = [only] if only else list(codes)
    liggghts_exe = ensure_liggghts() if "liggghts" in chosen else None
    if "grainscale" in chosen:
        check_grainscale()
    return chosen, liggghts_exe


def write_results(
    path: Path, benchmark: str, entries: dict[str, dict[str, Any]], command: dict[str, Any]
) -> None:
    """Merge the new per-size entries into ``path`` (other sizes already there are kept)."""
    data: dict[str, Any] = {}
    if path.exists():
        try:
            data = json.loads(path.read_text())
        except json.JSONDecodeError:
            data = {}
    data["benchmark"] = benchmark
    data["machine"] = machine_info()
    data["last_command"] = command
    data.setdefault("sizes", {}).update(entries)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1))
