#!/usr/bin/env bash
# Builds a self-contained bundle of Nestlight for a bare GPU machine (docs/GPU.md): the
# `nestlight` program and the GL test binaries, every shared library they need that a machine
# with only glibc and a GPU driver lacks (Embree, TBB, OpenEXR, Draco, zstd, GLFW, PCL, ... and
# what they pull in), the GL loader packages (libglvnd's libEGL, libOpenGL, ... as Debian .deb
# files, unpacked by scripts/gpu-unpack.py with Python's standard library alone) and a `run`
# wrapper that points the loader at them. Compressed with xz; prints the bundle's path last.
#
#   scripts/gpu-bundle.sh                     Release build in build/ (built if needed)
#   scripts/gpu-bundle.sh --tune x86-64-v3    a separate build in build-gpu/ with -march=x86-64-v3
#   scripts/gpu-bundle.sh --check             then unpack it and run the demo in a clean
#                                             environment (scripts/gpu-bundle-check.sh)
#   options: --build-dir DIR, --out FILE (default .gpu/nestlight-gpu-bundle.tar.xz), --fast (xz -1),
#            --no-shared-data (leave out the two scans of ../shared/data the golden tests render)
set -euo pipefail
cd "$(dirname "$0")/.."


build_dir=""
tune=""
out=".gpu/nestlight-gpu-bundle.tar.xz"
check=0
# xz -6: 32.7 MiB in 70 s on two cores; -9 saved 2 MiB for 160 s.
xz_level=6
shared_data=1
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) build_dir=$2; shift 2 ;;
    --tune) tune=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --check) check=1; shift ;;
    --fast) xz_level=1; shift ;;
    --no-shared-data) shared_data=0; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) echo "gpu-bundle: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done

# The carry limit of the GPU machine is 64 MiB for the working tree and everything carried;
# the bundle and the checkout together keep 25% of it spare.
carry_limit=$((64 * 1024 * 1024))
# The GL test suites of scripts/gpu-suites.txt.
suites=$(awk '$1 !~ /^#/ && NF {print $1 "_tests"}' scripts/gpu-suites.txt | tr '\n' ' ')
test_targets="nestlight $suites"

if [ -n "$tune" ]; then
  build_dir=${build_dir:-build-gpu}
  # x86-64-v3 (AVX2, FMA, BMI2) runs on every server CPU an H100 or H200 sits beside.
  BUILD_DIR=$build_dir CMAKE_ARGS="-DCMAKE_CXX_FLAGS=-march=$tune -DCMAKE_C_FLAGS=-march=$tune" \
    TARGETS="$test_targets" scripts/setup.sh >&2
else
  build_dir=${build_dir:-build}
  BUILD_DIR=$build_dir TARGETS="$test_targets" scripts/setup.sh >&2
fi

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
b="$stage/nestlight-gpu"
mkdir -p "$b/bin" "$b/lib" "$b/fallback" "$b/debs"
cp "$build_dir/nestlight" "$b/bin/"
for t in $suites; do cp "$build_dir/tests/$t" "$b/bin/"; done
strip --strip-unneeded "$b"/bin/* 2>/dev/null || true

# Libraries every Linux with glibc >= 2.36 has (the bundle's binaries need that glibc), and the
# GL loaders, which come as packages below; libstdc++ and libgcc_s go to fallback/, used only
# when the machine's own are older than the build's (a newer one serves, and the GPU driver may
# need it).
is_system() {
  case "$1" in
    linux-vdso.so.*|ld-linux-x86-64.so.*|libc.so.*|libm.so.*|libdl.so.*|libpthread.so.*|librt.so.*|libresolv.so.*|libutil.so.*) return 0 ;;
    libEGL.so.*|libGL.so.*|libOpenGL.so.*|libGLX.so.*|libGLdispatch.so.*|libGLESv2.so.*|libGLESv1_CM.so.*) return 0 ;;
  esac
  return 1
}
declare -A copied=()
for bin in "$b"/bin/*; do
  while read -r name _ path _; do
    [ -n "$name" ] || continue
    is_system "$name" && continue
    [ -n "${copied[$name]:-}" ] && continue
    if [ "$path" = "not" ] || [ ! -e "$path" ]; then
      echo "gpu-bundle: $(basename "$bin") needs $name, which this machine does not have" >&2
      exit 1
    fi
    case "$name" in
      libstdc++.so.*|libgcc_s.so.*) cp -L "$path" "$b/fallback/$name" ;;
      *) cp -L "$path" "$b/lib/$name" ;;
    esac
    copied[$name]=1
  done < <(ldd "$bin" | awk '/=>/ {print $1, $2, $3, $4}')
done
strip --strip-unneeded "$b"/lib/* "$b"/fallback/* 2>/dev/null || true

# libglvnd's loaders as Debian packages (libepoxy opens libEGL.so.1 and libOpenGL.so.0 at run
# time; the NVIDIA driver provides only the vendor libraries behind them).
gl_packages="libglvnd0 libegl1 libopengl0 libgl1 libglx0 libgles2"
download() { (cd "$b/debs" && apt-get download $gl_packages >/dev/null 2>&1); }
if ! download; then
  # No package lists yet (a machine whose packages were all installed before): fetch them once.
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq >/dev/null 2>&1 || true
  download || {
    echo "gpu-bundle: apt-get download $gl_packages failed (Debian's package archive unreachable?)" >&2
    exit 1
  }
fi

# The scans the golden-image tests render, where ../shared/data has them: the GPU machine gets
# no shared data, and without them those tests skip there (never committed: the bundle is not).
if [ "$shared_data" = 1 ]; then
  for f in scans/lion_takanawa.las scans/autzen_trim.las; do
    if [ -f "../shared/data/$f" ]; then
      mkdir -p "$b/shared-data/$(dirname "$f")"
      cp "../shared/data/$f" "$b/shared-data/$f"
    fi
  done
fi

cp scripts/gpu-bundle-run.sh "$b/run"
chmod +x "$b/run"
# The newest GLIBCXX the binaries ask for: the wrapper uses fallback/ where the machine lacks it.
glibcxx=$(for f in "$b"/bin/* "$b"/lib/*; do objdump -T "$f" 2>/dev/null; done |
  grep -o 'GLIBCXX_3\.4\.[0-9]*' | sort -t. -k3 -n -u | tail -n 1)
echo "${glibcxx:-GLIBCXX_3.4}" >"$b/glibcxx"

commit=$(git rev-parse HEAD 2>/dev/null || echo unknown)
dirty=$(git status --porcelain 2>/dev/null | grep -q . && echo true || echo false)
python3 - "$b" "$commit" "$dirty" "$build_dir" "${tune:-x86-64}" <<'EOF'
import hashlib, json, os, sys, platform, datetime
b, commit, dirty, build_dir, tune = sys.argv[1:]
files = []
for dirpath, _, names in os.walk(b):
    for n in sorted(names):
        p = os.path.join(dirpath, n)
        with open(p, 'rb') as f:
            files.append({"path": os.path.relpath(p, b), "bytes": os.path.getsize(p),
                          "sha256": hashlib.sha256(f.read()).hexdigest()})
json.dump({"commit": commit, "dirty": dirty, "build_dir": build_dir, "march": tune,
           "built_on": platform.platform(), "glibc": platform.libc_ver()[1],
           "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
           "files": sorted(files, key=lambda f: f["path"])}, open(os.path.join(b, "MANIFEST.json"), "w"), indent=1)
EOF

mkdir -p "$(dirname "$out")"
tmp_out="$out.tmp"
XZ_OPT="-$xz_level -T0" tar -C "$stage" -cJf "$tmp_out" nestlight-gpu
mv "$tmp_out" "$out"

bundle_bytes=$(stat -c %s "$out")
tree_bytes=$(git ls-files -z --cached --others --exclude-standard | du -cb --files0-from=- 2>/dev/null | tail -n 1 | cut -f1)
unpacked=$(du -sb "$b" | cut -f1)
echo "gpu-bundle: $(du -sh "$b/bin" | cut -f1) of binaries, ${#copied[@]} libraries ($(du -sh "$b/lib" | cut -f1)), $(ls "$b/debs" | wc -l) GL packages; $((unpacked / 1048576)) MiB unpacked" >&2
echo "gpu-bundle: $((bundle_bytes / 1048576)) MiB compressed + $((tree_bytes / 1048576)) MiB of checkout = $(((bundle_bytes + tree_bytes) * 100 / carry_limit))% of the 64 MiB carry limit" >&2
if [ $(((bundle_bytes + tree_bytes) * 4)) -gt $((carry_limit * 3)) ]; then
  echo "gpu-bundle: bundle and checkout exceed 75% of the carry limit" >&2
  exit 1
fi
if [ "$check" = 1 ]; then
  scripts/gpu-bundle-check.sh "$out" >&2
fi
readlink -f "$out"
