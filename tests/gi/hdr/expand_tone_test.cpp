// HDR expansion with photographs that are not the scan's colour times one exposure: generated
// from the ground-truth protocol's room, the photograph sees the whole room while the scan lacks
// everything above 2.9 m (the ceiling, its lamp, the top of the walls: background the scan has
// not got), and its tone is the true radiance through a known curve (an exposure change, two
// gammas, a filmic S-curve, a camera's log curve). Each expansion must bring the scan closer to
// the truth than its LDR colour (relative L2 over every point), or be refused with an error that
// says which check failed and what to pass; `force` writes it anyway, bounded by the photograph.
// Small on purpose (100k points, a 200 x 150 photograph, 96-pixel cube faces): no GL involved,
// but ASan runs these too.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "gi/hdr/small_expand.h"
#include "nestlight/bench/hdr_protocol.h"
#include "nestlight/converters/verify.h"
#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/exposure.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"
#include "test_support.h"

namespace nestlight::gi::hdr {
namespace {

namespace fs = std::filesystem;

// The whole room (its photograph is the source of every generated one) and the scan lacking its
// top, built once (about 2 s).
struct Scenes {
  fs::path full, cropped;
  HdrImage photo;  // the whole room's true radiance from protocolPhotoView
  // The same with a sky where the cropped scan does not render (its top, lamp included): a smooth
  // gradient of 0.6 to 3.5 times the scan's clipping, bright but no light source.
  HdrImage skyPhoto;
  // 1 where the cropped scan renders in the photograph (what a user would paint white), else 0.
  std::vector<uint8_t> sceneMask;
};
const Scenes& scenes() {
  static test::TempDir* tmp = new test::TempDir();  // outlives the tests
  static const Scenes s = [] {
    Scenes r;
    bench::ProtocolOptions o;
    o.points = 100'000;
    o.photoWidth = 200;
    o.photoHeight = 150;
    bench::makeHdrProtocol(tmp->path() / "full", o);
    o.maxHeight = 2.9;
    bench::makeHdrProtocol(tmp->path() / "cropped", o);
    r.full = tmp->path() / "full";
    r.cropped = tmp->path() / "cropped";
    r.photo = readHdrImage((r.full / "photo.exr").string());
    OctreeReader reader(r.cropped / "scan.octree");
    ScanAccess scan(reader);
    const auto cover = renderViews(scan, {bench::protocolPhotoView(r.photo.width, r.photo.height)},
                                   Payload::Display8)[0]
                           .coverage();
    r.skyPhoto = r.photo;
    r.sceneMask = cover;
    for (int y = 0; y < r.photo.height; ++y)
      for (int x = 0; x < r.photo.width; ++x)
        if (!cover[size_t(y) * size_t(r.photo.width) + size_t(x)]) {
          // Radiance (absolute units; the scan recorded half of it): brighter towards the top.
          const float b = 1.2f + 5.8f * (1.0f - float(y) / float(r.photo.height));
          r.skyPhoto.set(x, y, Rgb(0.6f * b, 0.8f * b, 1.0f * b));
        }
    return r;
  }();
  return s;
}

// Relative L2 distance of a layer ("ldr": the scan's own colour, linear) from the truth layer
// over every point: |layer - truth| / |truth|, channels and points together.
double relativeL2(const fs::path& octree, const std::string& layer) {
  OctreeReader reader(octree);
  ScanAccess scan(reader);
  const Metadata& m = reader.metadata();
  const ColourLayerReader truth(octree, m, "truth");
  std::unique_ptr<ColourLayerReader> other;
  if (layer != "ldr") other = std::make_unique<ColourLayerReader>(octree, m, layer);
  double num = 0, den = 0;
  for (const auto& [key, e] : reader.allNodes()) {
    const std::vector<float> t = truth.readNode(key, e.numPoints);
    std::vector<float> v;
    if (other) {
      v = other->readNode(key, e.numPoints);
    } else {
      const ScanNode n = scan.read(key, e);
      for (const glm::vec3& c : n.ldr) v.insert(v.end(), {c.r, c.g, c.b});
    }
    for (size_t i = 0; i < t.size(); ++i)
      num += double(v[i] - t[i]) * (v[i] - t[i]), den += double(t[i]) * t[i];
  }
  return std::sqrt(num / den);
}

struct Tone {
  const char* name;
  std::function<float(float)> curve;  // per channel, of the true radiance (absolute units)
  // What the expansion must do, registered and not: improve on the LDR colour (nullptr), or be
  // refused by the check whose words are given.
  const char *registeredRefusal, *unregisteredRefusal;
};

// The scan recorded the truth times 0.5; the photographs below are the truth through each curve.
// "exposure" is the control: a pure exposure change (times 4, so e = 1/8), only the background
// differs. The gamma of 0.8 compresses mildly: the clipped floor's 2 to 4 times the clipping come
// out somewhat low, still far closer than 1. The gamma of 1.4 expands: the clipped points would
// come out several times too bright (relative L2 1.96 against the LDR colour's 0.71, measured
// with the checks off), and its highlight slope (1.32) says so. The filmic curve (Narkowicz's fit
// of ACES) is steeper than an exposure change in the scan's upper mid-tones (highlight slope
// 1.21) and only rolls off beyond the clipping, which the pairs cannot see: it is refused,
// conservatively (written anyway it measured 0.61, an improvement). The camera's log curve
// flattens everything: no exposure puts its brightest value beyond the clipping.
// Unregistered, the sky makes the histogram search pair the scan's clipping with the sky's top
// (2^-5.5 where the truth is 2^-3), the matches made at that exposure agree with it, and the
// exposed photograph then ends at the clipping: every curve is refused by the plausible range.
// (Unregistered expansions that help are expand_test.cpp's: the whole room, no background.)
// The thresholds are ExpandOptions' defaults, not tuned to these cases.
constexpr const char* kRange = "plausible range";
constexpr const char* kSlope = "times as fast";
const std::vector<Tone>& tones() {
  static const std::vector<Tone> t = {
      {"exposure", [](float x) { return 4.0f * x; }, nullptr, kRange},
      {"gamma 0.8", [](float x) { return std::pow(x, 0.8f); }, nullptr, kRange},
      {"gamma 1.4", [](float x) { return std::pow(x, 1.4f); }, kSlope, kRange},
      {"filmic",
       [](float x) {
         const float v = 0.25f * x;
         return 100.0f * (v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f);
       },
       kSlope, kRange},
      {"camera log", [](float x) { return std::log2(1.0f + 16.0f * x); }, kRange, kRange},
  };
  return t;
}

HdrImage toned(const Tone& tone, bool sky = false) {
  HdrImage p = sky ? scenes().skyPhoto : scenes().photo;
  for (float& v : p.rgb) v = tone.curve(std::max(v, 0.0f));
  return p;
}

fs::path freshCopy(const test::TempDir& tmp, const std::string& name) {
  const fs::path to = tmp.path() / name;
  fs::copy(scenes().cropped / "scan.octree", to, fs::copy_options::recursive);
  return to;
}

// Runs one expansion and checks the outcome the tone expects. Returns the expansion's relative
// L2 (or -1 when refused).
double expectOutcome(const Tone& tone, bool registered, const char* refusal) {
  SCOPED_TRACE(std::string(tone.name) + (registered ? ", registered" : ", unregistered"));
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  // Registered, the background is the room's top with its lamp; unregistered, a sky (docs/HDR.md,
  // "What it does not do well": unregistered matches cannot tell a lamp the scan lacks from a
  // clipped region of the scan).
  const HdrImage photo = toned(tone, !registered);
  ExpandOptions o = smallExpandOptions();
  if (registered) o.photoView = bench::protocolPhotoView(photo.width, photo.height);
  const double ldr = relativeL2(dir, "ldr");
  if (!refusal) {
    const ExpandReport r = expandHdr(dir, photo, o);
    const double ours = relativeL2(dir, "hdr");
    std::printf(
        "%-10s %-12s exposure 2^%.2f (%s, histogram 2^%.2f) spread %.3f slope %.2f/%.2f matched "
        "%.1f%%: "
        "relative L2 %.4f, LDR %.4f; largest %.4g (bound %.4g)\n",
        tone.name, registered ? "registered" : "unregistered", r.log2Exposure,
        r.checks.method.c_str(), r.checks.histogramLog2, r.checks.spreadStops, r.checks.slope,
        r.checks.highlightSlope, 100 * r.checks.matchedShare, ours, ldr, r.maxValue,
        r.checks.bound);
    EXPECT_TRUE(r.checks.failed.empty());
    EXPECT_TRUE(r.warnings.empty());
    EXPECT_LE(r.maxValue, r.checks.bound);
    // Closer than the LDR colour by a margin: 0.9 of its distance (the improvements measured
    // are far larger; a draw would show the expansion did not help).
    EXPECT_LT(ours, 0.9 * ldr);
    return ours;
  }
  const Error e = test::errorOf([&] {
    const ExpandReport r = expandHdr(dir, photo, o);
    std::printf(
        "%-10s %-12s NOT refused: exposure 2^%.2f spread %.3f slope %.2f/%.2f bound %.3g matched "
        "%.1f%%: relative L2 %.4f, "
        "LDR %.4f\n",
        tone.name, registered ? "registered" : "unregistered", r.log2Exposure, r.checks.spreadStops,
        r.checks.slope, r.checks.highlightSlope, r.checks.bound, 100 * r.checks.matchedShare,
        relativeL2(dir, "hdr"), ldr);
  });
  const std::string what = e.what();
  std::printf("%-10s %-12s refused: %s\n", tone.name, registered ? "registered" : "unregistered",
              what.c_str());
  // The error says why (the check expected, with its numbers) and what to pass.
  EXPECT_NE(what.find(refusal), std::string::npos) << what;
  EXPECT_NE(what.find("--exposure"), std::string::npos) << what;
  EXPECT_NE(what.find("--force"), std::string::npos) << what;
  if (!registered) {
    EXPECT_NE(what.find("--photo-view"), std::string::npos) << what;
  }
  EXPECT_NE(what.find("--photo-mask"), std::string::npos) << what;
  EXPECT_EQ(OctreeReader(dir).metadata().layer("hdr"), nullptr)
      << "a refused expansion writes no layer";
  return -1;
}

class ToneCurves : public ::testing::TestWithParam<size_t> {};

TEST_P(ToneCurves, RegisteredExpandsCloserThanLdrOrRefuses) {
  const Tone& t = tones()[GetParam()];
  expectOutcome(t, true, t.registeredRefusal);
}

TEST_P(ToneCurves, UnregisteredExpandsCloserThanLdrOrRefuses) {
  const Tone& t = tones()[GetParam()];
  expectOutcome(t, false, t.unregisteredRefusal);
}

INSTANTIATE_TEST_SUITE_P(Expand, ToneCurves, ::testing::Range(size_t(0), size_t(5)),
                         [](const auto& info) {
                           std::string n = tones()[info.param].name;
                           for (char& c : n)
                             if (c == ' ' || c == '.') c = '_';
                           return n;
                         });

// The exposure of a registered photograph comes from the pixels the scan covers: with a sky the
// scan lacks in the frame, the histogram search of eq. 1-2 pairs the scan's clipping with the
// sky's top and lands stops away from the true 2^-3 (measured 2^-5.5); the pairs find it.
// Tolerance 0.1 stops: the pairs are 8-bit display values of a rendering (a step is 1% of
// mid-grey, 0.015 stops), their median is far finer.
TEST(ExpandExposure, RegisteredFromTheCoverageNotTheBackground) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[0], true);
  ExpandOptions o = smallExpandOptions();
  o.photoView = bench::protocolPhotoView(photo.width, photo.height);
  const ExpandReport r = expandHdr(dir, photo, o);
  EXPECT_EQ(r.checks.method, "photo-view");
  EXPECT_LT(relativeL2(dir, "hdr"), 0.9 * relativeL2(dir, "ldr"));
  EXPECT_NEAR(r.log2Exposure, -3.0, 0.1);
  EXPECT_LT(r.checks.spreadStops, 0.2);
  // What the paper's search makes of the same photograph (on record for the unregistered case).
  std::vector<float> y;
  for (size_t i = 0; i < photo.pixels(); ++i)
    if (const float v =
            luminance(Rgb(photo.rgb[3 * i], photo.rgb[3 * i + 1], photo.rgb[3 * i + 2]));
        v > 0)
      y.push_back(v);
  OctreeReader reader(dir);
  ScanAccess scan(reader);
  std::vector<float> scanY;
  for (const auto& [key, e] : reader.allNodes())
    for (const glm::vec3& c : scan.read(key, e).ldr) scanY.push_back(luminance(Rgb(c)));
  const ExposureSearch hist = findBestExposure(y, luminanceHistogram(scanY));
  EXPECT_GT(std::fabs(hist.log2Exposure + 3.0), 1.0)
      << "the histogram search is not misled: the test shows nothing";
  std::printf(
      "histogram search: 2^%.2f; from the coverage: 2^%.3f (spread %.3f stops, %llu pairs)\n",
      hist.log2Exposure, r.log2Exposure, r.checks.spreadStops, (unsigned long long)r.checks.pairs);
  // The info the layer records: the exposure and its checks.
  const OctreeReader written(dir);
  const LayerRecord* layer = written.metadata().layer("hdr");
  ASSERT_NE(layer, nullptr);
  ASSERT_TRUE(layer->build.contains("exposure"));
  EXPECT_EQ(layer->build["exposure"]["method"], "photo-view");
  EXPECT_NEAR(layer->build["exposure"]["spread_stops"].get<double>(), r.checks.spreadStops, 1e-9);
  EXPECT_NEAR(layer->build["exposure_log2"].get<double>(), r.log2Exposure, 1e-9);
}

// A refused photograph written with force: the failed checks become warnings recorded in the
// layer, and no value exceeds the photograph's largest times the exposure (the in-fill would
// carry a few matched values beyond it).
TEST(ExpandExposure, ForceWritesWithWarningsAndBoundedValues) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[2]);  // gamma 1.4: refused above
  ExpandOptions o = smallExpandOptions();
  o.photoView = bench::protocolPhotoView(photo.width, photo.height);
  o.force = true;
  const ExpandReport r = expandHdr(dir, photo, o);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_EQ(r.warnings, r.checks.failed);
  // Registered, the bound is the photograph's largest value where the scan renders, times e.
  EXPECT_LE(r.checks.bound,
            std::max(1.0, std::exp2(r.log2Exposure) * r.checks.photoMax) * (1 + 1e-6));
  EXPECT_LE(r.maxValue, r.checks.bound);
  EXPECT_TRUE(verifyOctree(dir).ok());
  const OctreeReader written(dir);
  const LayerRecord* layer = written.metadata().layer("hdr");
  ASSERT_NE(layer, nullptr);
  EXPECT_EQ(layer->build["warnings"].size(), r.warnings.size());
  // Half floats: the written largest value within 2^-10 of the bound's scale.
  EXPECT_LE(double(r.maxValue), r.checks.bound * (1 + 1e-3));
}

// Unregistered, a pure exposure change (times 4) with the lamp the scan lacks in the frame: the
// exposure comes out right and its checks pass, yet cube-map matches of clipped points to the
// lamp's glow made the written layer 2.66 against the LDR colour's 0.71 (values up to 370 times
// the clipping, the truth's largest being 5.7). With stray matches rejected
// (ExpandOptions::maxLocalRatio) it measures 0.31; it must stay closer to the truth than the LDR
// colour by the tones' margin, or be refused by a named check.
TEST(ExpandExposure, UnregisteredLampExpandsCloserThanLdrOrRefuses) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[0], false);
  const ExpandOptions o = smallExpandOptions();
  const double ldr = relativeL2(dir, "ldr");
  try {
    const ExpandReport r = expandHdr(dir, photo, o);
    const double ours = relativeL2(dir, "hdr");
    std::printf(
        "unregistered lamp: exposure 2^%.2f spread %.3f slope %.2f/%.2f matched %.1f%% projected "
        "%llu of %llu: relative L2 %.4f, LDR %.4f; largest %.4g (bound %.4g)\n",
        r.log2Exposure, r.checks.spreadStops, r.checks.slope, r.checks.highlightSlope,
        100 * r.checks.matchedShare, (unsigned long long)r.projected,
        (unsigned long long)r.overexposed, ours, ldr, r.maxValue, r.checks.bound);
    std::printf("stray matches rejected: %llu pixels\n", (unsigned long long)r.strayPixels);
    EXPECT_TRUE(r.checks.failed.empty());
    EXPECT_LE(r.maxValue, r.checks.bound);
    EXPECT_LT(ours, 0.9 * ldr);
  } catch (const Error& e) {
    const std::string what = e.what();
    std::printf("unregistered lamp refused: %s\n", what.c_str());
    // Refused by a named check: the plausible range, the highlight slope, the spread or the
    // matched share.
    EXPECT_TRUE(what.find(kRange) != std::string::npos || what.find(kSlope) != std::string::npos ||
                what.find("spread over") != std::string::npos ||
                what.find("of the over-exposed points") != std::string::npos)
        << what;
    EXPECT_NE(what.find("--photo-view"), std::string::npos) << what;
    EXPECT_NE(what.find("--force"), std::string::npos) << what;
    EXPECT_EQ(OctreeReader(dir).metadata().layer("hdr"), nullptr);
  }
}

// A mask over what the scan lacks (painted from the cropped scan's coverage, as a user would paint
// the ceiling and its lamp, or the sky) lets an unregistered photograph expand where it was
// refused or misled: unmasked, the sky pairs the scan's clipping with its top and the plausible
// range refuses every tone (ToneCurves above); the lamp's glow drew stray matches. Masked, the
// histogram, the matches and the bound see the room alone. The exposure tolerance is 0.35 stops
// (measured 2^-2.74 where the truth is 2^-3): unregistered, the matches are made at the histogram
// search's exposure and their pairs lean towards it; the layer still lands far closer than LDR.
TEST(ExpandExposure, AMaskLetsAnUnregisteredPhotographWithBackgroundExpand) {
  // A hand-painted mask is rarely exact: one case's is drawn 3 pixels inside the coverage.
  const int w = scenes().photo.width, h = scenes().photo.height;
  std::vector<uint8_t> inside = scenes().sceneMask;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int d = -3; d <= 3 && inside[size_t(y) * size_t(w) + size_t(x)]; ++d)
        for (int e = -3; e <= 3; ++e) {
          const int qx = std::clamp(x + d, 0, w - 1), qy = std::clamp(y + e, 0, h - 1);
          if (!scenes().sceneMask[size_t(qy) * size_t(w) + size_t(qx)]) {
            inside[size_t(y) * size_t(w) + size_t(x)] = 0;
            break;
          }
        }
  struct Case {
    const char* name;
    const Tone& tone;
    bool sky;
    const std::vector<uint8_t>& mask;
  };
  const Case cases[] = {{"exposure, sky", tones()[0], true, scenes().sceneMask},
                        {"exposure, lamp, 3 px inside", tones()[0], false, inside},
                        {"gamma 0.8, sky", tones()[1], true, scenes().sceneMask}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    test::TempDir tmp;
    const fs::path dir = freshCopy(tmp, "scan.octree");
    const HdrImage photo = toned(c.tone, c.sky);
    ExpandOptions o = smallExpandOptions();
    o.photoMask = c.mask;
    const double ldr = relativeL2(dir, "ldr");
    const ExpandReport r = expandHdr(dir, photo, o);
    const double ours = relativeL2(dir, "hdr");
    std::printf(
        "masked %-28s exposure 2^%.2f (histogram 2^%.2f) spread %.3f matched %.1f%%: "
        "relative L2 %.4f, LDR %.4f; largest %.4g (bound %.4g)\n",
        c.name, r.log2Exposure, r.checks.histogramLog2, r.checks.spreadStops,
        100 * r.checks.matchedShare, ours, ldr, r.maxValue, r.checks.bound);
    EXPECT_TRUE(r.checks.failed.empty());
    EXPECT_LT(ours, 0.9 * ldr);
    if (&c.tone == &tones()[0]) {
      EXPECT_NEAR(r.log2Exposure, -3.0, 0.35);
    }
    // The photograph's largest value is the masked-in pixels' (the sky and the lamp do not count).
    double inside = 0;
    for (size_t i = 0; i < photo.pixels(); ++i)
      if (o.photoMask[i])
        for (int k = 0; k < 3; ++k) inside = std::max(inside, double(photo.rgb[3 * i + size_t(k)]));
    EXPECT_DOUBLE_EQ(r.checks.photoMax, inside);
    EXPECT_LE(r.maxValue, r.checks.bound);
  }
}

// A mask of another size, or one that leaves nothing, is refused before any work.
TEST(ExpandExposure, AMaskOfAnotherSizeOrAllBlackIsRefused) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[0], true);
  ExpandOptions o = smallExpandOptions();
  o.photoMask.assign(photo.pixels() - 1, 1);
  EXPECT_NE(std::string(test::errorOf([&] { expandHdr(dir, photo, o); }).what()).find("photo mask"),
            std::string::npos);
  o.photoMask.assign(photo.pixels(), 0);
  EXPECT_NE(std::string(test::errorOf([&] { expandHdr(dir, photo, o); }).what())
                .find("mask lets it count"),
            std::string::npos);
  EXPECT_EQ(OctreeReader(dir).metadata().layer("hdr"), nullptr);
}

// The command line: the mask is a PNG at the photograph's size; one of another size is refused
// naming the file and both sizes.
TEST(ExpandExposure, CliTakesAPngMask) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[0], true);
  writeExr((tmp.path() / "photo.exr").string(), photo);
  HdrImage mask(photo.width, photo.height), wrong(photo.width / 2, photo.height / 2);
  for (size_t i = 0; i < photo.pixels(); ++i)
    if (scenes().sceneMask[i]) mask.rgb[3 * i] = mask.rgb[3 * i + 1] = mask.rgb[3 * i + 2] = 1.0f;
  writePng((tmp.path() / "mask.png").string(), mask);
  writePng((tmp.path() / "wrong.png").string(), wrong);
  const std::string base = "expand-hdr " + dir.string() + " --photo " +
                           (tmp.path() / "photo.exr").string() +
                           " --auto-views 2 --face-size 96 -q --photo-mask ";
  std::string out;
  EXPECT_NE(test::runCli(base + (tmp.path() / "wrong.png").string(), &out), 0);
  EXPECT_NE(out.find("wrong.png"), std::string::npos) << out;
  EXPECT_NE(out.find("photograph's size"), std::string::npos) << out;
  EXPECT_EQ(test::runCli(base + (tmp.path() / "mask.png").string(), &out), 0) << out;
  const OctreeReader written(dir);
  const LayerRecord* layer = written.metadata().layer("hdr");
  ASSERT_NE(layer, nullptr);
  EXPECT_NE(layer->build.dump().find("mask.png"), std::string::npos) << layer->build.dump();
}

// A forced exposure is used as given: no estimate, the checks measured but not stopping.
TEST(ExpandExposure, AForcedExposureIsUsedAsGiven) {
  test::TempDir tmp;
  const fs::path dir = freshCopy(tmp, "scan.octree");
  const HdrImage photo = toned(tones()[2]);
  ExpandOptions o = smallExpandOptions();
  o.photoView = bench::protocolPhotoView(photo.width, photo.height);
  o.log2Exposure = -2.5;
  o.minMatchedShare = 0;
  const ExpandReport r = expandHdr(dir, photo, o);
  EXPECT_EQ(r.checks.method, "forced");
  EXPECT_DOUBLE_EQ(r.log2Exposure, -2.5);
  EXPECT_GT(r.checks.highlightSlope, o.maxHighlightSlope);  // measured, recorded, not fatal
  EXPECT_TRUE(r.checks.failed.empty());
}

}  // namespace
}  // namespace nestlight::gi::hdr
