// `nestlight compare` as a user meets it: --help names every metric, a table or JSON whose
// numbers match known answers, the error image, .hdr input, non-finite pixels reported, and bad
// input (missing file, sizes that differ, nothing comparable, a bad range) failing with exit
// code 1 and a message that names the file.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "test_support.h"

using nestlight::gi::HdrImage;
using nestlight::gi::writeExr;
using nestlight::test::readFile;
using nestlight::test::runCli;
using nestlight::test::TempDir;
using nestlight::test::writeFile;

namespace {

// Multiples of 1/64 below 4: an offset of 1/4 then gives RMSE 0.25 exactly (see metrics_test).
HdrImage dyadic(int w, int h, float offset = 0) {
  HdrImage img(w, h);
  for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = float((i * 37) % 256) / 64.0f + offset;
  return img;
}

nlohmann::json compareJson(const std::string& args) {
  std::string out;
  EXPECT_EQ(runCli("compare --json " + args, &out), 0) << out;
  try {
    return nlohmann::json::parse(out);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what() << "\n" << out;
    return {};
  }
}

uint32_t be32(const std::string& s, size_t at) {
  return (uint32_t(uint8_t(s[at])) << 24) | (uint32_t(uint8_t(s[at + 1])) << 16) |
         (uint32_t(uint8_t(s[at + 2])) << 8) | uint32_t(uint8_t(s[at + 3]));
}

}  // namespace

TEST(CompareCli, HelpExplainsEveryMetric) {
  std::string out;
  EXPECT_EQ(runCli("compare --help", &out), 0) << out;
  for (const char* s :
       {"Usage", "RMSE", "relative MSE", "PSNR", "SSIM", "Wang", "tone-mapped", "non-finite",
        "--error-image", "--error-range", "--exposure", "--json", "Exit status"})
    EXPECT_NE(out.find(s), std::string::npos) << s << "\n" << out;
  EXPECT_EQ(runCli("--help", &out), 0);
  EXPECT_NE(out.find("compare"), std::string::npos) << out;
}

TEST(CompareCli, IdenticalImagesPrintATable) {
  TempDir t;
  writeExr(t.file("a.exr"), dyadic(16, 8));
  std::string out;
  ASSERT_EQ(runCli("compare " + t.file("a.exr") + " " + t.file("a.exr"), &out), 0) << out;
  for (const char* s : {"RMSE", "relative MSE", "PSNR", "SSIM", "linear HDR", "tone-mapped", "16x8",
                        "128 compared of 128", "non-finite test 0 pixels"})
    EXPECT_NE(out.find(s), std::string::npos) << s << "\n" << out;
  EXPECT_NE(out.find("inf"), std::string::npos) << out;  // PSNR of identical images
  EXPECT_EQ(out.find("warning"), std::string::npos) << out;
}

TEST(CompareCli, JsonCarriesKnownAnswers) {
  TempDir t;
  writeExr(t.file("ref.exr"), dyadic(16, 8));
  writeExr(t.file("test.exr"), dyadic(16, 8, 0.25f));
  const nlohmann::json j =
      compareJson(t.file("test.exr") + " " + t.file("ref.exr") + " --exposure -1");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["width"], 16);
  EXPECT_EQ(j["height"], 8);
  EXPECT_EQ(j["compared_pixels"], 128);
  EXPECT_EQ(j["linear"]["rmse"], 0.25);  // exact: dyadic values through a float EXR
  EXPECT_EQ(j["linear"]["max_absolute"], 0.25);
  EXPECT_EQ(j["exposure_stops"], -1.0);
  EXPECT_EQ(j["test_file"], t.file("test.exr"));
  EXPECT_EQ(j["reference_file"], t.file("ref.exr"));
  EXPECT_TRUE(j["linear"]["psnr_db"].is_number());
  EXPECT_GT(j["tone_mapped"]["ssim"].get<double>(), 0.0);
  EXPECT_LT(j["tone_mapped"]["ssim"].get<double>(), 1.0);
  EXPECT_EQ(j["non_finite"]["test"]["pixels"], 0);
  EXPECT_FALSE(j.contains("error_image"));
  // Identical images: PSNR is infinite, which JSON can only carry as a string.
  EXPECT_EQ(compareJson(t.file("ref.exr") + " " + t.file("ref.exr"))["linear"]["psnr_db"], "inf");
}

TEST(CompareCli, ErrorImageHasTheImagesSizeAndTheLegendIsReported) {
  TempDir t;
  writeExr(t.file("ref.exr"), dyadic(13, 7));
  writeExr(t.file("test.exr"), dyadic(13, 7, 0.25f));
  nlohmann::json j = compareJson(t.file("test.exr") + " " + t.file("ref.exr") + " --error-image " +
                                 t.file("e.png"));
  const std::string png = readFile(t.file("e.png"));
  ASSERT_GE(png.size(), 24u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_EQ(be32(png, 16), 13u);  // IHDR width
  EXPECT_EQ(be32(png, 20), 7u);   // IHDR height
  EXPECT_EQ(j["error_image"]["file"], t.file("e.png"));
  EXPECT_EQ(j["error_image"]["min_relative"], 0.001);
  EXPECT_EQ(j["error_image"]["max_relative"], 1.0);
  EXPECT_EQ(j["error_image"]["colour_map"], "viridis");

  j = compareJson(t.file("test.exr") + " " + t.file("ref.exr") + " --error-image " +
                  t.file("f.png") + " --error-range 0.01 10");
  EXPECT_EQ(j["error_image"]["min_relative"], 0.01);
  EXPECT_EQ(j["error_image"]["max_relative"], 10.0);

  std::string out;
  ASSERT_EQ(runCli("compare " + t.file("test.exr") + " " + t.file("ref.exr") + " --error-image " +
                       t.file("g.png"),
                   &out),
            0)
      << out;
  EXPECT_NE(out.find("viridis"), std::string::npos) << out;  // the legend in the table's report
}

TEST(CompareCli, RadianceHdrIsAccepted) {
  TempDir t;
  // 2x2 flat (uncompressed) RGBE: mantissa m and exponent e give m * 2^(e - 136).
  std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n";
  const unsigned char px[] = {128, 128, 128, 129,   // 1.0
                              128, 128, 128, 128,   // 0.5
                              128, 128, 128, 130,   // 2.0
                              192, 192, 192, 128};  // 0.75
  hdr.append(reinterpret_cast<const char*>(px), sizeof px);
  writeFile(t.file("a.hdr"), hdr);
  HdrImage same(2, 2);
  const float values[] = {1.0f, 0.5f, 2.0f, 0.75f};
  for (int i = 0; i < 4; ++i) same.set(i % 2, i / 2, nestlight::gi::Rgb(values[i]));
  writeExr(t.file("a.exr"), same);
  const nlohmann::json j = compareJson(t.file("a.hdr") + " " + t.file("a.exr"));
  EXPECT_EQ(j["linear"]["rmse"], 0.0);
  EXPECT_EQ(j["compared_pixels"], 4);
}

TEST(CompareCli, NonFinitePixelsAreReportedNotFolded) {
  TempDir t;
  HdrImage ref = dyadic(8, 8), test = dyadic(8, 8, 0.25f);
  test.set(2, 3, {std::numeric_limits<float>::quiet_NaN(), 0, 0});
  test.set(4, 4, {0, std::numeric_limits<float>::infinity(), 0});
  writeExr(t.file("ref.exr"), ref);
  writeExr(t.file("test.exr"), test);
  std::string out;
  ASSERT_EQ(runCli("compare " + t.file("test.exr") + " " + t.file("ref.exr"), &out), 0) << out;
  EXPECT_NE(out.find("warning: non-finite test 2 pixels (1 NaN, 1 Inf values)"), std::string::npos)
      << out;
  EXPECT_NE(out.find("62 compared of 64"), std::string::npos) << out;
  const nlohmann::json j = compareJson(t.file("test.exr") + " " + t.file("ref.exr"));
  EXPECT_EQ(j["non_finite"]["test"]["pixels"], 2);
  EXPECT_EQ(j["linear"]["rmse"], 0.25);  // the rest is off by exactly 1/4

  HdrImage nan(8, 8);
  for (float& v : nan.rgb) v = std::numeric_limits<float>::quiet_NaN();
  writeExr(t.file("nan.exr"), nan);
  EXPECT_EQ(runCli("compare " + t.file("nan.exr") + " " + t.file("ref.exr"), &out), 1) << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("nan.exr")), std::string::npos) << out;
  EXPECT_NE(out.find("no pixel is finite"), std::string::npos) << out;
}

TEST(CompareCli, BadInputFailsNamingTheFile) {
  TempDir t;
  writeExr(t.file("a.exr"), dyadic(8, 8));
  writeExr(t.file("b.exr"), dyadic(8, 6));
  std::string out;
  EXPECT_EQ(runCli("compare " + t.file("a.exr") + " " + t.file("b.exr"), &out), 1) << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("a.exr") + ": is 8x8"), std::string::npos)
      << out;
  EXPECT_NE(out.find(t.file("b.exr") + " is 8x6"), std::string::npos) << out;

  EXPECT_EQ(runCli("compare " + t.file("missing.exr") + " " + t.file("a.exr"), &out), 1) << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("missing.exr")), std::string::npos) << out;

  writeFile(t.file("junk.exr"), "not an EXR file at all");
  EXPECT_EQ(runCli("compare " + t.file("a.exr") + " " + t.file("junk.exr"), &out), 1) << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("junk.exr")), std::string::npos) << out;

  writeFile(t.file("x.png"), "");
  EXPECT_EQ(runCli("compare " + t.file("x.png") + " " + t.file("a.exr"), &out), 1) << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("x.png")), std::string::npos) << out;

  EXPECT_EQ(runCli("compare " + t.file("a.exr") + " " + t.file("a.exr") + " --error-image " +
                       t.file("e.png") + " --error-range 1 0.1",
                   &out),
            1)
      << out;
  EXPECT_NE(out.find("nestlight: error: --error-range"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(t.file("e.png")));

  EXPECT_EQ(runCli("compare " + t.file("a.exr") + " " + t.file("a.exr") + " --error-image " +
                       t.file("no/dir/e.png"),
                   &out),
            1)
      << out;
  EXPECT_NE(out.find("nestlight: error: " + t.file("no/dir/e.png")), std::string::npos) << out;

  EXPECT_NE(runCli("compare " + t.file("a.exr"), &out), 0) << out;  // the reference is required
}
