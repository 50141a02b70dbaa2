// The image library's PNG half: display-referred values survive a round trip to the nearest 8-bit
// code; NaN shows magenta; a bad file is named.
#include <gtest/gtest.h>

#include <cmath>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

using namespace nestlight;

TEST(ImageIo, PngRoundTripsToTheNearestCode) {
  test::TempDir t;
  gi::HdrImage img(5, 2);
  const float values[] = {0.0f, 0.2f, 0.5f, 0.999f, 1.0f, -1.0f, 7.0f, NAN, 0.25f, 0.75f};
  for (int i = 0; i < 10; ++i) img.set(i % 5, i / 5, gi::Rgb(values[i], values[i] * 0.5f, 0.1f));
  gi::writePng(t.file("a.png"), img);
  const gi::HdrImage back = gi::readPng(t.file("a.png"));
  ASSERT_EQ(back.width, 5);
  ASSERT_EQ(back.height, 2);
  for (int i = 0; i < 10; ++i) {
    const gi::Rgb c = back.get(i % 5, i / 5);
    if (std::isnan(values[i])) {
      EXPECT_EQ(c.r, 1.0f);
      EXPECT_EQ(c.g, 0.0f);
      EXPECT_EQ(c.b, 1.0f);
      continue;
    }
    const float want = std::round(std::clamp(values[i], 0.0f, 1.0f) * 255.0f) / 255.0f;
    EXPECT_EQ(c.r, want) << values[i];
  }
  test::writeFile(t.file("bad.png"), "not a png");
  Error e = test::errorOf([&] { gi::readPng(t.file("bad.png")); });
  EXPECT_NE(std::string(e.what()).find("bad.png"), std::string::npos) << e.what();
}
