// The GI frame (nestlight/gi/frame/raster_frame.h): the `raster` method, direct light, and the
// frame every GL method extends (nestlight/gi/raster/raster_method.h).
// Shadow maps are the classic technique (Williams 1978, "Casting Curved Shadows on Curved
// Surfaces") with normal-offset lookups and percentage-closer filtering (Reeves, Salesin and Cook
// 1987, "Rendering Antialiased Shadows with Depth Maps"); the environment's irradiance on diffuse
// lobes is order-2 spherical harmonics (Ramamoorthi and Hanrahan 2001, "An Efficient
// Representation for Irradiance Environment Maps").
#include "nestlight/gi/frame/raster_frame.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <glm/gtc/matrix_transform.hpp>
#include <thread>
#include <unordered_map>

#include "nestlight/frame/draw_tree.h"
#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/interface.h"
#include "nestlight/frame/passes.h"
#include "nestlight/frame/point_splatting.h"
#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/environment_source.h"
#include "nestlight/gi/frame/irradiance_sh.h"
#include "nestlight/gi/frame/shadow_fit.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/scan_colour.h"
#include "nestlight/gl/context.h"
#include "nestlight/gl/program.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::gi {

namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t0) {
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
};

class RasterMethod : public Method, public RasterFrame {
 public:
  RasterMethod(const Scene& scene, const MethodContext& mc,
               std::unique_ptr<RasterExtension> extension)
      : scene_(scene), quiet_(mc.quiet), extension_(std::move(extension)) {
    graph_.setSyncTiming(mc.syncPassTiming);
    params_ = parseRasterParameters(
        scene, extension_ ? extension_->parameterKeys() : std::vector<std::string>{});
    if (!mc.glContextCurrent) {
      context_ = gl::createHeadlessContext();
      if (!quiet_) std::fprintf(stderr, "raster: %s\n", context_->description().c_str());
    }
    loadScans();
    if (params_.computeRasteriser)
      for (const auto& o : scene_.octrees)
        if (o.colourScale != scene_.octrees.front().colourScale ||
            (o.colour == ScanColours::kRecorded) !=
                (scene_.octrees.front().colour == ScanColours::kRecorded))
          throw Error(scene_.file.string(), "gi.parameters.rasteriser",
                      "the compute rasteriser averages the scans' colours before scaling them: "
                      "give every octree the "
                      "same colour_scale and the same kind of colour (recorded or a layer), or use "
                      "\"points\"");
    loadMeshes();
    setUpLights();
    setUpEnvironment();
    uploadMaterials();
    buildGraph();
  }

  ~RasterMethod() override {
    if (context_) context_->makeCurrent();
    // Streamers release their nodes into the stores while the context lives; the extension's GL
    // objects go first.
    extension_.reset();
    scans_.clear();
  }

  std::string name() const override { return extension_ ? extension_->name() : "raster"; }

  // RasterFrame, for the extension.
  const Scene& scene() const override { return scene_; }
  const RasterParameters& rasterParameters() const override { return params_; }
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
  void bindEnvironment(const gl::ShaderProgram& program) const override {
    glBindTextureUnit(5, environment_ ? environment_.id() : 0);
    glUniform1i(program.uniform("uHasEnvironment"), hasEnvironment_ ? 1 : 0);
    glUniform1f(program.uniform("uEnvRotation"), envRotation_);
    glUniform1f(program.uniform("uEnvScale"), envScale_);
    glUniform3fv(program.uniform("uEnvSh"), 9, &sh_[0].x);
  }
  bool hasEnvironment() const override { return hasEnvironment_; }
  std::shared_ptr<const EnvironmentMap> environmentMap() const override { return envMap_; }
  uint64_t environmentGeneration() const override { return envGeneration_; }
  void setSkyOnDiffuseLobes(bool on) override { skyOnDiffuse_ = on; }
  const std::vector<CutNode>& lightsCut() const override { return lightsCut_; }
  uint64_t cutGeneration() const override { return cutGeneration_; }
  void bindLightsCutTree(int scan) const override { scans_.at(size_t(scan)).shadowTree.bind(); }
  size_t addNodeLayer(const NodeLayerFactory& make) override {
    NL_CHECK_MSG(frameNumber_ == 0, "node layers are added before the first frame streams");
    size_t index = 0;
    for (auto& s : scans_) index = s.store->addLayer(make(s.reader->metadata(), s.colours));
    return index;
  }
  unsigned layerBuffer(const CutNode& n, size_t layer) const override {
    return scans_.at(size_t(n.scan)).store->layerBuffer(n.handle, layer);
  }
  size_t layerBytes(const CutNode& n, size_t layer) const override {
    return scans_.at(size_t(n.scan)).store->layerBytes(n.handle, layer);
  }
  bool quiet() const override { return quiet_; }
  const std::vector<TriangleMesh>& meshes() const override { return cpuMeshes_; }

  MethodFrame render(const SceneCamera& camera) override {
    if (context_) context_->makeCurrent();
    setOutput(radianceTarget_);
    const int W = camera.width, H = camera.height;
    if (W <= 0 || H <= 0)
      throw Error(scene_.file.string(), "camera", "the image size must be positive");
    selectEnvironment(camera);
    const auto tStream = Clock::now();
    const uint64_t drawPoints = stream(camera, true);
    const double streamSeconds = secondsSince(tStream);
    auto t0 = Clock::now();
    // The compute rasteriser's per-pixel buffers hold 16 bytes a pixel within one SSBO range:
    // tiles (margins included) stay below it.
    int tile = params_.maxTile;
    if (params_.computeRasteriser)
      while (tile > 64 && size_t(tile + 2) * size_t(tile + 2) * 16 > gl::kMaxSsboRange) tile /= 2;
    std::vector<float> rgba = graph_.execute(W, H, tile);
    // An extension tuning itself to a time budget may ask for the still again.
    for (int again = 0; again < 4 && extension_ && extension_->afterFrame(secondsSince(t0), true);
         ++again) {
      const auto tAgain = Clock::now();
      rgba = graph_.execute(W, H, tile);
      t0 = tAgain;
    }
    MethodFrame f;
    f.seconds = secondsSince(t0) + beforeFrameSeconds_;
    f.image = HdrImage(W, H);
    for (size_t p = 0; p < size_t(W) * H; ++p)
      for (int k = 0; k < 3; ++k) f.image.rgb[3 * p + k] = rgba[4 * p + k];
    describe(f, drawPoints, streamSeconds);
    if (extension_) extension_->afterReadBack(rgba, f);
    return f;
  }

  unsigned renderInteractive(const SceneCamera& camera, float exposureStops,
                             MethodFrame* stats) override {
    if (context_) context_->makeCurrent();
    if (params_.computeRasteriser && size_t(camera.width) * camera.height * 16 > gl::kMaxSsboRange)
      throw Error(scene_.file.string(), "gi.parameters.rasteriser",
                  "a " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                      " window is too large for the compute rasteriser's per-pixel buffers (128 "
                      "MiB); use \"points\"");
    setOutput("display");
    *exposure_ = exposureStops;
    selectEnvironment(camera);
    const auto t0 = Clock::now();
    const uint64_t drawPoints = stream(camera, false);
    graph_.executeToTarget(camera.width, camera.height);
    if (extension_) extension_->afterFrame(secondsSince(t0), false);
    if (stats) {
      stats->seconds = secondsSince(t0);
      describe(*stats, drawPoints, 0);
    }
    return graph_.target("display").id();
  }

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    std::vector<std::pair<std::string, std::string>> p = {
        {"shadow_map_size", std::to_string(params_.shadowMapSize)},
        {"rasteriser", params_.computeRasteriser ? "compute" : "points"},
        {"splatting", params_.hqs ? "hqs" : "basic"},
        {"splat_scale", std::to_string(params_.splatScale).substr(0, 4)},
        {"point_budget", std::to_string(params_.pointBudget)},
        {"gpu_budget_mb", std::to_string(params_.gpuBytes >> 20)},
        {"max_tile", std::to_string(params_.maxTile)}};
    if (extension_)
      for (auto& kv : extension_->parameters()) p.push_back(kv);
    return p;
  }

 private:
  void setOutput(const std::string& output) {
    if (output_ == output) return;
    graph_.compile(output);
    output_ = output;
  }

  // Sets the frame's camera and brings each scan's cut for it in: completely (a still, judged
  // against the reference) or one streaming step (interactive). Returns the points drawn.
  uint64_t stream(const SceneCamera& camera, bool complete) {
    const int W = camera.width, H = camera.height;
    const glm::vec3 eye = scene_.local(camera.eye), target = scene_.local(camera.target);
    const glm::vec3 up = glm::vec3(camera.up);
    // Clip planes around everything there is, so depth precision is spent on the scene. The near
    // plane follows the nearest object alone (a 10^4 depth range of its own extent): tied to the
    // farthest one, a mesh 100 km from the scan pushed it 10 m out and clipped the scan away.
    float nearZ = 1e30f, farZ = 0;
    for (const LocalBox& b : objectBounds_) {
      float objectFar = 0;
      for (int c = 0; c < 8; ++c) {
        const glm::vec3 p((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y,
                          (c & 4) ? b.hi.z : b.lo.z);
        objectFar = std::max(objectFar, glm::length(p - eye));
      }
      const float objectNear = glm::length(glm::clamp(eye, b.lo, b.hi) - eye);
      nearZ = std::min(nearZ, std::max(0.95f * objectNear, 1e-4f * objectFar));
      farZ = std::max(farZ, objectFar);
    }
    if (!(nearZ > 0 && nearZ < 1e30f)) nearZ = 1e-4f * std::max(farZ, 1.0f);
    farZ = std::max(farZ * 1.01f, nearZ * 2);
    const double fovY = glm::radians(camera.fovYDegrees);

    const auto tStream = Clock::now();
    uint64_t drawPoints = 0;
    for (auto& s : scans_) {
      const streaming::View view = streaming::perspectiveView(
          camera.eye, camera.target, camera.up, fovY, W, H, double(nearZ), double(farZ));
      streaming::FrameStats st = s.streamer->update(view);
      while (complete && !st.complete) {
        if (secondsSince(tStream) > params_.streamTimeoutSeconds)
          throw Error(s.reader->dir().string(), "",
                      "the view's cut did not load within " +
                          std::to_string(params_.streamTimeoutSeconds) + " s");
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        st = s.streamer->update(view);
      }
      s.tree.upload(s.streamer->drawList());
      drawPoints += st.drawPoints;
      streaming::FrameStats sst = s.shadowStreamer->update(s.shadowView);
      while (complete && !sst.complete) {
        if (secondsSince(tStream) > params_.streamTimeoutSeconds)
          throw Error(s.reader->dir().string(), "",
                      "the lights' cut did not load within " +
                          std::to_string(params_.streamTimeoutSeconds) + " s");
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        sst = s.shadowStreamer->update(s.shadowView);
      }
      s.shadowTree.upload(s.shadowStreamer->drawList());
    }
    if (extension_) updateLightsCut();  // only extensions read it

    frame::FrameBlock& u = graph_.uniforms();
    u.viewFromWorld = glm::lookAt(eye, target, up);
    u.clipFromView = glm::perspective(float(fovY), float(W) / float(H), nearZ, farZ);
    u.eye = glm::vec4(eye, float(H) / (2.0f * std::tan(float(fovY) / 2)));
    const ShadowFitCamera fitCamera{u.viewFromWorld, std::tan(float(fovY) / 2), float(W) / float(H),
                                    nearZ, farZ};
    if (fitShadowsToCamera_)
      fitShadowsToCamera(fitCamera);
    else if (clusters_.boxes.size() > 1)
      fitLightViewsToClusters(fitCamera);
    u.counts = glm::ivec4(int(lightRecords_.size()), scene_.gi.mode == RadianceMode::Albedo ? 1 : 0,
                          frameNumber_++, 0);
    beforeFrameSeconds_ = 0;
    if (extension_) {
      // Per-frame preparation (hierarchies joined, an environment's sampling table) is the
      // frame's work: counted in its time, unlike the streaming before it.
      const auto tb = Clock::now();
      extension_->beforeFrame(*this);
      beforeFrameSeconds_ = secondsSince(tb);
    }
    return drawPoints;
  }

  // The lights' cuts as one list for the extension; a new generation when any node changed.
  void updateLightsCut() {
    std::vector<CutNode> cut;
    for (size_t si = 0; si < scans_.size(); ++si) {
      const auto& s = scans_[si];
      const auto& nodes = s.shadowStreamer->drawList();
      std::unordered_map<NodeKey, int, NodeKeyHash> index;
      for (size_t ni = 0; ni < nodes.size(); ++ni) {
        const auto& n = nodes[ni];
        CutNode c;
        c.scan = int(si);
        c.indexInScan = int(ni);
        c.buffer = s.store->buffer(n.handle);
        c.handle = n.handle;
        c.numPoints = n.numPoints;
        c.origin = scene_.local({n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z});
        c.size = float(n.worldBounds.max.x - n.worldBounds.min.x);
        c.spacing = float(n.spacing);
        c.colourScale = s.colourScale;
        c.hdrColour = s.store->hdrColour();
        if (n.key.level > 0) {
          auto it = index.find(n.key.parent());
          if (it != index.end()) c.parent = it->second;
        }
        index[n.key] = int(cut.size());
        cut.push_back(c);
      }
    }
    auto same = [](const CutNode& a, const CutNode& b) {
      return a.buffer == b.buffer && a.numPoints == b.numPoints;
    };
    if (cut.size() != lightsCut_.size() ||
        !std::equal(cut.begin(), cut.end(), lightsCut_.begin(), same)) {
      lightsCut_ = std::move(cut);
      ++cutGeneration_;
    }
  }

  void describe(MethodFrame& f, uint64_t drawPoints, double streamSeconds) const {
    f.passMs.clear();
    for (const auto& t : graph_.timings()) f.passMs.emplace_back(t.name, t.gpuMs);
    f.attributes = {{"nestlight:method", "raster"},
                    {"nestlight:shadow_map_size", std::to_string(params_.shadowMapSize)},
                    {"nestlight:splat_scale", std::to_string(params_.splatScale)},
                    {"nestlight:points", std::to_string(drawPoints)},
                    {"nestlight:seconds", std::to_string(f.seconds)}};
    if (envSource_ && envSource_->isSequence())
      f.attributes["nestlight:environment_frame"] = std::to_string(envFrame_);
    // Directional maps' texels follow the camera (world units).
    for (size_t i = 0; i < lightRecords_.size(); ++i)
      if (int(lightRecords_[i].position.w) == NL_LIGHT_DIRECTIONAL)
        f.attributes["nestlight:shadow_texel:" + std::to_string(i)] =
            std::to_string(lightRecords_[i].shadow.y);
    std::string passes;
    for (const auto& [name, ms] : f.passMs) {
      passes += (passes.empty() ? "" : ", ") + name + " " + std::to_string(ms).substr(0, 6) + " ms";
      f.attributes["nestlight:pass_ms:" + name] = std::to_string(ms);
    }
    for (const auto& t : graph_.timings())
      if (t.wallMs > 0) f.attributes["nestlight:pass_wall_ms:" + t.name] = std::to_string(t.wallMs);
    if (extension_) f.attributes["nestlight:method"] = extension_->name();
    // Nodes evicted so far (both cuts): streaming tests assert that eviction really happened.
    uint64_t evicted = 0, lightsEvicted = 0;
    for (const auto& s : scans_)
      evicted += s.streamer->totals().evicted, lightsEvicted += s.shadowStreamer->totals().evicted;
    f.attributes["nestlight:evicted_nodes"] = std::to_string(evicted);
    f.attributes["nestlight:lights_cut_evicted_nodes"] = std::to_string(lightsEvicted);
    char line[256];
    std::snprintf(line, sizeof line,
                  "%llu points, %zu lights, %d px shadow maps, %.1f ms (stream %.2f s)",
                  (unsigned long long)drawPoints, lightRecords_.size(), params_.shadowMapSize,
                  f.seconds * 1e3, streamSeconds);
    f.summary = std::string(line) + "; GPU: " + passes;
    if (extension_) extension_->describe(*this, f);
  }

  void loadScans() {
    for (const auto& o : scene_.octrees) {
      GpuScan s;
      s.reader = std::make_unique<OctreeReader>(o.path);
      const Metadata& meta = s.reader->metadata();
      s.colours = std::make_shared<const ScanColours>(o.path, meta, o.colour);
      const frame::ColourMode mode = s.colours->layer()            ? frame::ColourMode::Hdr
                                     : meta.layout.has(attr::kRgb) ? frame::ColourMode::Rgb
                                                                   : frame::ColourMode::Elevation;
      if (!s.colours->hasColour() && !quiet_)
        std::fprintf(stderr, "raster: %s has no colour; drawn by elevation\n", o.path.c_str());
      s.store = std::make_unique<frame::GlNodeStore>(meta, mode, s.colours->layer());
      streaming::Budgets b;
      b.points = params_.pointBudget;
      b.gpuBytes = params_.gpuBytes;
      b.uploadBytesPerFrame = params_.gpuBytes;  // a still waits for its cut anyway
      b.spacingPixels = 1.0;
      s.streamer = std::make_unique<streaming::Streamer>(*s.reader, *s.store, b);
      s.colourScale = o.colourScale;
      // The lights' cut: the whole bounds from outside them, in a square view of a shadow map's
      // size (60 degrees, from twice the bounding radius along a diagonal).
      const glm::dvec3 lo(meta.bounds.min.x, meta.bounds.min.y, meta.bounds.min.z),
          hi(meta.bounds.max.x, meta.bounds.max.y, meta.bounds.max.z);
      const glm::dvec3 centre = 0.5 * (lo + hi);
      const double radius = std::max(0.5 * glm::length(hi - lo), 1e-3);
      const glm::dvec3 eye = centre + glm::normalize(glm::dvec3(1, 0.7, 1.3)) * (2.0 * radius);
      s.shadowView = streaming::perspectiveView(eye, centre, {0, 0, 1}, glm::radians(60.0),
                                                params_.shadowMapSize, params_.shadowMapSize,
                                                radius * 0.5, radius * 3.5);
      streaming::Budgets sb = b;
      sb.points = std::max<uint64_t>(params_.pointBudget / 2, 1);
      sb.gpuBytes = std::max<uint64_t>(params_.gpuBytes / 2, 1 << 20);
      s.shadowStreamer = std::make_unique<streaming::Streamer>(*s.reader, *s.store, sb);
      LocalBox scan;
      for (int c = 0; c < 8; ++c)
        scan.add(scene_.local({(c & 1) ? meta.bounds.max.x : meta.bounds.min.x,
                               (c & 2) ? meta.bounds.max.y : meta.bounds.min.y,
                               (c & 4) ? meta.bounds.max.z : meta.bounds.min.z}));
      if (!scan.empty()) {
        bounds_.add(scan.lo), bounds_.add(scan.hi);
        objectBounds_.push_back(scan);
      }
      scans_.push_back(std::move(s));
    }
  }

  void loadMeshes() {
    for (const auto& m : scene_.meshes) {
      cpuMeshes_.push_back(readMesh(m.path.string()));
      const TriangleMesh& mesh = cpuMeshes_.back();
      const glm::mat4 localFromObject = scene_.localFromObject(m);
      const glm::mat3 normalFrom = glm::transpose(glm::inverse(glm::mat3(localFromObject)));
      std::vector<float> v;
      v.reserve(mesh.positions.size() * 9);
      LocalBox object;
      for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 p = glm::vec3(localFromObject * glm::vec4(mesh.positions[i], 1.0f));
        glm::vec3 n(0.0f);
        if (!mesh.normals.empty()) {
          n = normalFrom * mesh.normals[i];
          const float len = glm::length(n);
          n = len > 0 && std::isfinite(len) ? n / len : glm::vec3(0.0f);
        }
        const Rgb c = mesh.colors.empty() ? Rgb(1.0f) : mesh.colors[i];
        v.insert(v.end(), {p.x, p.y, p.z, n.x, n.y, n.z, c.r, c.g, c.b});
        if (std::isfinite(p.x + p.y + p.z)) bounds_.add(p), object.add(p);
      }
      if (!object.empty()) objectBounds_.push_back(object);
      GpuMesh g;
      g.vertices = gl::Buffer(v.size() * 4, v.data(), 0);
      g.indices = gl::Buffer(mesh.indices.size() * 4, mesh.indices.data(), 0);
      g.indexCount = GLsizei(mesh.indices.size());
      g.material = m.material;
      g.vao = gl::VertexArray::create();
      const GLuint vao = g.vao.id();
      glVertexArrayVertexBuffer(vao, 0, g.vertices.id(), 0, 9 * sizeof(float));
      glVertexArrayElementBuffer(vao, g.indices.id());
      for (GLuint a = 0; a < 3; ++a) {
        glEnableVertexArrayAttrib(vao, a);
        glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
        glVertexArrayAttribBinding(vao, a, 0);
      }
      meshes_.push_back(std::move(g));
    }
    if (bounds_.empty()) bounds_.add(glm::vec3(0.0f));
  }

  // One record per light; shadow-map layers: spot and directional one, point six (cube faces in
  // the order shadowLayer() in shaders/gi/common/lights.glsl picks them).
  void setUpLights() {
    fitShadowsToCamera_ = !extension_ || extension_->shadowsForTheCameraOnly();
    for (const LocalBox& b : objectBounds_) shadowBoxes_.push_back({b.lo, b.hi});
    // Every cluster until the first frame's camera picks those it sees.
    if (!fitShadowsToCamera_) clusters_ = clusterObjects(shadowBoxes_);
    litClusters_.assign(clusters_.boxes.size(), true);
    litBounds_ = bounds_;
    if (scene_.lights.size() > NL_MAX_LIGHTS)
      throw Error(scene_.file.string(), "lights",
                  "the raster method takes at most " + std::to_string(NL_MAX_LIGHTS) +
                      " lights; the scene has " + std::to_string(scene_.lights.size()));
    const glm::vec3 centre = bounds_.centre();
    const float R = std::max(bounds_.radius(), 1e-3f);
    const int S = params_.shadowMapSize;
    for (const Light& l : scene_.lights) {
      frame::LightRecord r{};
      const glm::vec3 pos = scene_.local(l.position);
      const glm::vec3 dir =
          glm::length(l.direction) > 0 ? glm::normalize(l.direction) : glm::vec3(0, 0, -1);
      const int type = l.type == LightType::Point  ? NL_LIGHT_POINT
                       : l.type == LightType::Spot ? NL_LIGHT_SPOT
                                                   : NL_LIGHT_DIRECTIONAL;
      r.position = glm::vec4(pos, float(type));
      r.direction = glm::vec4(dir, 0.0f);
      r.intensity = glm::vec4(l.intensity.r, l.intensity.g, l.intensity.b, 0.0f);
      r.cone = glm::vec4(std::cos(glm::radians(l.outerAngleDegrees)),
                         std::cos(glm::radians(l.innerAngleDegrees)), 0, 0);
      auto upFor = [](const glm::vec3& d) {
        return std::abs(d.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
      };
      const float farL = glm::length(pos - centre) + R * 1.01f;
      const float nearL = std::max(farL * 1e-4f, 1e-4f);
      r.shadow = glm::vec4(float(shadowViews_.size()), 0.0f, nearL, farL);
      if (type == NL_LIGHT_DIRECTIONAL && fitShadowsToCamera_) {
        // The whole scene until the first frame's camera refits it.
        const DirectionalShadowFit fit = fitDirectionalShadow(dir, shadowBoxes_, nullptr, S);
        shadowViews_.push_back(fit.clipFromWorld);
        shadowViewFromWorld_.push_back(fit.viewFromWorld);
        r.shadow.y = fit.texel;
        r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
      } else if (type == NL_LIGHT_DIRECTIONAL) {
        const DirectionalShadowFit fit =
            fitDirectionalToBox(dir, {bounds_.lo, bounds_.hi}, shadowBoxes_, S);
        shadowViews_.push_back(fit.clipFromWorld);
        shadowViewFromWorld_.push_back(fit.viewFromWorld);
        r.shadow.y = fit.texel;
        r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
      } else if (type == NL_LIGHT_SPOT) {
        // The outer cone plus a texel of margin, at most 170 degrees (beyond that a point light's
        // six views would serve better; the falloff still cuts the light at the cone).
        const float half = std::min(glm::radians(l.outerAngleDegrees) * 1.02f, glm::radians(85.0f));
        const glm::mat4 view = glm::lookAt(pos, pos + dir, upFor(dir));
        shadowViews_.push_back(glm::perspective(2 * half, 1.0f, nearL, farL) * view);
        shadowViewFromWorld_.push_back(view);
        r.shadow.y = 2 * std::tan(half) / float(S);
      } else {
        const glm::vec3 axes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                   {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
        for (const auto& a : axes) {
          const glm::mat4 view = glm::lookAt(pos, pos + a, upFor(a));
          shadowViews_.push_back(glm::perspective(glm::radians(90.0f), 1.0f, nearL, farL) * view);
          shadowViewFromWorld_.push_back(view);
        }
        r.shadow.y = 2.0f / float(S);
      }
      lightRecords_.push_back(r);
    }
    lightsBuffer_ =
        gl::Buffer(std::max<size_t>(lightRecords_.size(), 1) * sizeof(frame::LightRecord),
                   lightRecords_.empty() ? nullptr : lightRecords_.data());
    std::vector<glm::mat4> views = shadowViews_;
    if (views.empty()) views.emplace_back(1.0f);
    shadowViewsBuffer_ = gl::Buffer(views.size() * sizeof(glm::mat4), views.data());
  }

  // Directional lights' maps cover what this camera sees (shadow_fit.h); the shadow pass of the
  // frame that follows draws them, and lookups read the texel size and views from the buffers.
  void fitShadowsToCamera(const ShadowFitCamera& camera) {
    bool changed = false;
    for (frame::LightRecord& r : lightRecords_) {
      if (int(r.position.w) != NL_LIGHT_DIRECTIONAL) continue;
      const size_t layer = size_t(r.shadow.x);
      const DirectionalShadowFit fit = fitDirectionalShadow(glm::vec3(r.direction), shadowBoxes_,
                                                            &camera, params_.shadowMapSize);
      if (fit.clipFromWorld == shadowViews_[layer] && fit.texel == r.shadow.y) continue;
      shadowViews_[layer] = fit.clipFromWorld;
      shadowViewFromWorld_[layer] = fit.viewFromWorld;
      r.shadow.y = fit.texel;
      r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
      changed = true;
    }
    if (!changed) return;
    lightsBuffer_.upload(lightRecords_.data(), lightRecords_.size() * sizeof(frame::LightRecord));
    shadowViewsBuffer_.upload(shadowViews_.data(), shadowViews_.size() * sizeof(glm::mat4));
    ++lightViewsGeneration_;
  }

  // Extensions light beyond the camera's view, so their directional views span whole clusters:
  // those the camera sees (a cluster it does not see lights them negligibly, shadow_fit.h's
  // clusterObjects). Refitted only when that set changes, so the views (and what extensions
  // derive from them) stay put while the camera moves within a cluster; a camera that sees none
  // keeps the last set.
  void fitLightViewsToClusters(const ShadowFitCamera& camera) {
    std::vector<bool> seen(clusters_.boxes.size(), false);
    for (size_t i = 0; i < shadowBoxes_.size(); ++i)
      if (!seen[size_t(clusters_.of[i])] && meetsFrustum(shadowBoxes_[i], camera))
        seen[size_t(clusters_.of[i])] = true;
    if (seen == litClusters_ || std::find(seen.begin(), seen.end(), true) == seen.end()) return;
    litClusters_ = seen;
    litBounds_ = LocalBox{};
    for (size_t k = 0; k < seen.size(); ++k)
      if (seen[k]) litBounds_.add(clusters_.boxes[k].lo), litBounds_.add(clusters_.boxes[k].hi);
    for (frame::LightRecord& r : lightRecords_) {
      if (int(r.position.w) != NL_LIGHT_DIRECTIONAL) continue;
      const size_t layer = size_t(r.shadow.x);
      const DirectionalShadowFit fit =
          fitDirectionalToBox(glm::vec3(r.direction), {litBounds_.lo, litBounds_.hi}, shadowBoxes_,
                              params_.shadowMapSize);
      shadowViews_[layer] = fit.clipFromWorld;
      shadowViewFromWorld_[layer] = fit.viewFromWorld;
      r.shadow.y = fit.texel;
      r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
    }
    lightsBuffer_.upload(lightRecords_.data(), lightRecords_.size() * sizeof(frame::LightRecord));
    shadowViewsBuffer_.upload(shadowViews_.data(), shadowViews_.size() * sizeof(glm::mat4));
    ++lightViewsGeneration_;
  }

  void setUpEnvironment() {
    if (!scene_.environment) return;
    envSource_ = std::make_unique<EnvironmentSource>(scene_.environment);
    // A sequence lights every frame, even if its first is black: extensions plan for a sky.
    uploadEnvironment(envSource_->at(0), envSource_->isSequence());
    envFrame_ = 0;
  }

  // The frame of a video light probe that `camera.time` plays, uploaded when it changes.
  void selectEnvironment(const SceneCamera& camera) {
    if (!envSource_ || !envSource_->isSequence()) return;
    const size_t frame = envSource_->frameAt(camera.time);
    if (frame == envFrame_) return;
    uploadEnvironment(envSource_->at(camera.time), true);
    envFrame_ = frame;
  }

  void uploadEnvironment(std::shared_ptr<const EnvironmentMap> map, bool sequence) {
    envMap_ = std::move(map);
    const EnvironmentMap& env = *envMap_;
    // What the path tracer says of a map, every GL method (they all light through this frame)
    // says too: texels it cannot use are black, not silently.
    if ((env.invalidTexels() || (env.black() && env.image().pixels() > 0)) && scene_.environment) {
      const auto& e = *scene_.environment;
      std::string what = (e.sequence.empty() ? e.path : e.sequence).string() + ": environment";
      if (env.invalidTexels())
        what += ": " + std::to_string(env.invalidTexels()) +
                " NaN, infinite or negative texels set to 0";
      if (env.black())
        what += std::string(env.invalidTexels() ? ";" : ":") + " all black, it adds no light";
      if (what != lastEnvWarning_) std::fprintf(stderr, "nestlight: warning: %s\n", what.c_str());
      lastEnvWarning_ = what;
    }
    envGeneration_++;
    hasEnvironment_ = sequence || !env.black();
    envRotation_ = glm::radians(env.rotationDegrees());
    envScale_ = env.scale();
    sh_ = irradianceSh(env);
    const HdrImage& img = env.image();
    const std::vector<float> rgba = img.rgba();
    // Mip levels for lookups averaged over a solid angle (environment.glsl's environmentOver: a
    // GI method's micro-buffer m-pixel, which point samples would alias on a small bright sun).
    int levels = 1;
    while ((std::max(img.width, img.height) >> levels) > 0) ++levels;
    if (!environment_ || environment_.width() != img.width || environment_.height() != img.height) {
      environment_ = gl::Texture(GL_RGBA32F, img.width, img.height, levels);
      environment_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
    }
    glTextureSubImage2D(environment_.id(), 0, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT,
                        rgba.data());
    glGenerateTextureMipmap(environment_.id());
  }

  void uploadMaterials() {
    std::vector<frame::MaterialRecord> recs;
    for (const Material& m : scene_.materials) {
      frame::MaterialRecord r{};
      const int type = m.type == MaterialType::Lambert ? NL_MATERIAL_LAMBERT
                       : m.type == MaterialType::GGX   ? NL_MATERIAL_GGX
                                                       : NL_MATERIAL_PRINCIPLED;
      r.baseColor = glm::vec4(m.baseColor.r, m.baseColor.g, m.baseColor.b, float(type));
      r.params = glm::vec4(m.roughness, m.metallic, m.specular, m.specularTint);
      r.params2 = glm::vec4(m.sheen, m.sheenTint, m.clearcoat, m.clearcoatGloss);
      r.emission = glm::vec4(m.emission.r, m.emission.g, m.emission.b, 0.0f);
      recs.push_back(r);
    }
    if (recs.empty()) recs.emplace_back();
    materialsBuffer_ = gl::Buffer(recs.size() * sizeof(frame::MaterialRecord), recs.data(), 0);
  }

  // Draws every scan's drawn nodes with `program` (shaders/points/points.vert, NL_SCENE_FRAME 1).
  void drawScans(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                 const glm::mat4& viewFromWorld, float pixelsPerUnit, bool orthographic,
                 bool lightsCut = false) override {
    program.use();
    glUniformMatrix4fv(program.uniform("uClipFromWorld"), 1, GL_FALSE, &clipFromWorld[0][0]);
    glUniformMatrix4fv(program.uniform("uViewFromWorld"), 1, GL_FALSE, &viewFromWorld[0][0]);
    glUniform1f(program.uniform("uPixelsPerUnit"), pixelsPerUnit);
    glUniform1i(program.uniform("uOrthographic"), orthographic ? 1 : 0);
    // Splats that follow their discs write their own depth (splat_surface.glsl): the view's
    // projection. A tile's guard band narrows x and y only, so depth is the same either way.
    const glm::mat4 clipFromView = clipFromWorld * glm::inverse(viewFromWorld);
    glUniformMatrix4fv(program.uniform("uClipFromView"), 1, GL_FALSE, &clipFromView[0][0]);
    glUniform1f(program.uniform("uSizeScale"), params_.splatScale);
    // Up to 64 px as the viewer; at least 1 px (shadow maps of far scans still occlude).
    glUniform2f(program.uniform("uSizeRange"), 1.0f, kMaxSplatPixels);
    glBindVertexArray(emptyVao_.id());
    forEachNode(
        program,
        [](const streaming::DrawNode& n) { glDrawArrays(GL_POINTS, 0, GLsizei(n.numPoints)); },
        lightsCut);
  }

  // Every drawn node of every scan with `program` current: its points bound at
  // NL_SSBO_NODE_POINTS, its uniforms (origin, place in the draw tree, cube size, point count,
  // the scan's colour scale) set; `draw` issues the draw or dispatch.
  void forEachNode(const gl::ShaderProgram& program,
                   const std::function<void(const streaming::DrawNode&)>& draw,
                   bool lightsCut = false) {
    const GLint nodeOrigin = program.uniform("uNodeOrigin"),
                nodeIndex = program.uniform("uNodeIndex"), nodeSize = program.uniform("uNodeSize"),
                numPoints = program.uniform("uNumPoints"),
                colourScale = program.uniform("uColourScale"),
                hdrColour = program.uniform("uHdrColour");
    for (auto& s : scans_) {
      (lightsCut ? s.shadowTree : s.tree).bind();
      glUniform1f(colourScale, s.colourScale);
      glUniform1i(hdrColour, s.store->hdrColour());
      const auto& nodes = (lightsCut ? s.shadowStreamer : s.streamer)->drawList();
      for (size_t k = 0; k < nodes.size(); ++k) {
        const auto& n = nodes[k];
        if (n.numPoints == 0) continue;
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, s.store->buffer(n.handle),
                          0, GLsizeiptr(size_t(n.numPoints) * frame::kGpuPointBytes));
        const glm::vec3 origin =
            scene_.local({n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z});
        glUniform3f(nodeOrigin, origin.x, origin.y, origin.z);
        glUniform1i(nodeIndex, int(k));
        glUniform1f(nodeSize, float(n.worldBounds.max.x - n.worldBounds.min.x));
        glUniform1ui(numPoints, n.numPoints);
        draw(n);
      }
    }
  }

  void drawMeshes(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                  bool materials) override {
    program.use();
    glUniformMatrix4fv(program.uniform("uClipFromWorld"), 1, GL_FALSE, &clipFromWorld[0][0]);
    for (const auto& m : meshes_) {
      if (materials) {
        const Material& mat = scene_.materials.at(m.material);
        glUniform3f(program.uniform("uBaseColor"), mat.baseColor.r, mat.baseColor.g,
                    mat.baseColor.b);
        glUniform1i(program.uniform("uMaterialType"),
                    mat.type == MaterialType::Lambert ? NL_MATERIAL_LAMBERT
                    : mat.type == MaterialType::GGX   ? NL_MATERIAL_GGX
                                                      : NL_MATERIAL_PRINCIPLED);
        glUniform1f(program.uniform("uRoughness"), mat.roughness);
        glUniform1f(program.uniform("uMetallic"), mat.metallic);
        glUniform1ui(program.uniform("uMaterialIndex"), m.material);
      }
      glBindVertexArray(m.vao.id());
      glDrawElements(GL_TRIANGLES, m.indexCount, GL_UNSIGNED_INT, nullptr);
    }
  }

  // The G-buffer alone (the scan pass also writes its own HQS targets, which
  // PassContext::bindFramebuffer would attach too).
  void bindGBuffer(const frame::PassContext& ctx) {
    gbufferFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("base_colour"));
    gbufferFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("normal"));
    gbufferFbo_.attach(GL_COLOR_ATTACHMENT2, ctx.target("material"));
    gbufferFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
    gbufferFbo_.finish(3, "G-buffer");
    glBindFramebuffer(GL_FRAMEBUFFER, gbufferFbo_.id());
    glViewport(0, 0, ctx.tile().width, ctx.tile().height);
  }

  // GL drops a point whose centre lies outside the viewport, so splats centred just beyond the
  // tile (in the next tile, or beyond the image) would leave their part inside uncovered. Splats
  // are drawn into a viewport larger by half the largest splat on every side, with the projection
  // narrowed to match: pixels inside the tile map exactly as before. Returns the guarded clip.
  glm::mat4 guardBand(const frame::PassContext& ctx) const {
    const frame::Tile& t = ctx.tile();
    const int g = kGuardPixels;
    glm::mat4 narrow(1.0f);
    narrow[0][0] = float(t.width) / float(t.width + 2 * g);
    narrow[1][1] = float(t.height) / float(t.height + 2 * g);
    glViewport(-g, -g, t.width + 2 * g, t.height + 2 * g);
    return narrow * ctx.uniforms().clipFromWorld;
  }
  static constexpr float kMaxSplatPixels = 64.0f;
  static constexpr int kGuardPixels = int(kMaxSplatPixels / 2) + 1;

  // High-quality splatting's three passes (frame::PointSplatting) for every scan, into the tile's
  // G-buffer.
  void hqsScans(const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const auto& u = ctx.uniforms();
    // The splats' depth starts as the meshes' so that splats behind a mesh take no part.
    glCopyImageSubData(ctx.target("depth").id(), GL_TEXTURE_2D, 0, 0, 0, 0,
                       ctx.target("scan_depth").id(), GL_TEXTURE_2D, 0, 0, 0, 0, tile.width,
                       tile.height, 1);
    hqsDepthFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("scan_depth"));
    hqsDepthFbo_.finish(0, "HQS depth");
    hqsSumFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("scan_sum_colour"));
    hqsSumFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("scan_sum_normal"));
    hqsSumFbo_.attach(GL_COLOR_ATTACHMENT2, ctx.target("scan_sum_radius"));
    hqsSumFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("scan_depth"));
    hqsSumFbo_.finish(3, "HQS sums");
    bindGBuffer(ctx);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glEnable(GL_DEPTH_TEST);
    const glm::mat4 guarded = guardBand(ctx);
    frame::PointSplatting::HqsTargets t;
    t.depthFbo = hqsDepthFbo_.id();
    t.sumFbo = hqsSumFbo_.id();
    t.sums = 3;
    t.sumTextures = {ctx.target("scan_sum_colour").id(), ctx.target("scan_sum_normal").id(),
                     ctx.target("scan_sum_radius").id()};
    t.gbufferFbo = gbufferFbo_.id();
    t.resolveDepthFunc = GL_LESS;  // behind whatever mesh is nearer
    t.width = tile.width, t.height = tile.height;
    splatting_->hqs(t, params_.hqsDepthEpsilon, u.clipFromView,
                    [&](const gl::ShaderProgram& program, bool) {
                      drawScans(program, guarded, u.viewFromWorld, u.eye.w, false);
                    });
  }

  // The compute rasteriser's three passes (frame::PointSplatting) for every scan, into the tile's
  // G-buffer.
  void computeScans(const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const size_t pixels = size_t(tile.width) * tile.height;
    if (pixels * 16 > gl::kMaxSsboRange)
      throw Error("raster: a " + std::to_string(tile.width) + "x" + std::to_string(tile.height) +
                  " tile is too large for the compute rasteriser's per-pixel buffers (128 MiB)");
    const auto& u = ctx.uniforms();
    auto dispatch = [&](const gl::ShaderProgram& prog, bool) {
      prog.use();
      glUniformMatrix4fv(prog.uniform("uClipFromWorld"), 1, GL_FALSE, &u.clipFromWorld[0][0]);
      glUniformMatrix4fv(prog.uniform("uViewFromWorld"), 1, GL_FALSE, &u.viewFromWorld[0][0]);
      glUniform2i(prog.uniform("uViewport"), tile.width, tile.height);
      glUniform1f(prog.uniform("uSizeScale"), params_.splatScale);
      forEachNode(prog, [](const streaming::DrawNode& n) {
        glDispatchCompute((n.numPoints + 127) / 128, 1, 1);
      });
    };
    auto resolveUniforms = [&](const gl::ShaderProgram& r) {
      glUniform2i(r.uniform("uViewport"), tile.width, tile.height);
      glUniformMatrix4fv(r.uniform("uClipFromView"), 1, GL_FALSE, &u.clipFromView[0][0]);
      glUniform1f(r.uniform("uColourScale"), scans_.empty() ? 1.0f : scans_.front().colourScale);
      glUniform1i(r.uniform("uHdrColour"), !scans_.empty() && scans_.front().store->hdrColour());
    };
    bindGBuffer(ctx);
    splatting_->compute(tile.width, tile.height, false, gbufferFbo_.id(), GL_LESS, dispatch,
                        resolveUniforms);
  }

  void buildGraph() {
    using gl::ShaderProgram;
    meshGBuffer_ = ShaderProgram({{GL_VERTEX_SHADER, "gi/raster/mesh.vert"},
                                  {GL_FRAGMENT_SHADER, "gi/raster/mesh_gbuffer.frag"}});
    meshShadow_ = ShaderProgram({{GL_VERTEX_SHADER, "gi/raster/mesh.vert"},
                                 {GL_FRAGMENT_SHADER, "gi/raster/depth_only.frag"}});
    scanShadow_ = ShaderProgram({{GL_VERTEX_SHADER, "points/points.vert"},
                                 {GL_FRAGMENT_SHADER, "gi/raster/shadow_scan.frag"}},
                                {{"NL_SCENE_FRAME", "1"}});
    directLight_ = ShaderProgram({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                                  {GL_FRAGMENT_SHADER, "gi/raster/direct_light.frag"}});
    splatting_ = std::make_unique<frame::PointSplatting>(frame::SplatFrame::Scene,
                                                         params_.computeRasteriser);
    hqsDepthFbo_ = gl::Framebuffer::create();
    hqsSumFbo_ = gl::Framebuffer::create();
    gbufferFbo_ = gl::Framebuffer::create();
    emptyVao_ = gl::VertexArray::create();
    shadowFbo_ = gl::Framebuffer::create();

    const int S = params_.shadowMapSize;
    const int layers = std::max<int>(int(shadowViews_.size()), 1);
    graph_.addTarget("shadow_maps", {GL_DEPTH_COMPONENT32F, true, S, S, layers});
    graph_.addTarget("depth", {GL_DEPTH_COMPONENT32F});
    graph_.addTarget("base_colour", {GL_RGBA32F});
    graph_.addTarget("normal", {GL_RGBA16F});
    graph_.addTarget("material", {GL_RGBA16UI});
    graph_.addTarget("radiance", {GL_RGBA32F});
    // High-quality splatting's own: the splats' depth over the meshes', and the weighted sums.
    graph_.addTarget("scan_depth", {GL_DEPTH_COMPONENT32F});
    graph_.addTarget("scan_sum_colour", {GL_RGBA32F});
    graph_.addTarget("scan_sum_normal", {GL_RGBA32F});
    graph_.addTarget("scan_sum_radius", {GL_RGBA32F});
    graph_.addTarget("display", {GL_RGBA8});

    graph_.addPass(
        "shadow_maps", frame::Scope::Frame, [](frame::PassBuilder& b) { b.write("shadow_maps"); },
        [this, S](const frame::PassContext& ctx) {
          const gl::Texture& maps = ctx.target("shadow_maps");
          glEnable(GL_DEPTH_TEST);
          glDepthFunc(GL_LESS);
          glEnable(GL_PROGRAM_POINT_SIZE);
          glDisable(GL_BLEND);
          glDisable(GL_CULL_FACE);
          glViewport(0, 0, S, S);
          // Slope-scaled offset for triangles (points take theirs in the lookup).
          glEnable(GL_POLYGON_OFFSET_FILL);
          glPolygonOffset(1.5f, 2.0f);
          for (size_t layer = 0; layer < shadowViews_.size(); ++layer) {
            shadowFbo_.attachLayer(GL_DEPTH_ATTACHMENT, maps, int(layer));
            if (layer == 0) shadowFbo_.finish(0, "shadow map");
            glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo_.id());
            const float one = 1.0f;
            glClearBufferfv(GL_DEPTH, 0, &one);
            const glm::mat4& clip = shadowViews_[layer];
            drawMeshes(meshShadow_, clip, false);
            // Which light owns the layer: its projection sizes the splats.
            const frame::LightRecord* owner = nullptr;
            for (const auto& r : lightRecords_)
              if (size_t(r.shadow.x) <= layer) owner = &r;
            NL_CHECK(owner != nullptr);
            const bool ortho = int(owner->position.w) == NL_LIGHT_DIRECTIONAL;
            // Texels per world unit (orthographic) or per unit at distance 1 (perspective).
            drawScans(scanShadow_, clip, shadowViewFromWorld_[layer], 1.0f / owner->shadow.y, ortho,
                      true);
          }
          glDisable(GL_POLYGON_OFFSET_FILL);
        });

    auto gbufferWrites = [](frame::PassBuilder& b) {
      b.write("depth");
      b.write("base_colour");
      b.write("normal");
      b.write("material");
    };
    auto scanWrites = [gbufferWrites](frame::PassBuilder& b) {
      gbufferWrites(b);
      for (const char* t : {"scan_depth", "scan_sum_colour", "scan_sum_normal", "scan_sum_radius"})
        b.write(t);
    };
    graph_.addPass("gbuffer_meshes", frame::Scope::Tile, gbufferWrites,
                   [this](const frame::PassContext& ctx) {
                     ctx.bindFramebuffer();
                     glEnable(GL_DEPTH_TEST);
                     glDepthFunc(GL_LESS);
                     glDisable(GL_BLEND);
                     glDisable(GL_CULL_FACE);
                     frame::clearGBuffer();
                     drawMeshes(meshGBuffer_, ctx.uniforms().clipFromWorld, true);
                   });
    graph_.addPass(
        "gbuffer_scans", frame::Scope::Tile, scanWrites, [this](const frame::PassContext& ctx) {
          const auto& u = ctx.uniforms();
          if (params_.computeRasteriser) {
            computeScans(ctx);
            return;
          }
          if (params_.hqs) {
            hqsScans(ctx);
            return;
          }
          bindGBuffer(ctx);
          glEnable(GL_DEPTH_TEST);
          glEnable(GL_PROGRAM_POINT_SIZE);
          drawScans(splatting_->basic(), guardBand(ctx), u.viewFromWorld, u.eye.w, false);
          glViewport(0, 0, ctx.tile().width, ctx.tile().height);
        });
    graph_.addPass(
        "direct_light", frame::Scope::Tile,
        [](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "shadow_maps"})
            b.read(t);
          b.write("radiance");
          b.margin(1);  // pin-hole filling reads the 3 x 3 neighbourhood
        },
        [this](const frame::PassContext& ctx) {
          ctx.bindFramebuffer();
          glDisable(GL_DEPTH_TEST);
          directLight_.use();
          ctx.bindTexture("depth", 0);
          ctx.bindTexture("base_colour", 1);
          ctx.bindTexture("normal", 2);
          ctx.bindTexture("material", 3);
          const gl::Texture& maps = ctx.target("shadow_maps");
          maps.setFilter(GL_LINEAR, GL_LINEAR);
          maps.setDepthCompare(true);
          glBindTextureUnit(4, maps.id());
          bindEnvironment(directLight_);
          glUniform1i(directLight_.uniform("uSkyOnDiffuse"), skyOnDiffuse_ ? 1 : 0);
          lightsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_LIGHTS);
          shadowViewsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_SHADOW_VIEWS);
          materialsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_MATERIALS);
          glBindVertexArray(emptyVao_.id());
          glDrawArrays(GL_TRIANGLES, 0, 3);
        });
    if (extension_) radianceTarget_ = extension_->setUp(*this);
    cpuMeshes_ = {};  // meshes() is for setUp only
    frame::addToneMapPass(graph_, radianceTarget_, "display", exposure_);
  }

  Scene scene_;
  bool quiet_ = false;
  std::unique_ptr<RasterExtension> extension_;
  std::string radianceTarget_ = "radiance";  // what the tone map and the read-back take
  std::vector<CutNode> lightsCut_;
  uint64_t cutGeneration_ = 0;
  RasterParameters params_;
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
  bool skyOnDiffuse_ = true;
  int frameNumber_ = 0;
  double beforeFrameSeconds_ = 0;
  std::string output_;  // the target the graph was compiled for
};

}  // namespace

std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx,
                                           std::unique_ptr<RasterExtension> extension) {
  return std::make_unique<RasterMethod>(scene, ctx, std::move(extension));
}

}  // namespace nestlight::gi
