#!/usr/bin/env bash
# scripts/check_layers.py catches what it must: on a generated tree it passes clean includes and
# names an upward and a sideways include with file, line and floors, between top-level folders and
# between gi/'s libraries (a method including a sibling method). $1: the script.
set -euo pipefail
check=$1
root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/octree/src" "$root/converters/src" "$root/gi/src" "$root/cli/src"
printf '#include "nestlight/octree/error.h"\n#include "nestlight/converters/reader.h"\n' > "$root/gi/src/ok.cpp"
printf '#include "nestlight/gi/scene.h"\n' > "$root/cli/src/ok.cpp"
mkdir -p "$root/gi/shared/include/nestlight/gi/shared" "$root/gi/shared/src" \
         "$root/gi/pbgi/include/nestlight/gi/pbgi" "$root/gi/vpl/src" "$root/gi/methods/src"
touch "$root/gi/shared/include/nestlight/gi/shared/bsh.h" "$root/gi/pbgi/include/nestlight/gi/pbgi/pbgi_method.h"
printf '#include "nestlight/gi/shared/bsh.h"\n' > "$root/gi/vpl/src/ok.cpp"
printf '#include "nestlight/gi/pbgi/pbgi_method.h"\n' > "$root/gi/methods/src/ok.cpp"
if ! python3 "$check" "$root" > "$root/out"; then
  echo "a tree whose includes run downward failed:"; cat "$root/out"; exit 1
fi
printf '// a comment\n#include "nestlight/gi/scene.h"\n' > "$root/octree/src/up.cpp"
printf '#include "nestlight/streaming/streamer.h"\n' > "$root/converters/src/side.cpp"
printf '#include "nestlight/gi/pbgi/pbgi_method.h"\n' > "$root/gi/vpl/src/sibling.cpp"
printf '#include "nestlight/gi/pbgi/pbgi_method.h"\n' > "$root/gi/shared/src/up.cpp"
if python3 "$check" "$root" > "$root/out"; then
  echo "an upward include was not caught:"; cat "$root/out"; exit 1
fi
grep -q "octree/src/up.cpp:2: octree (floor 0) includes gi (floor 4): upward" "$root/out"
grep -q "converters/src/side.cpp:1: converters (floor 2) includes streaming (floor 2): sideways" "$root/out"
grep -q "gi/vpl/src/sibling.cpp:1: gi/vpl includes gi/pbgi: a method includes no sibling method" "$root/out"
grep -q "gi/shared/src/up.cpp:1: gi/shared (gi floor 2) includes gi/pbgi (gi floor 4): upward" "$root/out"
grep -q "4 includes against the floors" "$root/out"
echo "check_layers_test: upward and sideways includes caught, in gi/ too"
