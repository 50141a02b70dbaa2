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
  fuzz_mesh_ply)
    printf 'ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n0 1 0 0 0 1 9 9 9\n4 0 1 2 3\n3 0 0 2\n' > "$dir/a.ply"
    # Binary, both byte orders: 3 float vertices, one face of uchar count and int indices, an
    # extra element with a list after it.
    { printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nelement extra 1\nproperty list ushort double values\nend_header\n'
      printf '\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00''\x00\x00\x80\x3f\x00\x00\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x80\x3f\x00\x00\x00\x00'
      printf '\x03\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00''\x01\x00\x00\x00\x00\x00\x00\x00\xf0\x3f'; } > "$dir/b.ply"
    { printf 'ply\nformat binary_big_endian 1.0\nelement face 1\nproperty list uint ushort vertex_index\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n'
      printf '\x00\x00\x00\x03\x00\x00\x00\x01\x00\x02'
      printf '\x00\x00\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x00\x00''\x10\x20\x30'
      printf '\x3f\xf0\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x00\x00''\x40\x50\x60'
      printf '\x00\x00\x00\x00\x00\x00\x00\x00''\x3f\xf0\x00\x00\x00\x00\x00\x00''\x00\x00\x00\x00\x00\x00\x00\x00''\x70\x80\x90'; } > "$dir/c.ply" ;;
  fuzz_mesh_obj)
    printf '# cube corner\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvn 0 0 1\nvn 0 -1 0\no box\ng side\nusemtl m\ns 1\nf 1/1/1 2/2/1 3/2/1 4/1/1\nf 1//2 2//2 -1//2\nf -5 -4 \\\n -1\nl 1 2\n' > "$dir/a.obj"
    printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 2\n' > "$dir/b.obj" ;;
  fuzz_scene)
    printf '{"version": 1, "octrees": ["a.octree", {"path": "b", "max_level": 3, "memory_budget": "1GiB"}],\n "materials": {"m": {"type": "principled", "base_color": [1, 0.5, 0.2], "clearcoat": 1}},\n "meshes": [{"path": "x.obj", "material": "m", "transform": {"translate": [1, 2, 3], "rotate": [0, 0, 90], "scale": [1, 2, 3]}, "surfels": {"method": "poisson", "count": 10}}],\n "lights": [{"type": "spot", "position": [0, 0, 1], "direction": [0, 0, -1], "intensity": 2, "inner_angle": 5, "outer_angle": 9}],\n "environment": {"constant": [1, 1, 1]}, "camera": {"eye": [0, -1, 0], "target": [0, 0, 0]},\n "camera_path": {"fps": 2, "keyframes": [{"time": 0, "eye": [0, 1, 0], "target": [0, 0, 0]}]},\n "gi": {"mode": "albedo", "max_bounces": 2}, "output": {"exr": "o.exr"}}\n' > "$dir/a.json"
    printf '{"meshes": [{"path": "m.ply", "transform": {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}}]}' > "$dir/b.json" ;;
  fuzz_laz)
    # Whole files (a leading even byte): the small LAZ files of ../shared/data when present
    # (copied at run time, never committed), else a generated LAS file, which exercises the
    # header paths; and a bare chunk (a leading odd byte): a raw first record and random bytes.
    shared=../shared/data/laz
    n=0
    for f in "$shared"/point10.las.laz "$shared"/point-color-time.las.laz "$shared"/extrabytes.laz "$shared"/1_4_w_evlr.laz "$shared"/simple.copc.laz; do
      [ -f "$f" ] || continue
      n=$((n + 1)); { printf '\x00'; cat "$f"; } > "$dir/file$n"
    done
    if [ "$n" = 0 ]; then "$bin" generate -n 50 -o "$dir/a.las" >/dev/null; { printf '\x00'; cat "$dir/a.las"; } > "$dir/file0"; rm "$dir/a.las"; fi
    # pf 3 with a bare chunk of 5 points: the first record raw, then arbitrary stream bytes.
    head -c 200 /dev/urandom > "$dir/rnd"; { printf '\x01\x06\x04'; cat "$dir/rnd"; } > "$dir/chunk3"; rm "$dir/rnd" ;;
  *) : ;;
esac
