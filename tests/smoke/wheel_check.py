"""Check a built wheel before it is installed (``make wheel``).

    python tests/smoke/wheel_check.py WHEEL --compile-commands BUILD/compile_commands.json

Refuses the wheel when

- a compile command of its build lacks ``-march=x86-64-v2`` (on x86-64) or has
  ``-march=native``,
- the extension module contains instructions on AVX registers (ymm, zmm) or FMA instructions,
  which an x86-64-v2 CPU does not have (needs objdump; skipped with a note without it),
- a file of the wheel holds an absolute path of the machine that built it: the source tree,
  the build directory or the isolated build environment.

Prints the wheel's name, size and file count and what was checked.
"""

from __future__ import annotations

import argparse
import json
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
# ymm/zmm registers (AVX, AVX2, AVX-512) and fused multiply-add, in AT&T syntax.
WIDE = re.compile(r"%[yz]mm\d|\bv?fn?m(add|sub)\d{3}")


def check_compile_commands(paths: list[Path], x86: bool) -> list[str]:
    problems: list[str] = []
    count = 0
    for path in paths:
        if not path.is_file():
            problems.append(f"{path}: no such file (configure with CMAKE_EXPORT_COMPILE_COMMANDS)")
            continue
        for entry in json.loads(path.read_text()):
            count += 1
            command = entry.get("command") or " ".join(entry.get("arguments", []))
            source = Path(entry["file"]).name
            if "-march=native" in command:
                problems.append(f"{source} is compiled with -march=native")
            if x86 and "-march=x86-64-v2" not in command:
                problems.append(f"{source} is compiled without -march=x86-64-v2")
    if count == 0 and not problems:
        problems.append("no compile commands")
    print(f"compile commands: {count}, all portable" if not problems else "compile commands:")
    return problems


def check_instructions(module: Path) -> list[str]:
    objdump = shutil.which("objdump")
    if objdump is None:
        print("instructions: objdump not found, not checked")
        return []
    out = subprocess.run(
        [objdump, "-d", "--no-show-raw-insn", str(module)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    lines = [line for line in out.splitlines() if "\t" in line]
    wide = [line.strip() for line in lines if WIDE.search(line)]
    print(f"instructions: {len(lines)} in {module.name}, {len(wide)} AVX or FMA")
    return [f"AVX or FMA instruction: {line}" for line in wide[:5]]


def check_paths(wheel: zipfile.ZipFile, build_dirs: list[Path]) -> list[str]:
    needles = {str(REPO).encode(), b"/build-env-"}
    needles |= {str(d.resolve()).encode() for d in build_dirs}
    problems = []
    for name in wheel.namelist():
        if name.startswith("/") or ".." in Path(name).parts:
            problems.append(f"{name}: not a relative path")
        data = wheel.read(name)
        for needle in sorted(needles):
            if needle in data:
                problems.append(f"{name} contains {needle.decode()}")
    searched = ", ".join(sorted(n.decode() for n in needles))
    print(f"paths: {len(wheel.namelist())} files searched for {searched}")
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("wheel", type=Path)
    parser.add_argument("--compile-commands", type=Path, nargs="+", default=[])
    args = parser.parse_args(argv)
    x86 = platform.machine() in ("x86_64", "AMD64")
    size = args.wheel.stat().st_size
    problems = check_compile_commands(args.compile_commands, x86)
    with zipfile.ZipFile(args.wheel) as wheel:
        modules = [n for n in wheel.namelist() if re.fullmatch(r"grainscale/_core\..*\.so", n)]
        print(f"wheel: {args.wheel.name}, {size / 1e6:.2f} MB, {len(wheel.namelist())} files")
        if len(modules) != 1:
            problems.append(f"expected one extension module grainscale/_core*.so, got {modules}")
        elif x86:
            with tempfile.TemporaryDirectory() as tmp:
                module = Path(wheel.extract(modules[0], tmp))
                problems += check_instructions(module)
        build_dirs = [p.parent for p in args.compile_commands]
        problems += check_paths(wheel, build_dirs)
    for problem in problems:
        print(f"error: {problem}", file=sys.stderr)
    if problems:
        return 1
    print("wheel check passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
