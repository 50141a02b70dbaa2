// The `vpl` method's extension of the raster frame, private to gi/vpl: Preiner, "Real-Time Global
// Illumination in Point Clouds" (light G-buffer, Halton VPLs with hierarchical warping, imperfect
// shadow maps with parabolic projection and pull-push, interleaved shading with a geometry-aware
// filter, multiple bounces). One algorithm per file, each with its paper: vpl_method.cpp (the
// frame), vpl_warping.cpp, vpl_ism.cpp, vpl_pull_push.cpp, vpl_shading.cpp and
// vpl_exact_visibility.cpp.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/gtc/packing.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/interface.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/shared/reference_scene.h"
#include "nestlight/gi/vpl/vpl_method.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"

namespace nestlight::gi {

namespace vplglsl {
using vec4 = glm::vec4;
using ivec4 = glm::ivec4;
using uvec4 = glm::uvec4;
using mat4 = glm::mat4;
#include "gi/vpl/vpl_interface.glsl"
#include "interface/frame_interface.glsl"
}  // namespace vplglsl

namespace vpl {

using vplglsl::LightView;
using vplglsl::PoolNode;
using vplglsl::PoolPoint;
using vplglsl::VplRecord;
using vplglsl::WarpSample;
static_assert(sizeof(VplRecord) == 5 * 16, "VplRecord must keep std430's layout");
static_assert(sizeof(WarpSample) == 2 * 16, "WarpSample must keep std430's layout");
static_assert(sizeof(PoolPoint) == 2 * 16, "PoolPoint must keep std430's layout");
static_assert(sizeof(PoolNode) == 3 * 16, "PoolNode must keep std430's layout");
static_assert(sizeof(LightView) == 5 * 16, "LightView must keep std430's layout");

inline int log2Exact(int v) {
  int l = 0;
  while ((1 << l) < v) ++l;
  return l;
}

inline size_t pyramidLayerFloats(int size) {
  size_t n = 0;
  for (int s = size; s >= 1; s >>= 1) n += size_t(s) * size_t(s);
  return n;
}

inline size_t ismPyramidFloats(int size) {
  size_t n = 0;
  for (int s = size >> 1; s >= 1; s >>= 1) n += size_t(s) * size_t(s);
  return n;
}

// Importance pyramid and warping: shared by the method and warpImportanceOnGpu
// (vpl_warping.cpp).
class ImportanceWarp {
 public:
  ImportanceWarp();

  // `levels` holds level 0 of every layer (pyramidLayerFloats(size) floats per layer): fills the
  // levels above, then warps `count` Halton points into `samples`.
  void run(const gl::Buffer& levels, int size, int layers, int count, gl::Buffer& samples) const;

 private:
  gl::ShaderProgram pyramid_, warp_;
};

class VplExtension : public FrameExtension {
 public:
  explicit VplExtension(const Scene& scene) : params_(vplParameters(scene)) {}
  std::string name() const override { return "vpl"; }
  std::vector<std::string> parameterKeys() const override {
    return parameterNames(vplParameterSpecs());
  }
  bool usesIsms() const { return params_.visibility != VplParameters::Visibility::None; }
  bool exact() const { return params_.visibility == VplParameters::Visibility::Exact; }
  const char* visibilityName() const {
    return params_.visibility == VplParameters::Visibility::Ism ? "ism"
           : exact()                                            ? "exact"
                                                                : "none";
  }
  std::vector<std::pair<std::string, std::string>> parameters() const override;
  std::string setUp(SceneFrame& f) override;
  void beforeFrame(SceneFrame& f) override;
  void describe(const SceneFrame& f, MethodFrame& out) const override;
  void afterReadBack(const std::vector<float>& rgba, MethodFrame& out) override;

 private:
  // vpl_method.cpp: the frame (light views, buffers, the VPL count, VPL generations over the
  // bounces, the passes in order).
  void setUpLightViews(SceneFrame& f);
  void compile();
  void allocateCountBuffers();
  bool afterFrame(double seconds, bool still) override;
  void addPasses(SceneFrame& f);
  void addVisibilityAndShadingPasses(SceneFrame& f);
  void generateVpls(SceneFrame& f, const frame::PassContext& ctx);
  double emittedFlux(int gen);

  // vpl_warping.cpp: the light G-buffer and importance-warped VPLs.
  void addLightPasses(SceneFrame& f, const char* const (&lightTargets)[4]);
  void bindLightTextures(const frame::PassContext& ctx) const;
  void emitFromScans();

  // vpl_ism.cpp: the ISM pool (the cut's points, the meshes' surfels) and the ISM atlas.
  void setUpSurfels(SceneFrame& f);
  void setPoolUniforms(const gl::ShaderProgram& p) const;
  void buildPool(SceneFrame& f);
  void addIsmPass(SceneFrame& f);

  // vpl_pull_push.cpp: the ISMs' holes filled from their coarser levels.
  void addPullPushPass(SceneFrame& f);

  // vpl_shading.cpp: interleaved shading and the geometry-aware filter.
  void addShadePass(SceneFrame& f);
  void addFilterPass(SceneFrame& f);

  // vpl_exact_visibility.cpp: Embree's rays instead of the ISMs.
  void addExactPass(SceneFrame& f);
  void exactVisibility(const frame::PassContext& ctx);

  static uint32_t packHalf2(float a, float b) {
    return uint32_t(glm::packHalf1x16(std::min(a, 65504.f))) |
           (uint32_t(glm::packHalf1x16(std::min(b, 65504.f))) << 16);
  }
  void setCount(int n) {
    if (n == params_.count) return;
    params_.count = n;
    allocateCountBuffers();
  }
  void bindCommon(SceneFrame& f) const {
    f.bindSceneBuffers();
    lightViews_.bindBase(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_LIGHT_VIEWS);
    records_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_RECORDS, 0, records_.bytes());
  }

  VplParameters params_;
  int bounces_ = 1, generations_ = 0, generationsRun_ = 0;
  // "vpls": "auto"
  int autoCap_ = 0, sinceChange_ = 0;
  bool autoDecided_ = false;
  double smoothed_ = 0;
  std::vector<std::pair<int, double>> probes_;
  std::string autoNote_;
  bool radianceCache_ = false;
  uint64_t vplChecksum_ = 0, liveVpls_ = 0;
  std::string stopNote_, poolNote_;
  int layers_ = 0;
  std::vector<int> layerOwner_;
  float radius_ = 1, clampDistance_ = 0;
  gl::Buffer lightViews_, pyramid_, samples_, records_, ism_, ismLevels_, pool_, poolNodes_;
  // Visibility "exact": the reference's scene, the tile's bits, the agreement counters.
  std::unique_ptr<ReferenceScene> exactScene_;
  gl::Buffer exactBits_, agreement_;
  int exactWords_ = 1;
  std::vector<PoolPoint> surfelPoints_;
  std::vector<PoolNode> surfelNodes_;
  size_t poolNodeCount_ = 0;
  uint64_t poolPoints_ = 0;
  uint64_t poolGeneration_ = ~uint64_t(0);
  uint64_t lightViewsGeneration_ = 0;
  gl::ShaderProgram emitImportance_, emit_;  // radiance-cache mode
  gl::Buffer emitPyramid_;
  int emitSide_ = 1;
  uint64_t scanPoints_ = 0;
  glm::vec3 objectsLo_{INFINITY}, objectsHi_{-INFINITY};
  gl::ShaderProgram scanGBuffer_, meshGBuffer_, importance_, generate_, bounce_, gather_, splat_,
      pull_, push_, shade_, filter_;
  gl::ShaderProgram shadeExact_;  // shade_ with the ISM-against-exact comparison, made on first use
  std::unique_ptr<ImportanceWarp> warp_;
  gl::Framebuffer lightFbo_;
  gl::VertexArray emptyVao_;
};

}  // namespace vpl
}  // namespace nestlight::gi
