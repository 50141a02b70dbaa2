#!/usr/bin/env bash
# Sets up, builds and runs every test: unit tests (Release), the same under ASan+UBSan, and each
# libFuzzer target briefly. Prints ctest's summary; exits non-zero on any failure.
#   FUZZ_SECONDS=20 SKIP_SANITIZE=1 SKIP_FUZZ=1 SKIP_GPU_SCRIPTS=1 scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
# Each step says when it starts (minutes into the run), so a slow step shows in the CI log.
step() { echo "== $1 [$(( (SECONDS - start) / 60 )) min]"; }
step "set-up and Release build"
scripts/setup.sh

step "format (.clang-format) and include floors (docs/ARCHITECTURE.md)"
scripts/format.sh --check
python3 scripts/check_layers.py

step "unit tests (Release)"
ctest --test-dir build --output-on-failure -j2 --timeout 900

if [ -z "${SKIP_GPU_SCRIPTS:-}" ]; then
  # The GPU run's one command, every step at tiny sizes on llvmpipe, and the GPU bundle made from
  # this build, unpacked and run in a clean environment (docs/GPU.md).
  step "GPU run script (--quick) and GPU bundle"
  scripts/gpu-run.sh --quick --bin build --out build/gpu-quick
  scripts/gpu-bundle.sh --build-dir build --out build/gpu-bundle/nestlight-gpu-bundle.tar.xz --check
fi

if [ -z "${SKIP_SANITIZE:-}" ]; then
  step "ASan+UBSan build and unit tests"
  BUILD_DIR=build-asan BUILD_TYPE=RelWithDebInfo CMAKE_ARGS="-DNESTLIGHT_SANITIZE=ON" \
    scripts/setup.sh
  # tests/sanitizer_skips.txt: the statistical tests the Release pass runs and this one leaves out.
  skips=$(sed -e 's/#.*//' -e 's/[[:space:]]//g' -e '/^$/d' tests/sanitizer_skips.txt | paste -sd'|')
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure -j2 --timeout 1800 -E "${ASAN_EXCLUDE:-$skips}"
fi

if [ -z "${SKIP_FUZZ:-}" ]; then
  step "fuzz build and targets (${FUZZ_SECONDS:-15} s each)"
  fuzzers=$(cd tests/fuzz && ls fuzz_*.cpp | sed 's/\.cpp$//' | tr '\n' ' ')
  BUILD_DIR=build-fuzz TARGETS="$fuzzers" \
    CMAKE_ARGS="-DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14 -DNESTLIGHT_FUZZ=ON" \
    scripts/setup.sh
  for f in build-fuzz/tests/fuzz_*; do
    [ -x "$f" ] || continue
    name=$(basename "$f")
    corpus=$(mktemp -d)
    tests/fuzz/seed_corpus.sh "$name" "$corpus"
    echo "-- $name"
    "$f" -max_total_time="${FUZZ_SECONDS:-15}" -rss_limit_mb=2048 -print_final_stats=0 "$corpus" 2>&1 | tail -n 3
    rm -rf "$corpus"
  done
fi
step "all tests passed"
