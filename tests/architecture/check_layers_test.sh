#!/usr/bin/env bash
# scripts/check_layers.py catches what it must: on a generated tree it passes clean includes and
# names an upward and a sideways include with file, line and floors. $1: the script.
set -euo pipefail
check=$1
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/octree/src" "$root/converters/src" "$root/gi/src" "$root/cli/src"
printf '#include "nestlight/octree/error.h"\n#include "nestlight/converters/reader.h"\n' > "$root/gi/src/ok.cpp"
printf '#include "nestlight/gi/scene.h"\n' > "$root/cli/src/ok.cpp"
if ! python3 "$check" "$root" > "$root/out"; then
  echo "a tree whose includes run downward failed:"; cat "$root/out"; exit 1
fi
printf '// a comment\n#include "nestlight/gi/scene.h"\n' > "$root/octree/src/up.cpp"
printf '#include "nestlight/streaming/streamer.h"\n' > "$root/converters/src/side.cpp"
if python3 "$check" "$root" > "$root/out"; then
  echo "an upward include was not caught:"; cat "$root/out"; exit 1
fi
grep -q "octree/src/up.cpp:2: octree (floor 0) includes gi (floor 4): upward" "$root/out"
grep -q "converters/src/side.cpp:1: converters (floor 2) includes streaming (floor 2): sideways" "$root/out"
grep -q "2 includes against the floors" "$root/out"
echo "check_layers_test: upward and sideways includes caught"
