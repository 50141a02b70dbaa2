#!/usr/bin/env bash
# Writes a few valid inputs for fuzz target $1 into folder $2, made by the project itself.
set -euo pipefail
name=$1
dir=$2
bin=build/nestlight
case "$name" in
  fuzz_las) "$bin" generate -n 50 -o "$dir/a.las" >/dev/null; "$bin" generate -n 20 --shape plane -o "$dir/b.las" >/dev/null ;;
  fuzz_ply) "$bin" generate -n 30 -o "$dir/a.ply" >/dev/null
            printf 'ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nend_header\n1 2 3 4\n5 6 7 8\n' > "$dir/b.ply" ;;
  fuzz_xyz) printf '1 2 3\n4 5 6\n' > "$dir/a.xyz"; printf '2\n1 2 3 10 20 30 40\n4 5 6 11 21 31 41\n' > "$dir/b.pts" ;;
  *) : ;;
esac
