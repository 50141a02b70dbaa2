// Video light probes: frames listed from a pattern or a folder, read on demand with a bounded
// cache, and gaps and damaged frames named (or the previous frame kept, when asked).
#include "nestlight/gi/environment_sequence.h"

#include <gtest/gtest.h>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"
#include "test_support.h"

namespace nestlight::gi {
namespace {

namespace fs = std::filesystem;

// A 16 x 8 lat-long frame of one radiance everywhere.
void writeFrame(const fs::path& path, float value) {
  HdrImage img(16, 8);
  for (float& v : img.rgb) v = value;
  writeExr(path.string(), img);
}

float radianceOf(const EnvironmentMap& m) {
  return m.eval({0.0f, 0.0f, 1.0f}).r;
}

TEST(EnvironmentSequence, APatternPlaysItsFramesAtItsRateHoldingTwo) {
  test::TempDir t;
  for (int k = 3; k <= 8; ++k)
    writeFrame(
        t.path() / ("probe_" + std::string(k < 10 ? "000" : "00") + std::to_string(k) + ".exr"),
        float(k));
  writeFrame(t.path() / "other_0001.exr", 99.0f);  // another pattern's frame
  EnvironmentSequenceSpec spec;
  spec.source = t.path() / "probe_%04d.exr";
  spec.fps = 2;
  spec.scale = 0.5f;
  EnvironmentSequence seq(spec);
  ASSERT_EQ(seq.frames(), 6u);  // 3 to 8
  EXPECT_DOUBLE_EQ(seq.durationSeconds(), 3.0);
  EXPECT_EQ(seq.framePath(0).filename(), "probe_0003.exr");
  EXPECT_EQ(seq.frameAt(-1.0), 0u);
  EXPECT_EQ(seq.frameAt(0.49), 0u);
  EXPECT_EQ(seq.frameAt(0.5), 1u);
  EXPECT_EQ(seq.frameAt(100.0), 5u);
  for (size_t i = 0; i < seq.frames(); ++i) {
    EXPECT_FLOAT_EQ(radianceOf(*seq.frame(i)), 0.5f * float(i + 3));
    EXPECT_LE(seq.cachedFrames(), 2u);
  }
  EXPECT_EQ(seq.framesRead(), 6u);
  // The two most recent are held: asking again reads nothing; an older one is read again.
  seq.frame(5);
  seq.frame(4);
  EXPECT_EQ(seq.framesRead(), 6u);
  seq.frame(0);
  EXPECT_EQ(seq.framesRead(), 7u);
}

TEST(EnvironmentSequence, AFolderPlaysItsMapsInNameOrder) {
  test::TempDir t;
  writeFrame(t.path() / "b.exr", 2.0f);
  writeFrame(t.path() / "a.exr", 1.0f);
  writeFrame(t.path() / "c.EXR", 3.0f);
  test::writeFile(t.file("notes.txt"), "not a frame");
  EnvironmentSequenceSpec spec;
  spec.source = t.path();
  EnvironmentSequence seq(spec);
  ASSERT_EQ(seq.frames(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(radianceOf(*seq.frame(i)), float(i + 1));
}

TEST(EnvironmentSequence, AGapOrADamagedFrameIsNamedOrThePreviousKept) {
  test::TempDir t;
  writeFrame(t.path() / "p_1.exr", 1.0f);
  writeFrame(t.path() / "p_3.exr", 3.0f);  // p_2 missing
  writeFrame(t.path() / "p_4.exr", 4.0f);
  fs::resize_file(t.path() / "p_4.exr", fs::file_size(t.path() / "p_4.exr") / 2);  // truncated
  EnvironmentSequenceSpec spec;
  spec.source = t.path() / "p_%d.exr";
  {
    EnvironmentSequence seq(spec);
    ASSERT_EQ(seq.frames(), 4u);
    const Error gap = test::errorOf([&] { seq.frame(1); });
    EXPECT_NE(std::string(gap.what()).find("p_2.exr"), std::string::npos) << gap.what();
    EXPECT_NE(std::string(gap.what()).find("missing"), std::string::npos) << gap.what();
    const Error cut = test::errorOf([&] { seq.frame(3); });
    EXPECT_NE(std::string(cut.what()).find("p_4.exr"), std::string::npos) << cut.what();
    EXPECT_EQ(seq.badFrames(), 2u);
  }
  spec.keepPreviousOnBadFrame = true;
  EnvironmentSequence seq(spec);
  EXPECT_THROW(seq.frame(1), Error);  // nothing good read yet: nothing to keep
  EXPECT_FLOAT_EQ(radianceOf(*seq.frame(0)), 1.0f);
  EXPECT_FLOAT_EQ(radianceOf(*seq.frame(1)), 1.0f);  // the gap plays frame 0 again
  EXPECT_FLOAT_EQ(radianceOf(*seq.frame(2)), 3.0f);
  EXPECT_FLOAT_EQ(radianceOf(*seq.frame(3)), 3.0f);  // the truncated frame plays frame 2 again
  EXPECT_EQ(seq.badFrames(), 3u);
}

TEST(EnvironmentSequence, NoFramesOrNoRateIsAnErrorNamingTheSource) {
  test::TempDir t;
  EnvironmentSequenceSpec spec;
  spec.source = t.path() / "none_%04d.exr";
  const Error none = test::errorOf([&] { EnvironmentSequence s(spec); });
  EXPECT_NE(std::string(none.what()).find("none_%04d.exr"), std::string::npos) << none.what();
  spec.source = t.path() / "plain.exr";
  const Error noPattern = test::errorOf([&] { EnvironmentSequence s(spec); });
  EXPECT_NE(std::string(noPattern.what()).find("%0Nd"), std::string::npos) << noPattern.what();
  writeFrame(t.path() / "f_1.exr", 1.0f);
  spec.source = t.path() / "f_%d.exr";
  spec.fps = 0;
  const Error rate = test::errorOf([&] { EnvironmentSequence s(spec); });
  EXPECT_NE(std::string(rate.what()).find("frame rate"), std::string::npos) << rate.what();
}

// A scene's environment may be a sequence: listed when the scene is read (a pattern naming no
// frame fails with its field), lit with the frame at a time (a still: the first).
TEST(EnvironmentSequence, ASceneNamesOneByPatternAndRate) {
  test::TempDir t;
  writeFrame(t.path() / "p_1.exr", 2.0f);
  writeFrame(t.path() / "p_2.exr", 5.0f);
  test::writeFile(t.file("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  auto scene = [&](const std::string& environment) {
    test::writeFile(
        t.file("scene.json"),
        R"({"version": 1, "meshes": [{"path": "tri.obj"}], "environment": )" + environment + "}");
    return t.file("scene.json");
  };
  const Scene s = loadScene(scene(R"({"sequence": "p_%d.exr", "fps": 10, "scale": 2})"));
  ASSERT_TRUE(s.environment);
  EXPECT_EQ(s.environment->sequence, t.path() / "p_%d.exr");
  EXPECT_DOUBLE_EQ(s.environment->fps, 10.0);
  EXPECT_FLOAT_EQ(radianceOf(loadEnvironmentAt(*s.environment)), 4.0f);
  EXPECT_FLOAT_EQ(radianceOf(loadEnvironmentAt(*s.environment, 0.15)), 10.0f);
  const Error none = test::errorOf([&] { loadScene(scene(R"({"sequence": "q_%d.exr"})")); });
  EXPECT_NE(std::string(none.what()).find("environment.sequence"), std::string::npos)
      << none.what();
  const Error both =
      test::errorOf([&] { loadScene(scene(R"({"sequence": "p_%d.exr", "path": "p_1.exr"})")); });
  EXPECT_NE(std::string(both.what()).find("exactly one"), std::string::npos) << both.what();
  const Error stray = test::errorOf([&] { loadScene(scene(R"({"path": "p_1.exr", "fps": 3})")); });
  EXPECT_NE(std::string(stray.what()).find("belong to a"), std::string::npos) << stray.what();
}

}  // namespace
}  // namespace nestlight::gi
