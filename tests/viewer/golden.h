// Golden-image comparison for the image tests (tests/goldens/): per-test tolerances, the image
// and a diff image written beside the test binary on failure, and NESTLIGHT_UPDATE_GOLDENS=1
// (scripts/update_goldens.sh) to re-make a golden from this machine's render.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "nestlight/viewer/image.h"
#include "test_support.h"

namespace nestlight::test {

inline std::filesystem::path goldenDir() {
  return sourceDir() / "tests" / "goldens";
}

// Compares `file` with the golden `name`: a pixel differs when a channel is off by more than
// `channelTol`; at most `maxFraction` of pixels may differ.
inline void expectMatchesGolden(const std::string& file, const std::string& name, float channelTol,
                                double maxFraction) {
  const std::filesystem::path golden = goldenDir() / (name + ".png");
  const char* update = std::getenv("NESTLIGHT_UPDATE_GOLDENS");
  if (update && std::string(update) == "1") {
    std::filesystem::copy_file(file, golden, std::filesystem::copy_options::overwrite_existing);
    GTEST_SKIP() << "golden " << golden << " updated";
  }
  ASSERT_TRUE(std::filesystem::exists(golden))
      << "no golden " << golden << "; run scripts/update_goldens.sh";
  viewer::Image got = viewer::readImage(file), want = viewer::readImage(golden.string());
  viewer::ImageDiff d = viewer::compareImages(got, want, channelTol);
  // Always said, pass or fail: scripts/gpu-run.sh reports how far a GPU's image is from llvmpipe's.
  std::printf(
      "golden %s: %zu of %zu pixels differ by more than %.4f (%.3f%%), max channel error %.4f\n",
      name.c_str(), size_t(d.differing), size_t(got.width) * size_t(got.height), channelTol,
      100.0 * d.fraction, double(d.maxChannel));
  if (d.fraction > maxFraction) {
    std::filesystem::copy_file(file, "render-" + name + ".png",
                               std::filesystem::copy_options::overwrite_existing);
    viewer::writeImage(d.diff, "render-" + name + "-diff.png");
  }
  EXPECT_LE(d.fraction, maxFraction)
      << name << ": " << d.differing << " pixels differ (max channel error " << d.maxChannel
      << "); see render-" << name << "-diff.png in " << std::filesystem::current_path();
}

}  // namespace nestlight::test
