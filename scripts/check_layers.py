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

# Floors inside gi/ (docs/ARCHITECTURE.md, "Within gi/"): each sub-folder is a library whose
# headers sit under gi/<library>/include/nestlight/gi/. A sub-folder not listed is a method.
GI_FLOORS = {
    "core": 0,
    "metrics": 1, "frame": 1,
    "shared": 2,
    "reference": 3,
    "methods": 5,
}
GI_METHOD_FLOOR = 4  # raster, vpl, pbgi, ibl, hdr and every method to come: siblings
# Includes of a method's headers that stay until what they name moves below the methods (none
# now: the raster frame that vpl, pbgi and ibl extend is gi/frame/'s). Remove an entry when its
# header has moved.
GI_PENDING = set()
GI_INCLUDE = re.compile(r'^\s*#\s*include\s+"(nestlight/gi/[^"]+)"')


def gi_floor(library):
    return GI_FLOORS.get(library, GI_METHOD_FLOOR)


def check_gi(root):
    """Includes between gi/'s libraries: downward only, and no method includes a sibling method."""
    base = os.path.join(root, "gi")
    if not os.path.isdir(base):
        return []
    libraries = sorted(d for d in os.listdir(base) if os.path.isdir(os.path.join(base, d)))
    owner = {}  # "nestlight/gi/..." header -> the gi library that holds it
    for library in libraries:
        include = os.path.join(base, library, "include")
        for dirpath, _, files in os.walk(include):
            for name in files:
                owner[os.path.relpath(os.path.join(dirpath, name), include)] = library
    problems = []
    for library in libraries:
        for dirpath, _, files in os.walk(os.path.join(base, library)):
            for name in files:
                if not name.endswith((".cpp", ".h", ".hpp", ".inc")):
                    continue
                path = os.path.join(dirpath, name)
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = GI_INCLUDE.match(line)
                        if not m or m.group(1) in GI_PENDING:
                            continue
                        target = owner.get(m.group(1))
                        if target is None or target == library:
                            continue
                        here, there = gi_floor(library), gi_floor(target)
                        where = f"{os.path.relpath(path, root)}:{number}: "
                        if here == there == GI_METHOD_FLOOR:
                            problems.append(
                                where + f"gi/{library} includes gi/{target}: a method includes no "
                                f"sibling method (what both need belongs in gi/shared)")
                        elif there >= here:
                            way = "upward" if there > here else "sideways"
                            problems.append(where + f"gi/{library} (gi floor {here}) includes "
                                            f"gi/{target} (gi floor {there}): {way}")
    return problems


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
    problems += check_gi(root)
    for p in problems:
        print(p)
    if checked == 0:
        print(f"check_layers: no sources under {root}")
        return 1
    print(f"check_layers: {checked} files, {len(problems)} includes against the floors")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
