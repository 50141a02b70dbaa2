// The GI frame's graph: declarations checked, culling, per-frame passes run once per frame, tiled
// frames equal untiled ones, the tone-map pass equals gi/metrics' tone map.
#include "nestlight/frame/frame_graph.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nestlight/frame/passes.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/program.h"
#include "nestlight/octree/error.h"
#include "test_support.h"

namespace nestlight::frame {
namespace {

void noop(const PassContext&) {}

TEST(FrameGraph, ReadBeforeWriteNamesPassAndTarget) {
  FrameGraph g;
  g.addTarget("a", {GL_RGBA16F});
  g.addTarget("out", {GL_RGBA8});
  g.addPass(
      "shade", Scope::Tile,
      [](PassBuilder& b) {
        b.read("a");
        b.write("out");
      },
      noop);
  g.addPass(
      "gbuffer", Scope::Tile, [](PassBuilder& b) { b.write("a"); }, noop);
  Error e = test::errorOf([&] { g.compile("out"); });
  EXPECT_NE(std::string(e.what()).find("pass 'shade' reads 'a' before any pass writes it"),
            std::string::npos)
      << e.what();
}

TEST(FrameGraph, ScopesAreChecked) {
  {
    FrameGraph g;
    g.addTarget("gb", {GL_RGBA16F});
    g.addTarget("out", {GL_RGBA8});
    g.addPass(
        "gbuffer", Scope::Tile, [](PassBuilder& b) { b.write("gb"); }, noop);
    g.addPass(
        "lights", Scope::Frame,
        [](PassBuilder& b) {
          b.read("gb");
          b.write("out");
        },
        noop);
    Error e = test::errorOf([&] { g.compile("out"); });
    EXPECT_NE(std::string(e.what()).find("frame pass 'lights' reads tile target 'gb'"),
              std::string::npos)
        << e.what();
  }
  {
    FrameGraph g;
    TargetDesc shadow{GL_DEPTH_COMPONENT32F, true, 64, 64};
    g.addTarget("shadow", shadow);
    g.addTarget("out", {GL_RGBA8});
    g.addPass(
        "shade", Scope::Tile,
        [](PassBuilder& b) {
          b.write("shadow");
          b.write("out");
        },
        noop);
    Error e = test::errorOf([&] { g.compile("out"); });
    EXPECT_NE(std::string(e.what()).find("tile pass 'shade' writes fixed target 'shadow'"),
              std::string::npos)
        << e.what();
  }
  FrameGraph g;
  g.addTarget("out", {GL_RGBA8});
  EXPECT_THROW(g.addTarget("out", {GL_RGBA8}), Error);
  g.addPass(
      "p", Scope::Tile, [](PassBuilder& b) { b.write("out"); }, noop);
  EXPECT_THROW(g.addPass("p", Scope::Tile, {}, noop), Error);
  EXPECT_THROW(g.compile("missing"), Error);
}

TEST(FrameGraph, PassesNobodyReadsAreCulled) {
  FrameGraph g;
  g.addTarget("a", {GL_RGBA16F});
  g.addTarget("unused", {GL_RGBA16F});
  g.addTarget("out", {GL_RGBA8});
  g.addPass(
      "make_a", Scope::Tile, [](PassBuilder& b) { b.write("a"); }, noop);
  g.addPass(
      "debug_view", Scope::Tile,
      [](PassBuilder& b) {
        b.read("a");
        b.write("unused");
      },
      noop);
  g.addPass(
      "readback", Scope::Tile,
      [](PassBuilder& b) {
        b.read("a");
        b.write("unused");
        b.sideEffect();
      },
      noop);
  g.addPass(
      "final", Scope::Tile,
      [](PassBuilder& b) {
        b.read("a");
        b.write("out");
      },
      noop);
  g.compile("out");
  EXPECT_FALSE(g.isCulled("make_a"));
  EXPECT_TRUE(g.isCulled("debug_view"));
  EXPECT_FALSE(g.isCulled("readback"));
  EXPECT_FALSE(g.isCulled("final"));
  EXPECT_NE(g.describe().find("debug_view (tile): reads a; writes unused [culled]"),
            std::string::npos)
      << g.describe();
}

// Builds palette (frame) -> pattern (tile) -> blur (tile, margin 2) -> tone map.
struct TestFrame {
  FrameGraph graph;
  gl::ShaderProgram palette{{{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                             {GL_FRAGMENT_SHADER, "tests/frame_palette.frag"}}};
  gl::ShaderProgram pattern{{{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                             {GL_FRAGMENT_SHADER, "tests/frame_pattern.frag"}}};
  gl::ShaderProgram blur{{{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                          {GL_FRAGMENT_SHADER, "tests/frame_blur.frag"}}};
  gl::VertexArray vao = gl::VertexArray::create();
  std::shared_ptr<float> exposure = std::make_shared<float>(0.0f);

  TestFrame() {
    graph.addTarget("palette", {GL_RGBA16F, true, 4, 4});
    graph.addTarget("pattern", {GL_RGBA32F});
    graph.addTarget("blurred", {GL_RGBA32F});
    graph.addTarget("display", {GL_RGBA8});
    auto draw = [this](const gl::ShaderProgram& p) {
      p.use();
      glBindVertexArray(vao.id());
      glDrawArrays(GL_TRIANGLES, 0, 3);
    };
    graph.addPass(
        "palette", Scope::Frame, [](PassBuilder& b) { b.write("palette"); },
        [=, this](const PassContext& c) {
          c.bindFramebuffer();
          draw(palette);
        });
    graph.addPass(
        "pattern", Scope::Tile,
        [](PassBuilder& b) {
          b.read("palette");
          b.write("pattern");
        },
        [=, this](const PassContext& c) {
          c.bindFramebuffer();
          c.bindTexture("palette", 0);
          draw(pattern);
        });
    graph.addPass(
        "blur", Scope::Tile,
        [](PassBuilder& b) {
          b.read("pattern");
          b.write("blurred");
          b.margin(2);
        },
        [=, this](const PassContext& c) {
          c.bindFramebuffer();
          c.bindTexture("pattern", 0);
          draw(blur);
        });
    addToneMapPass(graph, "blurred", "display", exposure);
    graph.compile("blurred");
  }
};

TEST(FrameGraph, TiledFrameEqualsUntiledAndFramePassesRunOnce) {
  auto ctx = gl::createHeadlessContext();
  TestFrame f;
  EXPECT_TRUE(f.graph.isCulled("tone_map"));  // the output is the linear image here
  const int W = 100, H = 70;
  std::vector<float> whole = f.graph.execute(W, H, 4096);
  const auto& t1 = f.graph.timings();
  ASSERT_EQ(t1.size(), 3u);
  EXPECT_EQ(t1[0].name, "palette");
  EXPECT_EQ(t1[0].runs, 1);
  EXPECT_EQ(t1[1].runs, 1);
  std::vector<float> tiled = f.graph.execute(W, H, 32);
  const auto& t2 = f.graph.timings();
  EXPECT_EQ(t2[0].runs, 1);      // per frame, whatever the tiling
  EXPECT_EQ(t2[1].runs, 4 * 3);  // ceil(100/32) x ceil(70/32) tiles
  EXPECT_EQ(t2[2].runs, 4 * 3);
  ASSERT_EQ(whole.size(), tiled.size());
  size_t differing = 0;
  for (size_t i = 0; i < whole.size(); ++i) differing += whole[i] != tiled[i];
  EXPECT_EQ(differing, 0u)
      << "tiles must reproduce the untiled frame exactly (same arithmetic per pixel)";
  // Rows come back top first: the top-left pixel has the largest GL y.
  const float* topLeft = &whole[0];
  const float* bottomLeft = &whole[4 * size_t(W) * (H - 1)];
  EXPECT_GT(topLeft[1], bottomLeft[1]);
}

TEST(FrameGraph, ToneMapPassEqualsTheMetricsToneMap) {
  auto ctx = gl::createHeadlessContext();
  // A 16 x 1 strip of linear values across the curve, beyond half-float range and NaN included.
  const float values[16] = {0.0f, 1e-4f, 0.0031308f, 0.01f, 0.05f, 0.1f, 0.2f,  0.3f,
                            0.5f, 0.7f,  0.9f,       1.0f,  2.0f,  1e5f, 3e38f, NAN};
  FrameGraph g;
  g.addTarget("linear", {GL_RGBA32F});
  g.addTarget("display", {GL_RGBA8});
  gl::Texture src(GL_RGBA32F, 16, 1);
  std::vector<float> px;
  for (float v : values) px.insert(px.end(), {v, v * 0.5f, v * 0.25f, 1.0f});
  g.addPass(
      "upload", Scope::Tile, [](PassBuilder& b) { b.write("linear"); },
      [&](const PassContext& c) {
        glCopyImageSubData(src.id(), GL_TEXTURE_2D, 0, 0, 0, 0, c.target("linear").id(),
                           GL_TEXTURE_2D, 0, 0, 0, 0, 16, 1, 1);
      });
  auto exposure = std::make_shared<float>(-0.5f);
  addToneMapPass(g, "linear", "display", exposure);
  g.compile("display");
  glTextureSubImage2D(src.id(), 0, 0, 0, 16, 1, GL_RGBA, GL_FLOAT, px.data());
  std::vector<float> out = g.execute(16, 1);
  const float scale = gi::exposureScale(*exposure);
  for (int i = 0; i < 16; ++i)
    for (int k = 0; k < 3; ++k) {
      const float want = gi::toneMapValue(px[4 * i + k], scale);
      const float got = out[4 * i + k];
      if (std::isnan(want)) {
        EXPECT_EQ(got, k == 1 ? 0.0f : 1.0f) << "NaN shows magenta";
      } else {
        // RGBA8 storage: within half a code value plus float rounding of the GPU's pow.
        EXPECT_NEAR(got, want, 0.6f / 255.0f) << "value " << px[4 * i + k];
      }
    }
}

}  // namespace
}  // namespace nestlight::frame
