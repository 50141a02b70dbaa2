#!/usr/bin/env python3
"""The floors of docs/ARCHITECTURE.md, checked: every #include of a project header
("nestlight/<library>/...") from a source folder must name a library on a lower floor, or the
folder's own. Prints each include that runs upward or sideways, with its file and line, and exits
1 if there is one. Run by ctest (Architecture.IncludesRunDownward) and by hand:
    scripts/check_layers.py [repository root]
"""
import os
import re
import sys

# Floor of each top-level source folder. Folders on one floor may not include each other.
FLOORS = {
    "octree": 0, "shaders": 0,
    "gl": 1,
    "converters": 2, "streaming": 2,
    "frame": 3,
    "gi": 4,
    "bench": 5, "viewer": 5,
    "cli": 6,
}
# The library a header prefix belongs to: the folder that holds nestlight/<name>/.
LIBRARY_FOLDER = {
    "octree": "octree", "shaders": "shaders", "gl": "gl", "converters": "converters",
    "streaming": "streaming", "frame": "frame", "gi": "gi", "bench": "bench", "viewer": "viewer",
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"nestlight/([a-z_]+)/')


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), ".."))
    problems = []
    checked = 0
    for folder, floor in FLOORS.items():
        base = os.path.join(root, folder)
        for dirpath, _, files in os.walk(base):
            for name in files:
                if not name.endswith((".cpp", ".h", ".hpp", ".inc")):
                    continue
                path = os.path.join(dirpath, name)
                checked += 1
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        library = m.group(1)
                        target = LIBRARY_FOLDER.get(library)
                        if target is None:
                            problems.append(f"{os.path.relpath(path, root)}:{number}: includes "
                                            f"nestlight/{library}/, a library the floors do not list")
                        elif target != folder and FLOORS[target] >= floor:
                            way = "upward" if FLOORS[target] > floor else "sideways"
                            problems.append(f"{os.path.relpath(path, root)}:{number}: {folder} (floor "
                                            f"{floor}) includes {target} (floor {FLOORS[target]}): "
                                            f"{way}")
    for p in problems:
        print(p)
    if checked == 0:
        print(f"check_layers: no sources under {root}")
        return 1
    print(f"check_layers: {checked} files, {len(problems)} includes against the floors")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
