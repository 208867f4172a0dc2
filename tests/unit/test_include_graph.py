"""The C++ include graph respects the floors of DESIGN.md 1: a file includes only its own folder
and lower floors; folders on the same floor do not include each other. A new folder under cpp/
must be placed in FLOORS before any file in it passes."""

import re
from pathlib import Path

CPP = Path(__file__).resolve().parents[2] / "cpp"

# Floors, lowest first (DESIGN.md 1).
FLOORS = {
    "core": 0,
    "state": 1,
    "geometry": 1,
    "neighbor": 2,
    "insert": 2,
    "integrate": 2,
    "parallel": 2,
    "contact": 3,
    "field": 4,
    "level": 5,
    "coupling": 6,
    "bindings": 7,
}

INCLUDE = re.compile(r'^\s*#\s*include\s+"(([^"/]+)/[^"]+)"', re.MULTILINE)


def sources():
    return sorted(p for ext in ("*.hpp", "*.cpp") for p in CPP.rglob(ext))


def violations():
    found = []
    for path in sources():
        rel = path.relative_to(CPP)
        folder = rel.parts[0]
        if folder not in FLOORS:
            found.append(f"{rel}: folder '{folder}' has no floor in FLOORS")
            continue
        for include, target in INCLUDE.findall(path.read_text()):
            if target == folder:
                continue
            if target not in FLOORS:
                found.append(f'{rel}: includes "{include}", a folder with no floor in FLOORS')
            elif FLOORS[target] >= FLOORS[folder]:
                kind = "same floor" if FLOORS[target] == FLOORS[folder] else "higher floor"
                found.append(
                    f'{rel} (floor {FLOORS[folder]}, {folder}) includes "{include}" '
                    f"(floor {FLOORS[target]}, {target}): {kind}"
                )
    return found


def test_sources_are_found():
    assert len(sources()) > 50


def test_no_include_points_up_the_floors():
    found = violations()
    assert not found, "includes that break the floors:\n" + "\n".join(found)
