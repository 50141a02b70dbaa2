// The GI frame (nestlight/gi/frame/scene_frame.h): the `raster` method and the frame every GL
// method extends, driven here: made from the scene (scans, meshes, lights, environment,
// materials), its passes in order (shadow maps, G-buffer, direct light, the extension's, the
// tone map), stills and interactive frames rendered, what a frame reports. The concerns live
// beside it (scene_frame_impl.h lists them).
#include <cstdio>

#include "scene_frame_impl.h"

namespace nestlight::gi {

namespace frame_detail {

RasterMethod::RasterMethod(const Scene& scene, const MethodContext& mc,
                           std::unique_ptr<FrameExtension> extension)
    : scene_(scene), quiet_(mc.quiet), extension_(std::move(extension)) {
  graph_.setSyncTiming(mc.syncPassTiming);
  params_ = parseFrameParameters(
      scene, extension_ ? extension_->parameterKeys() : std::vector<std::string>{});
  if (!mc.glContextCurrent) {
    context_ = gl::createHeadlessContext();
    if (!quiet_) std::fprintf(stderr, "raster: %s\n", context_->description().c_str());
  }
  mc.report("streaming the scans' lights' cuts", 0.05);
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
  mc.report("reading the meshes", 0.3);
  loadMeshes();
  mc.report("lights", 0.45);
  setUpLights();
  mc.report("environment", 0.5);
  setUpEnvironment();
  uploadMaterials();
  // Compiling the passes' programs is most of a GL method's set-up on a CPU rasteriser.
  mc.report(
      extension_ ? "compiling shaders, setting up " + extension_->name() : "compiling shaders",
      0.6);
  buildGraph();
}

RasterMethod::~RasterMethod() {
  if (context_) context_->makeCurrent();
  // Streamers release their nodes into the stores while the context lives; the extension's GL
  // objects go first.
  extension_.reset();
  scans_.clear();
}

MethodFrame RasterMethod::render(const SceneCamera& cameraIn) {
  if (context_) context_->makeCurrent();
  setOutput(radianceTarget_);
  if (cameraIn.width <= 0 || cameraIn.height <= 0)
    throw Error(scene_.file.string(), "camera", "the image size must be positive");
  const int ss = extension_ ? std::max(1, extension_->supersample()) : 1;
  SceneCamera camera = cameraIn;
  camera.width *= ss, camera.height *= ss;
  const int W = camera.width, H = camera.height;
  selectEnvironment(camera);
  still_ = true;
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
  if (ss > 1) {  // box-filtered back to the camera's pixels
    const int w = cameraIn.width, h = cameraIn.height;
    std::vector<float> small(size_t(w) * size_t(h) * 4, 0.0f);
    const float weight = 1.0f / float(ss * ss);
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        for (int c = 0; c < 4; ++c)
          small[(size_t(y / ss) * w + size_t(x / ss)) * 4 + c] +=
              weight * rgba[(size_t(y) * W + size_t(x)) * 4 + c];
    rgba = std::move(small);
  }
  MethodFrame f;
  f.seconds = secondsSince(t0) + beforeFrameSeconds_;
  f.image = imageOf(rgba, cameraIn.width, cameraIn.height);
  describe(f, drawPoints, streamSeconds);
  if (extension_) extension_->afterReadBack(rgba, f);
  return f;
}

unsigned RasterMethod::renderInteractive(const SceneCamera& camera, float exposureStops,
                                         MethodFrame* stats) {
  if (context_) context_->makeCurrent();
  if (params_.computeRasteriser && size_t(camera.width) * camera.height * 16 > gl::kMaxSsboRange)
    throw Error(scene_.file.string(), "gi.parameters.rasteriser",
                "a " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                    " window is too large for the compute rasteriser's per-pixel buffers (128 "
                    "MiB); use \"points\"");
  setOutput("display");
  *exposure_ = exposureStops;
  selectEnvironment(camera);
  still_ = false;
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

std::vector<std::pair<std::string, std::string>> RasterMethod::parameters() const {
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

void RasterMethod::setOutput(const std::string& output) {
  if (output_ == output) return;
  graph_.compile(output);
  output_ = output;
}

// The frame's programs, GL objects and targets, and its passes in order.
void RasterMethod::buildGraph() {
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
  splatting_ =
      std::make_unique<frame::PointSplatting>(frame::SplatFrame::Scene, params_.computeRasteriser);
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

  // Shadow maps, the G-buffer (meshes, then scans), direct light, the extension's passes reading
  // it, and the tone map of what the extension returns (or of direct light).
  addShadowMapPass();
  addGBufferPasses();
  addDirectLightPass();
  if (extension_) radianceTarget_ = extension_->setUp(*this);
  cpuMeshes_ = {};  // meshes() is for setUp only
  addToneMapPass();
}

void RasterMethod::describe(MethodFrame& f, uint64_t drawPoints, double streamSeconds) const {
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

}  // namespace frame_detail

std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx,
                                           std::unique_ptr<FrameExtension> extension) {
  return std::make_unique<frame_detail::RasterMethod>(scene, ctx, std::move(extension));
}

}  // namespace nestlight::gi
