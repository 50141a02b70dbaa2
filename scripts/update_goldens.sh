#!/usr/bin/env bash
# Re-renders the golden images of tests/goldens/ on this machine (llvmpipe) and shows the change.
#   scripts/update_goldens.sh            all image tests
#   scripts/update_goldens.sh LionPoints one test (a gtest filter fragment)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
ninja -C "$BUILD_DIR" viewer_tests
NESTLIGHT_UPDATE_GOLDENS=1 "$BUILD_DIR/tests/viewer_tests" --gtest_filter="RenderGolden.*${1:-}*:WindowTools.*${1:-}*"
git status --short tests/goldens
