// The GI frame's implementation, shared by its files (one concern each): the class behind
// SceneFrame and the `raster` method (nestlight/gi/frame/scene_frame.h), its scans, meshes,
// lights and environment. scene_frame.cpp drives a frame (the passes in order, render,
// renderInteractive); scene_frame_scans.cpp streams the scans' cuts and draws them;
// scene_frame_meshes.cpp loads and draws the meshes and uploads the materials;
// scene_frame_lights.cpp holds the lights and their shadow maps; scene_frame_environment.cpp
// the environment map; scene_frame_gbuffer.cpp the G-buffer passes; scene_frame_shading.cpp
// direct light, the tone map and the read-back.
#pragma once

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/frame/draw_tree.h"
#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/gpu_clip.h"
#include "nestlight/frame/interface.h"
#include "nestlight/frame/point_splatting.h"
#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/environment_source.h"
#include "nestlight/gi/frame/frame_parameters.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/frame/shadow_fit.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/scan_colour.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/program.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::gi::frame_detail {

using Clock = std::chrono::steady_clock;

inline double secondsSince(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A box in the scene's local frame.
struct LocalBox {
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  void add(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  bool empty() const { return !(lo.x <= hi.x); }
  glm::vec3 centre() const { return 0.5f * (lo + hi); }
  float radius() const { return 0.5f * glm::length(hi - lo); }
};

struct GpuMesh {
  gl::Buffer vertices, indices;
  gl::VertexArray vao;
  GLsizei indexCount = 0;
  uint32_t material = 0;
};

struct GpuScan {
  std::unique_ptr<OctreeReader> reader;
  std::unique_ptr<frame::GlNodeStore> store;
  std::unique_ptr<streaming::Streamer> streamer;  // the camera's cut
  frame::DrawTree tree;
  // The lights' cut: the whole scan seen from outside its bounds at about a shadow map's
  // resolution, so occluders out of the camera's view still cast shadows. Its nodes share the
  // store (and are counted in their own budget).
  std::unique_ptr<streaming::Streamer> shadowStreamer;
  frame::DrawTree shadowTree;
  streaming::View shadowView;
  float colourScale = 1;
  std::shared_ptr<const ScanColours>
      colours;  // the scene's octrees[].colour (a layer: drawn as HDR)
  // The scene's octrees[].clipping: nodes it removes whole stay out of both cuts, the rest are
  // clipped point by point on the GPU (shaders/common/clip_volumes.glsl), in the scene's frame.
  std::shared_ptr<const ClipSet> clip;
  std::unique_ptr<frame::GpuClip> gpuClip;
};

class RasterMethod : public Method, public SceneFrame {
 public:
  RasterMethod(const Scene& scene, const MethodContext& mc,
               std::unique_ptr<FrameExtension> extension);

  ~RasterMethod() override;

  std::string name() const override { return extension_ ? extension_->name() : "raster"; }

  // SceneFrame, for the extension.
  const Scene& scene() const override { return scene_; }
  const FrameParameters& frameParameters() const override { return params_; }
  frame::FrameGraph& graph() override { return graph_; }
  glm::vec3 boundsLo() const override { return bounds_.lo; }
  glm::vec3 boundsHi() const override { return bounds_.hi; }
  glm::vec3 lightViewBoundsLo() const override { return litBounds_.lo; }
  glm::vec3 lightViewBoundsHi() const override { return litBounds_.hi; }
  uint64_t lightViewsGeneration() const override { return lightViewsGeneration_; }
  const std::vector<frame::LightRecord>& lights() const override { return lightRecords_; }
  const std::vector<glm::mat4>& lightClipFromWorld() const override { return shadowViews_; }
  const std::vector<glm::mat4>& lightViewFromWorld() const override { return shadowViewFromWorld_; }
  void bindSceneBuffers() const override {
    lightsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_LIGHTS);
    shadowViewsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_SHADOW_VIEWS);
    materialsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_MATERIALS);
  }
  void bindEnvironment(const gl::ShaderProgram& program) const override;
  bool hasEnvironment() const override { return hasEnvironment_; }
  std::shared_ptr<const EnvironmentMap> environmentMap() const override { return envMap_; }
  uint64_t environmentGeneration() const override { return envGeneration_; }
  void setSkyInDirectLight(bool on) override { skyInDirectLight_ = on; }
  const std::vector<CutNode>& lightsCut() const override { return lightsCut_; }
  uint64_t cutGeneration() const override { return cutGeneration_; }
  uint64_t viewGeneration() const override { return viewGeneration_; }
  bool still() const override { return still_; }
  void bindLightsCutTree(int scan) const override { scans_.at(size_t(scan)).shadowTree.bind(); }
  void bindScanClip(int scan) const override;
  size_t addNodeLayer(const NodeLayerFactory& make) override;
  unsigned layerBuffer(const CutNode& n, size_t layer) const override {
    return scans_.at(size_t(n.scan)).store->layerBuffer(n.handle, layer);
  }
  size_t layerBytes(const CutNode& n, size_t layer) const override {
    return scans_.at(size_t(n.scan)).store->layerBytes(n.handle, layer);
  }
  bool quiet() const override { return quiet_; }
  const std::vector<TriangleMesh>& meshes() const override { return cpuMeshes_; }

  MethodFrame render(const SceneCamera& camera) override;

  unsigned renderInteractive(const SceneCamera& camera, float exposureStops,
                             MethodFrame* stats) override;

  std::vector<std::pair<std::string, std::string>> parameters() const override;

 private:
  // scene_frame.cpp: the frame's passes in order, its output and what it reports.
  void setOutput(const std::string& output);
  void buildGraph();
  void describe(MethodFrame& f, uint64_t drawPoints, double streamSeconds) const;

  // scene_frame_scans.cpp: the scans, their cuts streamed and drawn.
  void loadScans();
  uint64_t stream(const SceneCamera& camera, bool complete);
  void updateLightsCut();
  void drawScans(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                 const glm::mat4& viewFromWorld, float pixelsPerUnit, bool orthographic,
                 bool lightsCut = false) override;
  void forEachNode(const gl::ShaderProgram& program,
                   const std::function<void(const streaming::DrawNode&)>& draw,
                   bool lightsCut = false);

  // scene_frame_meshes.cpp: the meshes and the materials.
  void loadMeshes();
  void uploadMaterials();
  void drawMeshes(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                  bool materials) override;
  void drawMeshesWhere(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                       bool materials, const std::function<bool(size_t)>& include) override;

  // scene_frame_lights.cpp: the lights and their shadow maps.
  void setUpLights();
  void fitShadowsToCamera(const ShadowFitCamera& camera);
  void fitLightViewsToClusters(const ShadowFitCamera& camera);
  void addShadowMapPass();

  // scene_frame_environment.cpp: the environment map.
  void setUpEnvironment();
  void selectEnvironment(const SceneCamera& camera);
  void uploadEnvironment(std::shared_ptr<const EnvironmentMap> map, bool sequence);
  void prefilterEnvironment();
  void bindEnvironmentSpecular(const gl::ShaderProgram& program) const;

  // scene_frame_gbuffer.cpp: the G-buffer passes.
  void bindGBuffer(const frame::PassContext& ctx);
  glm::mat4 guardBand(const frame::PassContext& ctx) const;
  static constexpr float kMaxSplatPixels = 64.0f;
  static constexpr int kGuardPixels = int(kMaxSplatPixels / 2) + 1;
  void hqsScans(const frame::PassContext& ctx);
  void computeScans(const frame::PassContext& ctx);
  void addGBufferPasses();

  // scene_frame_shading.cpp: direct light, the tone map and the read-back.
  void addDirectLightPass();
  void addToneMapPass();
  static HdrImage imageOf(const std::vector<float>& rgba, int W, int H);

  Scene scene_;
  bool quiet_ = false;
  std::unique_ptr<FrameExtension> extension_;
  std::string radianceTarget_ = "radiance";  // what the tone map and the read-back take
  std::vector<CutNode> lightsCut_;
  uint64_t cutGeneration_ = 0;
  uint64_t viewGeneration_ = 0;
  // The camera's cut as last drawn (per scan, its nodes' handles, keys' hashes and point
  // counts): viewGeneration.
  std::vector<uint64_t> viewCut_;
  bool still_ = false;
  FrameParameters params_;
  std::unique_ptr<gl::GlContext> context_;
  LocalBox bounds_;
  std::vector<LocalBox>
      objectBounds_;  // each scan's and mesh's: the near plane follows the nearest
  std::vector<ShadowBox> shadowBoxes_;  // the same, as directional shadow maps fit them
  // Directional shadow maps cover the camera's view (raster alone, or an extension that reads
  // them only for the camera's pixels), else the whole scene.
  bool fitShadowsToCamera_ = true;
  // Otherwise, the objects' clusters (empty when fitted to the camera) and those the directional
  // views span now, with their bounds; the count changes with any light view.
  ObjectClusters clusters_;
  std::vector<bool> litClusters_;
  LocalBox litBounds_;
  uint64_t lightViewsGeneration_ = 0;
  std::vector<GpuScan> scans_;
  std::vector<GpuMesh> meshes_;
  std::vector<TriangleMesh> cpuMeshes_;  // the files' meshes, until the extension's setUp is done
  std::vector<frame::LightRecord> lightRecords_;
  std::vector<glm::mat4> shadowViews_;          // clip from world, per shadow-map layer
  std::vector<glm::mat4> shadowViewFromWorld_;  // the view alone (splat sizes)
  gl::Buffer lightsBuffer_, shadowViewsBuffer_, materialsBuffer_;
  gl::Texture environment_;
  // The split sum's two factors (environment_specular.glsl): the sky prefiltered per roughness
  // level, and the GGX lobe's table (made once, with the first environment).
  gl::Texture envPrefiltered_, splitSumTable_;
  gl::ShaderProgram envPrefilter_;
  bool hasEnvironment_ = false;
  std::unique_ptr<EnvironmentSource> envSource_;
  std::shared_ptr<const EnvironmentMap> envMap_ = std::make_shared<const EnvironmentMap>();
  std::string lastEnvWarning_;  // said once, not every frame of a sequence
  size_t envFrame_ = 0;
  uint64_t envGeneration_ = 0;
  float envRotation_ = 0, envScale_ = 1;
  std::array<glm::vec3, 9> sh_{};
  gl::ShaderProgram meshGBuffer_, meshShadow_, scanShadow_, directLight_;
  std::unique_ptr<frame::PointSplatting> splatting_;  // the scans' G-buffer passes
  gl::Framebuffer hqsDepthFbo_, hqsSumFbo_, gbufferFbo_;
  gl::VertexArray emptyVao_;
  gl::Framebuffer shadowFbo_;
  frame::FrameGraph graph_;
  std::shared_ptr<float> exposure_ = std::make_shared<float>(0.0f);
  bool skyInDirectLight_ = true;
  int frameNumber_ = 0;
  double beforeFrameSeconds_ = 0;
  std::string output_;  // the target the graph was compiled for
};

}  // namespace nestlight::gi::frame_detail
