#!/usr/bin/env bash
# The one command of a GPU run (docs/GPU.md): on a machine lent with an NVIDIA GPU, from the
# checkout with the bundle of scripts/gpu-bundle.sh carried beside it, it measures what the
# project's real-time targets are about and writes a report:
#   1. context: GL vendor, renderer, version; every shader program compiled and linked
#      (`nestlight gl-info --programs`, the 64-bit compute rasteriser included);
#   2. the GL test suites (scripts/gpu-suites.txt) on that GPU, per test, with the golden images'
#      differences;
#   3. point rendering: `bench render` on a generated scan converted there (100M points): GL_POINTS
#      basic and HQS, compute 32-bit and 64-bit;
#   4. streaming: `bench stream` over that scan, and a camera path rendered with per-frame stats;
#   5. GI at 1920x1080 on that scan with its inserted mesh, sky, sun and a spot light: `bench frame`
#      per pass for raster, vpl (256, 1024, 4096 VPLs), pbgi (classic, mip, x at 512x512 with 16x16
#      and 32x32 micro-buffers) and ibl (mis, bis, smc);
#   6. speed against error: `bench gi` on the cornell and object scenes, the reference on every core.
# Each step has a time limit and the run a deadline (default 8 min 40 s), so the report is written
# even when a step hangs. --quick runs every step at tiny sizes (on llvmpipe in about a minute):
# the script is tested on every machine by scripts/test.sh.
#
#   scripts/gpu-run.sh [--quick] [--bundle FILE | --bin BUILD_DIR] [--out DIR] [--deadline S] [--keep]
#     --bundle FILE   the bundle to unpack and run (default .gpu/nestlight-gpu-bundle.tar.xz when
#                     present, else the build in build/)
#     --bin DIR       run the build in DIR instead (DIR/nestlight, DIR/tests/*_tests)
#     --out DIR       report.json, report.md, details.tar.gz and a few PNGs (default gpu-report)
#     --deadline S    seconds the whole run may take (default 520; --quick 240)
#     --keep          keep the work folder (generated scans, logs)
#   For a second run on the same lent machine, after the first showed what to look at:
#     --steps REGEX   only the steps whose names match (bash regex, whole name: 'gl_info|tests|frame_vpl.*')
#     --runs N        runs per benchmark instead of 5
#     --suite-filter SUITE=FILTER   the gtest filter of one suite of scripts/gpu-suites.txt (repeatable)
#     --shader-dir DIR              shader files read from DIR where it holds them (NESTLIGHT_SHADER_DIR)
#     --shader-variants DIR         bisect a driver's refusal: each folder of DIR (in name order) is an
#                     edited copy of part of shaders/ with a file `programs` naming the programs to
#                     check; each is compiled with gl-info, and the first whose programs all link
#                     becomes the shader folder of the rest of the run
# Exit status: 0 when every step succeeded, 1 when one failed or timed out, 2 for bad options.
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)

quick=0
bundle=""
bin_dir=""
out="gpu-report"
deadline=""
keep=0
only_steps=""
runs_override=""
shader_dir=""
variants_dir=""
suite_filters=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1; shift ;;
    --bundle) bundle=$2; shift 2 ;;
    --bin) bin_dir=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --deadline) deadline=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --steps) only_steps=$2; shift 2 ;;
    --runs) runs_override=$2; shift 2 ;;
    --suite-filter) suite_filters+=("$2"); shift 2 ;;
    --shader-dir) shader_dir=$2; shift 2 ;;
    --shader-variants) variants_dir=$2; shift 2 ;;
    -h|--help) sed -n '2,37p' "$0"; exit 0 ;;
    *) echo "gpu-run: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
if [ -z "$deadline" ]; then deadline=$([ $quick = 1 ] && echo 240 || echo 520); fi

mkdir -p "$out"
out=$(cd "$out" && pwd)
rm -f "$out"/report.json "$out"/report.md "$out"/details.tar.gz "$out"/*.png
work=$(mktemp -d "${TMPDIR:-/tmp}/nestlight-gpu-run.XXXXXX")
[ $keep = 1 ] || trap 'rm -rf "$work"' EXIT
mkdir -p "$work/res" "$work/logs"
steps="$work/steps.jsonl"
: >"$steps"
SECONDS=0

say() { echo "gpu-run [$(printf '%3d' $SECONDS) s] $*" >&2; }

# Which programs: the bundle's wrapper, or a build folder.
if [ -z "$bin_dir" ] && [ -z "$bundle" ]; then
  if [ -f .gpu/nestlight-gpu-bundle.tar.xz ]; then bundle=.gpu/nestlight-gpu-bundle.tar.xz; else bin_dir=build; fi
fi
if [ -n "$bundle" ]; then
  say "unpacking $bundle"
  b=$(python3 scripts/gpu-unpack.py "$bundle" "$work/bundle" | tail -n 1) || { say "cannot unpack $bundle"; exit 1; }
  NL="$b/run nestlight"
  suite() { echo "$b/run $1"; }
  # The golden tests' scans travel in the bundle where they were there to take.
  [ -d "$b/shared-data" ] && export NESTLIGHT_TEST_SHARED_DATA="$b/shared-data"
  export NESTLIGHT_TEST_BINARY="$b/run nestlight"
else
  bin_dir=$(cd "$bin_dir" && pwd) || exit 2
  [ -x "$bin_dir/nestlight" ] || { say "no $bin_dir/nestlight (run scripts/setup.sh)"; exit 2; }
  NL="$bin_dir/nestlight"
  suite() { echo "$bin_dir/tests/$1"; }
  export NESTLIGHT_TEST_BINARY="$bin_dir/nestlight"
fi
export NESTLIGHT_TEST_SOURCE_DIR="$repo"
threads=$(nproc)
if [ -n "$shader_dir" ]; then
  export NESTLIGHT_SHADER_DIR=$(cd "$shader_dir" && pwd) || exit 2
fi

# step NAME LIMIT_S COMMAND: runs COMMAND (a bash command line) with its output in logs/NAME.log,
# within LIMIT_S and what is left before the deadline (20 s kept for the report).
failed=0
step() {
  local name=$1 limit=$2 cmd=$3
  if [ -n "$only_steps" ] && ! [[ $name =~ ^($only_steps)$ ]]; then
    printf '{"name": "%s", "status": "not selected", "seconds": 0, "limit": 0}\n' "$name" >>"$steps"
    return 1
  fi
  local left=$((deadline - SECONDS - 20))
  [ "$left" -lt "$limit" ] && limit=$left
  if [ "$limit" -lt 5 ]; then
    say "$name: skipped, the deadline is near"
    printf '{"name": "%s", "status": "skipped", "seconds": 0, "limit": 0}\n' "$name" >>"$steps"
    failed=1
    return 1
  fi
  local t0=$SECONDS
  say "$name (limit ${limit} s)"
  timeout -k 5 "$limit" bash -c "$cmd" >"$work/logs/$name.log" 2>&1
  local rc=$? status=ok
  if [ $rc = 124 ] || [ $rc = 137 ]; then status=timeout; elif [ $rc != 0 ]; then status=failed; fi
  [ $status = ok ] || failed=1
  say "$name: $status in $((SECONDS - t0)) s"
  [ $status = ok ] || tail -n 5 "$work/logs/$name.log" | sed 's/^/    /' >&2
  printf '{"name": "%s", "status": "%s", "rc": %d, "seconds": %d, "limit": %d}\n' "$name" "$status" $rc \
    $((SECONDS - t0)) "$limit" >>"$steps"
  [ $status = ok ]
}

# 0. Shader variants: which edit of a refused program this driver takes (docs/GPU.md).
if [ -n "$variants_dir" ]; then
  variants_dir=$(cd "$variants_dir" && pwd) || exit 2
  step shader_variants 60 "
    for v in \$(ls -d $variants_dir/*/ | sort); do
      v=\${v%/}
      if NESTLIGHT_SHADER_DIR=\$v $NL gl-info --programs --only \$(tr -s ' \\n' ',' < \$v/programs | sed 's/,\$//') \\
          --json $work/res/variant-\$(basename \$v).json > $work/logs/variant-\$(basename \$v).log 2>&1; then
        echo \"\$(basename \$v) links\"; echo \$v >> $work/variants-ok
      else
        echo \"\$(basename \$v) fails\"; grep -m3 -E 'error|fatal' $work/logs/variant-\$(basename \$v).log | sed 's/^/    /'
      fi
    done"
  if [ -s "$work/variants-ok" ]; then
    export NESTLIGHT_SHADER_DIR=$(head -n 1 "$work/variants-ok")
    say "shader folder for the rest of the run: $NESTLIGHT_SHADER_DIR"
  fi
  cp "$work/logs/shader_variants.log" "$out/variants.txt" 2>/dev/null
fi

if [ $quick = 1 ]; then
  points=200k; W=64; H=36; pbgi_size=32; runs=1
  vpls="16 64"; mbs="8"; variants="classic x"; estimators="smc"
  gi_points=20k; gi_size="--width 24 --height 16"; gi_ref="--reference-time-limit 2 --reference-spp 16"
  gi_methods="--methods raster,vpl --no-variants"
else
  points=100M; W=1920; H=1080; pbgi_size=512; runs=5
  vpls="256 1024 4096"; mbs="16 32"; variants="classic mip x"; estimators="mis bis smc"
  gi_points=300k; gi_size=""; gi_ref="--reference-time-limit 40"
  gi_methods=""
fi
[ -n "$runs_override" ] && runs=$runs_override

# 1. Context and every shader program.
step gl_info 60 "$NL gl-info --programs --json $work/res/gl-info.json"

# 2. The GL test suites, side by side (each prints per-test lines the report reads). The full
# run's filters leave out the window tests of `viewer`: they need Xvfb, which the GPU machine lacks.
suites=""
tests_cmd=""
while read -r name full quick_filter; do
  case "$name" in ''|'#'*) continue ;; esac
  filter=$([ $quick = 1 ] && echo "$quick_filter" || echo "$full")
  for f in "${suite_filters[@]}"; do [ "${f%%=*}" = "$name" ] && filter=${f#*=}; done
  [ "$filter" = "-" ] && continue
  suites="$suites $name"
  tests_cmd="$tests_cmd
  mkdir -p $work/tests-$name
  (cd $work/tests-$name && $(suite ${name}_tests) --gtest_filter='$filter' --gtest_output=json:$work/res/tests-$name.json > $work/logs/tests-$name.log 2>&1; echo \$? > rc) &"
done < scripts/gpu-suites.txt
step tests $([ $quick = 1 ] && echo 60 || echo 150) "$tests_cmd
  wait
  for s in $suites; do test \"\$(cat $work/tests-\$s/rc)\" = 0 || exit 1; done"
# Diff images of failed golden tests come back with the details.
cp "$work"/tests-*/render-*.png "$work/res/" 2>/dev/null

# 3-5 run on one scene: the object scene (a synthetic town scan, a gold torus, sky and sun) with
# its scan at the run's size, plus a spot light on the torus.
step scene $([ $quick = 1 ] && echo 60 || echo 150) "
  $NL make-scene object -o $work/object -n $points --width $W --height $H &&
  python3 scripts/gpu-report.py add-spot $work/object/scene.json $work/scene.json > $work/res/scene.txt"
octree=$(sed -n 's/^octree //p' "$work/res/scene.txt" 2>/dev/null)

if [ -n "$octree" ]; then
  step render 60 "$NL bench render $octree --width $W --height $H --runs $runs --json $work/res/bench-render.json"
  step stream $([ $quick = 1 ] && echo 30 || echo 60) \
    "$NL bench stream $octree $([ $quick = 1 ] && echo '--frames 10 --teleports 2' || echo '--frames 120 --teleports 8') --json $work/res/bench-stream.json"
  step stream_path $([ $quick = 1 ] && echo 30 || echo 60) "
    python3 scripts/gpu-report.py path $octree $work/path.json $([ $quick = 1 ] && echo 0.5 || echo 6) &&
    mkdir -p $work/frames &&
    $NL render $octree --path $work/path.json -o $work/frames/f_%04d.png --width $W --height $H --stats $work/res/stream-path.csv"
  frame() {  # NAME SIZE ARGS...
    local name=$1 size=$2
    shift 2
    step "frame_$name" $([ $quick = 1 ] && echo 30 || echo 40) \
      "$NL bench frame $work/scene.json $size --runs $runs --json $work/res/frame-$name.json $*"
  }
  frame raster "--width $W --height $H" --method raster
  for n in $vpls; do frame "vpl_$n" "--width $W --height $H" --method vpl --param vpls=$n; done
  for v in $variants; do
    for m in $mbs; do
      frame "pbgi_${v}_$m" "--width $pbgi_size --height $pbgi_size" --method pbgi --param variant=$v --param micro_buffer=$m
    done
  done
  for e in $estimators; do frame "ibl_$e" "--width $W --height $H" --method ibl --param estimator=$e; done
  frame projection "--width $W --height $H" --method projection
  # Differential rendering on its own scene (the cornell room's scan, its capture baked on every
  # core, an inserted sphere): the paper's queries at medium quality.
  step diffrender_scene $([ $quick = 1 ] && echo 30 || echo 60) "
    $NL make-scene diffrender -o $work/dr -n $gi_points --width $W --height $H --bake-spp 8 -q"
  if [ -f "$work/dr/scene.json" ]; then
    for q in dit em vct; do
      step "frame_diffrender_$q" $([ $quick = 1 ] && echo 30 || echo 40) \
        "$NL bench frame $work/dr/scene.json --width $W --height $H --runs $runs --json $work/res/frame-diffrender_$q.json --method diffrender --param query=$q"
    done
  fi
  # A picture of each GI method on the big scene.
  for m in vpl pbgi ibl; do
    step "image_$m" 40 "$NL render $work/scene.json --method $m --still -o $work/$m.exr && cp $work/$m.png $out/$m.png"
  done
else
  say "no scene: steps 3 to 5 not run"
  failed=1
fi

# 6. Speed against error, the reference on every core.
for s in cornell object; do
  step "bench_gi_$s" $([ $quick = 1 ] && echo 60 || echo 90) "
    $NL make-scene $s -o $work/gi-$s -n $gi_points -q &&
    $NL bench gi $work/gi-$s/scene.json -o $work/res/bench-gi-$s --runs $([ $quick = 1 ] && echo 1 || echo 3) $gi_size $gi_ref $gi_methods"
done

say "writing the report to $out"
python3 scripts/gpu-report.py report "$work" "$out" --quick $quick --threads "$threads" --deadline "$deadline" ||
  { say "the report could not be written"; failed=1; }
tar -C "$work" -czf "$out/details.tar.gz" res logs steps.jsonl 2>/dev/null
say "done: $(grep -c '"ok"' "$steps") of $(wc -l <"$steps") steps ok"
exit $failed
