// The `vpl` method (nestlight/gi/vpl/vpl_method.h): Preiner, "Real-Time Global Illumination in
// Point Clouds" (light G-buffer, Halton VPLs with hierarchical warping, imperfect shadow maps
// with parabolic projection and pull-push, interleaved shading with a geometry-aware filter,
// multiple bounces), on the raster frame. ISMs: Ritschel, Grosch, Kim, Seidel, Dachsbacher and
// Kautz 2008, "Imperfect Shadow Maps for Efficient Computation of Indirect Illumination".
// Warping: Clarberg, Jarosz, Akenine-Moeller and Jensen 2005, "Wavelet Importance Sampling".
// Interleaved sampling: Keller and Heidrich 2001, "Interleaved Sampling".
#include "nestlight/gi/vpl/vpl_method.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/gtc/packing.hpp>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/interface.h"
#include "nestlight/frame/passes.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/raster/raster_frame.h"
#include "nestlight/gi/reference/reference_scene.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace vplglsl {
using vec4 = glm::vec4;
using ivec4 = glm::ivec4;
using uvec4 = glm::uvec4;
using mat4 = glm::mat4;
#include "gi/vpl/vpl_interface.glsl"
#include "interface/frame_interface.glsl"
}  // namespace vplglsl

namespace {

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

int log2Exact(int v) {
  int l = 0;
  while ((1 << l) < v) ++l;
  return l;
}

size_t pyramidLayerFloats(int size) {
  size_t n = 0;
  for (int s = size; s >= 1; s >>= 1) n += size_t(s) * size_t(s);
  return n;
}

size_t ismPyramidFloats(int size) {
  size_t n = 0;
  for (int s = size >> 1; s >= 1; s >>= 1) n += size_t(s) * size_t(s);
  return n;
}

// Importance pyramid and warping: shared by the method and warpImportanceOnGpu.
class ImportanceWarp {
 public:
  ImportanceWarp()
      : pyramid_({{GL_COMPUTE_SHADER, "gi/vpl/vpl_pyramid.comp"}}),
        warp_({{GL_COMPUTE_SHADER, "gi/vpl/vpl_warp.comp"}}) {}

  // `levels` holds level 0 of every layer (pyramidLayerFloats(size) floats per layer): fills the
  // levels above, then warps `count` Halton points into `samples`.
  void run(const gl::Buffer& levels, int size, int layers, int count, gl::Buffer& samples) const {
    levels.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, levels.bytes());
    pyramid_.use();
    glUniform1i(pyramid_.uniform("uSize"), size);
    for (int level = 1; (size >> level) >= 1; ++level) {
      glUniform1i(pyramid_.uniform("uLevel"), level);
      const GLuint g = GLuint(((size >> level) + 7) / 8);
      glDispatchCompute(g, g, GLuint(layers));
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    samples.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_SAMPLES, 0,
                      size_t(count) * sizeof(WarpSample));
    warp_.use();
    glUniform1i(warp_.uniform("uSize"), size);
    glUniform1i(warp_.uniform("uLayers"), layers);
    glUniform1i(warp_.uniform("uCount"), count);
    glUniform1i(warp_.uniform("uFirstIndex"), 1);
    glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }

 private:
  gl::ShaderProgram pyramid_, warp_;
};

class VplExtension : public RasterExtension {
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

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    return {{"vpls", std::to_string(params_.count) + (params_.autoCount ? " (auto)" : "")},
            {"bounces", std::to_string(bounces_)},
            {"light_resolution", std::to_string(params_.lightResolution)},
            {"ism_size", std::to_string(params_.ismSize)},
            {"ism_points", std::to_string(params_.ismPoints)},
            {"pull_push", std::to_string(params_.pullPushLevels)},
            {"interleave", std::to_string(params_.interleave)},
            {"clamp", std::to_string(params_.clampFraction).substr(0, 6)},
            {"energy_stop", std::to_string(params_.energyStop).substr(0, 6)},
            {"visibility", visibilityName()}};
  }

  std::string setUp(RasterFrame& f) override {
    const Scene& scene = f.scene();
    bounces_ = std::max(scene.gi.maxBounces, 1);
    radianceCache_ = scene.gi.mode == RadianceMode::RadianceCache;
    // Bounces as the reference counts them. With lights, the first bounce is direct light (the
    // raster frame's) and each further one a VPL generation; in the radiance-cache mode the scan's
    // emission reaching an object is already its first bounce, so the emitting generation counts
    // as bounce 1.
    generations_ = radianceCache_ ? bounces_ : bounces_ - 1;
    if (params_.autoCount) {
      // The most VPLs whose ISMs fit one buffer range, a power of two up to 16384; probes start
      // low.
      const size_t perVpl =
          size_t(std::max(generations_, 1)) * size_t(params_.ismSize) * size_t(params_.ismSize) * 4;
      autoCap_ = 16;
      while (autoCap_ < 16384 && size_t(autoCap_) * 2 * perVpl <= gl::kMaxSsboRange) autoCap_ *= 2;
      params_.count = std::min(64, autoCap_);
    }
    const size_t atlasBytes = size_t(params_.count) * size_t(std::max(generations_, 1)) *
                              size_t(params_.ismSize) * size_t(params_.ismSize) * 4;
    if (usesIsms() && atlasBytes > gl::kMaxSsboRange)
      throw Error(scene.file.string(), "gi.parameters.ism_size",
                  "the ISM atlas (vpls x VPL generations x ism_size^2 x 4 bytes = " +
                      std::to_string(atlasBytes >> 20) +
                      " MiB) exceeds one 128 MiB buffer range: lower vpls, bounces or ism_size");
    layers_ = int(f.lightClipFromWorld().size());
    setUpLightViews(f);
    setUpSurfels(f);
    if (exact()) {
      exactScene_ = ReferenceScene::load(scene);
      agreement_ = gl::Buffer(6 * 4);
    }
    compile();
    addPasses(f);
    return "radiance_gi";
  }

  void beforeFrame(RasterFrame& f) override {
    if (exact()) {
      const GLuint zero = 0;
      glClearNamedBufferData(agreement_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    }
    if (f.lightViewsGeneration() != lightViewsGeneration_) setUpLightViews(f);
    if (f.cutGeneration() != poolGeneration_) {
      buildPool(f);
      poolGeneration_ = f.cutGeneration();
    }
  }

  void describe(const RasterFrame& f, MethodFrame& out) const override {
    (void)f;
    out.attributes["nestlight:vpls"] = std::to_string(params_.count);
    out.attributes["nestlight:vpl_generations"] = std::to_string(generationsRun_);
    out.attributes["nestlight:ism_size"] = std::to_string(params_.ismSize);
    out.attributes["nestlight:interleave"] = std::to_string(params_.interleave);
    out.attributes["nestlight:clamp_distance"] = std::to_string(clampDistance_);
    out.attributes["nestlight:vpl_checksum"] = std::to_string(vplChecksum_);
    out.attributes["nestlight:vpls_live"] = std::to_string(liveVpls_);
    char line[320];
    std::snprintf(
        line, sizeof line,
        "; vpl: %d VPLs%s x %d generation(s) of %d bounce(s)%s, %d^2 ISMs from %llu pool points%s, "
        "interleave %dx%d, clamp %.3g",
        params_.count, autoNote_.c_str(), generationsRun_, bounces_, stopNote_.c_str(),
        params_.ismSize, (unsigned long long)poolPoints_, poolNote_.c_str(), params_.interleave,
        params_.interleave, double(clampDistance_));
    out.summary += line;
  }

  void afterReadBack(const std::vector<float>& rgba, MethodFrame& out) override {
    // Alpha holds the luminance the clamp removed (vpl_filter.frag): its share of the indirect
    // light is the clamp's measured bias.
    double loss = 0, total = 0;
    for (size_t p = 0; p + 3 < rgba.size(); p += 4) {
      loss += rgba[p + 3];
      total += luminance({rgba[p], rgba[p + 1], rgba[p + 2]});
    }
    const double ratio = total > 0 ? loss / total : 0;
    out.attributes["nestlight:clamp_loss"] = std::to_string(ratio);
    if (exact()) {
      GLuint c[6] = {0, 0, 0, 0, 0, 0};
      glGetNamedBufferSubData(agreement_.id(), 0, sizeof c, c);
      const double agree = c[1] ? double(c[0]) / c[1] : 1.0;
      const double weighted = c[5] ? double(c[4]) / c[5] : 1.0;
      out.attributes["nestlight:ism_agreement"] = std::to_string(agree);
      out.attributes["nestlight:ism_agreement_light"] = std::to_string(weighted);
      out.attributes["nestlight:ism_false_shadow"] =
          std::to_string(c[1] ? double(c[2]) / c[1] : 0.0);
      out.attributes["nestlight:ism_leak"] = std::to_string(c[1] ? double(c[3]) / c[1] : 0.0);
      char a[200];
      std::snprintf(a, sizeof a,
                    "; exact visibility: ISMs agreed on %.2f%% of %u pairs (%.2f%% false shadow, "
                    "%.2f%% leaks), "
                    "%.2f%% of the light",
                    100 * agree, c[1], c[1] ? 100.0 * c[2] / c[1] : 0.0,
                    c[1] ? 100.0 * c[3] / c[1] : 0.0, 100 * weighted);
      out.summary += a;
    }
    char line[96];
    std::snprintf(line, sizeof line, "; clamp removed %.3g%% of the image's light", 100 * ratio);
    out.summary += line;
  }

 private:
  // The lights' views' inverses, and the clamp's distance, relative to the clusters they span
  // (RasterFrame::lightViewBoundsLo): a mesh 1000 km away, in a cluster of its own, would
  // otherwise clamp every VPL's light. Again whenever the frame refits the views.
  void setUpLightViews(RasterFrame& f) {
    lightViewsGeneration_ = f.lightViewsGeneration();
    radius_ = 0.5f * glm::length(f.lightViewBoundsHi() - f.lightViewBoundsLo());
    clampDistance_ = std::max(params_.clampFraction * radius_, 1e-6f);
    layerOwner_.clear();
    const auto& clips = f.lightClipFromWorld();
    const int S = f.rasterParameters().shadowMapSize;
    std::vector<LightView> views;
    for (size_t layer = 0; layer < clips.size(); ++layer) {
      int owner = -1;
      for (size_t i = 0; i < f.lights().size(); ++i)
        if (size_t(f.lights()[i].shadow.x) <= layer) owner = int(i);
      NL_CHECK(owner >= 0);
      const frame::LightRecord& l = f.lights()[size_t(owner)];
      LightView v{};
      v.worldFromClip = glm::inverse(clips[layer]);
      const bool ortho = int(l.position.w) == NL_LIGHT_DIRECTIONAL;
      // shadow.y is a shadow-map texel at distance 1 (or in world units): half the view's width.
      v.info = glm::vec4(float(owner), l.shadow.y * float(S) * 0.5f, ortho ? 1.0f : 0.0f, 0.0f);
      views.push_back(v);
      layerOwner_.push_back(owner);
    }
    if (views.empty()) views.emplace_back();
    lightViews_ = gl::Buffer(views.size() * sizeof(LightView), views.data(), 0);
  }

  // The meshes' surfels join the ISM occluders (and the bounces' hit points) as nodes of their own.
  void setUpSurfels(RasterFrame& f) {
    const Scene& scene = f.scene();
    for (size_t mi = 0; mi < scene.meshes.size(); ++mi) {
      const SceneMesh& m = scene.meshes[mi];
      const TriangleMesh& mesh = f.meshes().at(mi);
      SurfelOptions o;
      o.method = m.surfelMethod;
      o.count = m.surfelCount;
      o.material = m.material;
      const Material& mat = scene.materials.at(m.material);
      o.baseColor = mat.baseColor;
      Surfels s = sampleSurfels(mesh, scene.localFromObject(m), o);
      if (s.positions.empty()) continue;
      double area = 0;
      glm::vec3 lo(INFINITY), hi(-INFINITY);
      for (size_t i = 0; i < s.positions.size(); ++i) {
        area += s.area[i];
        lo = glm::min(lo, s.positions[i]);
        hi = glm::max(hi, s.positions[i]);
      }
      const float spacing = float(std::sqrt(area / double(s.positions.size())));
      objectsLo_ = glm::min(objectsLo_, lo);
      objectsHi_ = glm::max(objectsHi_, hi);
      PoolNode n{};
      n.box = glm::vec4(0.5f * (lo + hi), 0.5f * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}));
      n.lod = glm::vec4(spacing, 1e30f, spacing, 0.0f);
      n.range = glm::ivec4(int(surfelPoints_.size()), int(s.positions.size()), 0, 0);
      surfelNodes_.push_back(n);
      for (size_t i = 0; i < s.positions.size(); ++i) {
        PoolPoint q{};
        q.position = glm::vec4(s.positions[i], 0.5f * spacing);
        const glm::vec3 nn = s.normals[i];
        float a = s.area[i];
        uint32_t areaBits;
        std::memcpy(&areaBits, &a, 4);
        q.surface =
            glm::uvec4(frame::packNormal(nn.x, nn.y, nn.z), packHalf2(s.albedo[i].r, s.albedo[i].g),
                       packHalf2(s.albedo[i].b, 0.0f) | (s.material[i] << 16), areaBits);
        surfelPoints_.push_back(q);
      }
    }
  }

  static uint32_t packHalf2(float a, float b) {
    return uint32_t(glm::packHalf1x16(std::min(a, 65504.f))) |
           (uint32_t(glm::packHalf1x16(std::min(b, 65504.f))) << 16);
  }

  void compile() {
    using gl::ShaderProgram;
    // Each mode makes only what its first generation needs: the lights' (albedo) or the
    // emitting scan points' (radiance cache).
    if (radianceCache_) {
      emitImportance_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_emit_importance.comp"}});
      emit_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_emit.comp"}});
    } else {
      scanGBuffer_ = ShaderProgram(
          {{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/points.frag"}},
          {{"NL_SCENE_FRAME", "1"}});
      meshGBuffer_ = ShaderProgram({{GL_VERTEX_SHADER, "gi/raster/mesh.vert"},
                                    {GL_FRAGMENT_SHADER, "gi/raster/mesh_gbuffer.frag"}});
      importance_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_importance.comp"}});
      generate_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_generate.comp"}});
      lightFbo_ = gl::Framebuffer::create();
      pyramid_ = gl::Buffer(pyramidLayerFloats(params_.lightResolution) *
                            size_t(std::max(layers_, 1)) * 4);
    }
    bounce_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_bounce.comp"}});
    gather_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_gather.comp"}});
    splat_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_splat.comp"}});
    pull_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_pull.comp"}});
    push_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_push.comp"}});
    shade_ = ShaderProgram({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                            {GL_FRAGMENT_SHADER, "gi/vpl/vpl_shade.frag"}});
    filter_ = ShaderProgram({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                             {GL_FRAGMENT_SHADER, "gi/vpl/vpl_filter.frag"}});
    warp_ = std::make_unique<ImportanceWarp>();
    emptyVao_ = gl::VertexArray::create();
    allocateCountBuffers();
  }

  // The buffers whose size follows the VPL count.
  void allocateCountBuffers() {
    samples_ = gl::Buffer(size_t(params_.count) * sizeof(WarpSample));
    records_ =
        gl::Buffer(size_t(params_.count) * size_t(std::max(generations_, 1)) * sizeof(VplRecord));
    if (usesIsms()) {
      const size_t isms = size_t(params_.count) * size_t(std::max(generations_, 1));
      ism_ = gl::Buffer(isms * size_t(params_.ismSize) * size_t(params_.ismSize) * 4);
      ismLevels_ = gl::Buffer(std::max<size_t>(isms * ismPyramidFloats(params_.ismSize) * 4, 16));
    }
  }

  void setCount(int n) {
    if (n == params_.count) return;
    params_.count = n;
    allocateCountBuffers();
  }

  // "vpls": "auto". Stills: a warm-up frame, then frames at 64 and 256 VPLs give a + b x count,
  // then the count that fits target_ms. Interactive: the frame time, smoothed, halves or doubles
  // the count when it leaves [0.5, 1.25] x target (at most every 8 frames: the VPLs change only
  // then).
  bool afterFrame(double seconds, bool still) override {
    if (!params_.autoCount) return false;
    const double target = params_.targetMs * 1e-3;
    if (still) {
      if (autoDecided_) return false;
      // The first frame pays one-time costs (shader compilation, the pool): it only warms up.
      probes_.emplace_back(params_.count, seconds);
      if (probes_.size() == 1) return true;
      if (probes_.size() == 2) {
        setCount(std::min(256, autoCap_));
        return true;
      }
      const auto [n1, t1] = probes_[probes_.size() - 2];
      const auto [n2, t2] = probes_.back();
      const double b = n2 != n1 ? (t2 - t1) / double(n2 - n1) : 0, a = t1 - b * n1;
      // No measurable cost per VPL: all fit, or none does.
      int n = t2 <= target ? autoCap_ : 16;
      if (b > 0) {
        const double fit = (target - a) / b;
        n = 16;
        while (n * 2 <= autoCap_ && n * 2 <= fit) n *= 2;
      }
      autoDecided_ = true;
      autoNote_ =
          " (auto: " + std::to_string(n) + " fit " + std::to_string(int(params_.targetMs)) + " ms)";
      setCount(n);
      return n != n2;
    }
    smoothed_ = smoothed_ > 0 ? 0.8 * smoothed_ + 0.2 * seconds : seconds;
    if (++sinceChange_ < 8) return false;
    if (smoothed_ > 1.25 * target && params_.count > 16)
      setCount(params_.count / 2), sinceChange_ = 0;
    else if (smoothed_ < 0.5 * target && params_.count * 2 <= autoCap_)
      setCount(params_.count * 2), sinceChange_ = 0;
    return false;
  }

  void bindCommon(RasterFrame& f) const {
    f.bindSceneBuffers();
    lightViews_.bindBase(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_LIGHT_VIEWS);
    records_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_RECORDS, 0, records_.bytes());
  }

  void setPoolUniforms(const gl::ShaderProgram& p) const {
    glUniform1i(p.uniform("uNodeCount"), int(poolNodeCount_));
    glUniform1i(p.uniform("uIsmSize"), params_.ismSize);
    glUniform1f(p.uniform("uLodScale"), params_.lodScale);
    glUniform1ui(p.uniform("uPointBudget"), GLuint(params_.ismPoints));
    if (pool_.bytes()) pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
    if (poolNodes_.bytes())
      poolNodes_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL_NODES, 0, poolNodes_.bytes());
  }

  // The ISM pool: the lights' cut's points (gathered on the GPU from the nodes' buffers) and the
  // meshes' surfels, with a node table for the level-of-detail choice.
  void buildPool(RasterFrame& f) {
    const auto& cut = f.lightsCut();
    std::vector<PoolNode> nodes;
    std::vector<char> hasChild(cut.size(), 0);
    for (const auto& c : cut)
      if (c.parent >= 0) hasChild[size_t(c.parent)] = 1;
    const size_t maxPoints = gl::kMaxSsboRange / sizeof(PoolPoint) - surfelPoints_.size();
    uint64_t points = 0, dropped = 0;
    std::vector<size_t> taken;
    for (size_t i = 0; i < cut.size(); ++i) {
      const CutNode& c = cut[i];
      if (c.numPoints == 0) continue;
      if (points + c.numPoints > maxPoints) {  // the finest nodes come last in the list
        dropped += c.numPoints;
        continue;
      }
      PoolNode n{};
      n.box = glm::vec4(c.origin + glm::vec3(0.5f * c.size), 0.5f * c.size);
      const float parentSpacing = c.parent >= 0 ? cut[size_t(c.parent)].spacing : 1e30f;
      n.lod = glm::vec4(c.spacing, parentSpacing, hasChild[i] ? 0.0f : c.spacing, 0.0f);
      n.range = glm::ivec4(int(points), int(c.numPoints), 0, 0);
      nodes.push_back(n);
      taken.push_back(i);
      points += c.numPoints;
    }
    const uint64_t scanPoints = points;
    scanPoints_ = scanPoints;
    emitSide_ = 1;
    while (uint64_t(emitSide_) * uint64_t(emitSide_) < scanPoints) emitSide_ *= 2;
    if (radianceCache_ && scanPoints > 0)
      emitPyramid_ = gl::Buffer(pyramidLayerFloats(emitSide_) * 4);
    for (PoolNode n : surfelNodes_) {
      n.range.x += int(scanPoints);
      nodes.push_back(n);
    }
    points += surfelPoints_.size();
    poolPoints_ = points;
    poolNote_ =
        dropped ? " (" + std::to_string(dropped) + " points of the finest nodes left out: 128 MiB)"
                : "";
    poolNodeCount_ = nodes.size();
    pool_ = points ? gl::Buffer(points * sizeof(PoolPoint)) : gl::Buffer();
    poolNodes_ =
        nodes.empty() ? gl::Buffer() : gl::Buffer(nodes.size() * sizeof(PoolNode), nodes.data(), 0);
    if (!surfelPoints_.empty())
      pool_.upload(surfelPoints_.data(), surfelPoints_.size() * sizeof(PoolPoint),
                   scanPoints * sizeof(PoolPoint));
    if (scanPoints == 0) return;
    pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
    gather_.use();
    const float splat = f.rasterParameters().splatScale;
    int boundScan = -1;
    for (size_t j = 0; j < taken.size(); ++j) {
      const CutNode& c = cut[taken[j]];
      if (c.scan != boundScan) f.bindLightsCutTree(boundScan = c.scan);
      glUniform1i(gather_.uniform("uNodeIndex"), c.indexInScan);
      glUniform1f(gather_.uniform("uNodeSize"), c.size);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, c.buffer, 0,
                        GLsizeiptr(size_t(c.numPoints) * frame::kGpuPointBytes));
      glUniform3f(gather_.uniform("uNodeOrigin"), c.origin.x, c.origin.y, c.origin.z);
      glUniform1i(gather_.uniform("uFirst"), nodes[j].range.x);
      glUniform1ui(gather_.uniform("uNumPoints"), c.numPoints);
      glUniform1f(gather_.uniform("uRadius"), 0.5f * c.spacing * splat * 0.5f);
      glUniform1f(gather_.uniform("uColourScale"), c.colourScale);
      glUniform1i(gather_.uniform("uHdrColour"), c.hdrColour);
      glDispatchCompute((c.numPoints + 127) / 128, 1, 1);
    }
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

  void addPasses(RasterFrame& f) {
    frame::FrameGraph& g = f.graph();
    g.addBuffer("vpls");
    g.addBuffer("ism_raw");
    g.addBuffer("ism");
    g.addTarget("vpl_indirect", {GL_RGBA32F});
    g.addTarget("vpl_clamp_loss", {GL_RGBA32F});
    g.addTarget("radiance_gi", {GL_RGBA32F});
    const char* lightTargets[] = {"light_depth", "light_base", "light_normal", "light_material"};
    // The lights' VPLs (albedo mode). In the radiance-cache mode the first generation is drawn on
    // the emitting scan points instead (vpl_generate), and neither pass exists.
    if (!radianceCache_) addLightPasses(f, lightTargets);

    // VPLs: the first generation from the samples (or the emitting scan points), then one
    // generation per further bounce while each still re-emits at least energy_stop of what came
    // before.
    g.addPass(
        "vpl_generate", frame::Scope::Frame,
        [&](frame::PassBuilder& b) {
          if (!radianceCache_) {
            for (const char* t : lightTargets) b.read(t);
            b.read("vpl_samples");
          }
          b.write("vpls");
        },
        [this, &f](const frame::PassContext& ctx) { generateVpls(f, ctx); });

    addVisibilityAndShadingPasses(f);
  }

  // The light G-buffer and the warped samples on it.
  void addLightPasses(RasterFrame& f, const char* const (&lightTargets)[4]) {
    frame::FrameGraph& g = f.graph();
    const int G = params_.lightResolution, layers = std::max(layers_, 1);
    g.addTarget("light_depth", {GL_DEPTH_COMPONENT32F, true, G, G, layers});
    g.addTarget("light_base", {GL_RGBA32F, true, G, G, layers});
    g.addTarget("light_normal", {GL_RGBA16F, true, G, G, layers});
    g.addTarget("light_material", {GL_RGBA16UI, true, G, G, layers});
    g.addBuffer("vpl_samples");

    // The light G-buffer: every light's views (the shadow maps' projections) of the meshes and
    // the lights' cut, with the camera G-buffer's shaders and encoding.
    g.addPass(
        "light_gbuffer", frame::Scope::Frame,
        [&](frame::PassBuilder& b) {
          for (const char* t : lightTargets) b.write(t);
        },
        [this, &f, G](const frame::PassContext& ctx) {
          glEnable(GL_DEPTH_TEST);
          glDepthFunc(GL_LESS);
          glEnable(GL_PROGRAM_POINT_SIZE);
          glDisable(GL_BLEND);
          glDisable(GL_CULL_FACE);
          glViewport(0, 0, G, G);
          const int S = f.rasterParameters().shadowMapSize;
          for (int layer = 0; layer < layers_; ++layer) {
            lightFbo_.attachLayer(GL_COLOR_ATTACHMENT0, ctx.target("light_base"), layer);
            lightFbo_.attachLayer(GL_COLOR_ATTACHMENT1, ctx.target("light_normal"), layer);
            lightFbo_.attachLayer(GL_COLOR_ATTACHMENT2, ctx.target("light_material"), layer);
            lightFbo_.attachLayer(GL_DEPTH_ATTACHMENT, ctx.target("light_depth"), layer);
            lightFbo_.finish(3, "light G-buffer");
            glBindFramebuffer(GL_FRAMEBUFFER, lightFbo_.id());
            frame::clearGBuffer();
            const glm::mat4& clip = f.lightClipFromWorld()[size_t(layer)];
            f.drawMeshes(meshGBuffer_, clip, true);
            const frame::LightRecord& l = f.lights()[size_t(layerOwner_[size_t(layer)])];
            const bool ortho = int(l.position.w) == NL_LIGHT_DIRECTIONAL;
            // Texels per unit at distance 1 (or per world unit): the shadow map's, rescaled.
            const float pixelsPerUnit = float(G) / (l.shadow.y * float(S));
            f.drawScans(scanGBuffer_, clip, f.lightViewFromWorld()[size_t(layer)], pixelsPerUnit,
                        ortho, true);
          }
        });

    // Importance, its pyramid and the warped Halton samples.
    g.addPass(
        "vpl_warp", frame::Scope::Frame,
        [&](frame::PassBuilder& b) {
          for (const char* t : lightTargets) b.read(t);
          b.write("vpl_samples");
        },
        [this, &f, G, layers](const frame::PassContext& ctx) {
          bindCommon(f);
          bindLightTextures(ctx);
          pyramid_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, pyramid_.bytes());
          importance_.use();
          glUniform1i(importance_.uniform("uLayerStride"), int(pyramidLayerFloats(G)));
          if (layers_ > 0) {
            glDispatchCompute(GLuint((G + 7) / 8), GLuint((G + 7) / 8), GLuint(layers_));
          } else {
            const float zero = 0;
            glClearNamedBufferData(pyramid_.id(), GL_R32F, GL_RED, GL_FLOAT, &zero);
          }
          glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
          warp_->run(pyramid_, G, layers, params_.count, samples_);
        });
  }

  void generateVpls(RasterFrame& f, const frame::PassContext& ctx) {
    bindCommon(f);
    generationsRun_ = 0;
    stopNote_.clear();
    vplChecksum_ = 14695981039346656037ull;
    liveVpls_ = 0;
    if (generations_ == 0) return;
    if (radianceCache_) {
      emitFromScans();
    } else {
      bindLightTextures(ctx);
      samples_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_SAMPLES, 0, samples_.bytes());
      generate_.use();
      glUniform1i(generate_.uniform("uCount"), params_.count);
      glDispatchCompute(GLuint((params_.count + 63) / 64), 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }
    generationsRun_ = 1;
    double emitted = emittedFlux(0);
    for (int gen = 1; gen < generations_; ++gen) {
      bounce_.use();
      setPoolUniforms(bounce_);
      glUniform1i(bounce_.uniform("uParentFirst"), (gen - 1) * params_.count);
      glUniform1i(bounce_.uniform("uChildFirst"), gen * params_.count);
      glUniform1i(bounce_.uniform("uCount"), params_.count);
      glUniform1i(bounce_.uniform("uRadianceCache"), radianceCache_ ? 1 : 0);
      if (poolNodeCount_ == 0) {
        // Nothing to hit: the generation is dark.
        std::vector<VplRecord> dark(size_t(params_.count));
        records_.upload(dark.data(), dark.size() * sizeof(VplRecord),
                        size_t(gen) * params_.count * sizeof(VplRecord));
      } else {
        glDispatchCompute(GLuint(params_.count), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
      }
      generationsRun_ = gen + 1;
      const double e = emittedFlux(gen);
      if (!(e >= params_.energyStop * emitted)) {
        char note[96];
        std::snprintf(note, sizeof note,
                      " (stopped: generation %d re-emits %.2g%% of the ones before)", gen + 1,
                      emitted > 0 ? 100 * e / emitted : 0.0);
        stopNote_ = note;
        // Its light is still counted (it is computed); the next is not made.
        break;
      }
      emitted += e;
    }
  }

  // ISMs, pull-push, (exact visibility,) shading and the filter.
  void addVisibilityAndShadingPasses(RasterFrame& f) {
    frame::FrameGraph& g = f.graph();
    if (usesIsms()) {
      g.addPass(
          "ism", frame::Scope::Frame,
          [](frame::PassBuilder& b) {
            b.read("vpls");
            b.write("ism_raw");
          },
          [this, &f](const frame::PassContext&) {
            bindCommon(f);
            const GLuint far = VPL_FAR_BITS;
            glClearNamedBufferData(ism_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &far);
            if (poolNodeCount_ == 0 || generationsRun_ == 0) return;
            ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
            splat_.use();
            setPoolUniforms(splat_);
            glUniform1i(splat_.uniform("uFirstVpl"), 0);
            glDispatchCompute(GLuint(params_.count * generationsRun_), 1, 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
          });
      g.addPass(
          "pull_push", frame::Scope::Frame,
          [](frame::PassBuilder& b) {
            b.read("ism_raw");
            b.write("ism");
          },
          [this](const frame::PassContext&) {
            const int S = params_.ismSize;
            const int levels = std::min(params_.pullPushLevels, log2Exact(S));
            if (levels == 0 || generationsRun_ == 0) return;
            ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
            ismLevels_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM_PYRAMID, 0,
                                 ismLevels_.bytes());
            const GLuint isms = GLuint(params_.count * generationsRun_);
            auto run = [&](const gl::ShaderProgram& p, int level) {
              p.use();
              glUniform1i(p.uniform("uIsmSize"), S);
              glUniform1i(p.uniform("uLevel"), level);
              glUniform1i(p.uniform("uFirstVpl"), 0);
              const GLuint n = GLuint(((S >> level) + 7) / 8);
              glDispatchCompute(n, n, isms);
              glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
            };
            for (int l = 1; l <= levels; ++l) run(pull_, l);
            for (int l = levels - 1; l >= 0; --l) run(push_, l);
          });
    }

    if (exact()) {
      g.addBuffer("vpl_exact");
      g.addPass(
          "vpl_exact", frame::Scope::Tile,
          [](frame::PassBuilder& b) {
            for (const char* t : {"depth", "base_colour", "normal", "vpls"}) b.read(t);
            b.write("vpl_exact");
          },
          [this](const frame::PassContext& ctx) { exactVisibility(ctx); });
    }

    g.addPass(
        "vpl_shade", frame::Scope::Tile,
        [this](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "vpls"}) b.read(t);
          if (usesIsms()) b.read("ism");
          if (exact()) b.read("vpl_exact");
          b.write("vpl_indirect");
          b.write("vpl_clamp_loss");
        },
        [this, &f](const frame::PassContext& ctx) {
          ctx.bindFramebuffer();
          glDisable(GL_DEPTH_TEST);
          glDisable(GL_BLEND);
          shade_.use();
          bindCommon(f);
          ctx.bindTexture("depth", 0);
          ctx.bindTexture("base_colour", 1);
          ctx.bindTexture("normal", 2);
          ctx.bindTexture("material", 3);
          if (usesIsms()) ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
          if (exact()) {
            exactBits_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_EXACT, 0, exactBits_.bytes());
            agreement_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_AGREEMENT, 0,
                                 agreement_.bytes());
          }
          glUniform1i(shade_.uniform("uExactWords"), exactWords_);
          glUniform1i(shade_.uniform("uVplCount"), params_.count * generationsRun_);
          glUniform1i(shade_.uniform("uInterleave"), params_.interleave);
          glUniform1i(shade_.uniform("uIsmSize"), params_.ismSize);
          glUniform1f(shade_.uniform("uClampDistance"), clampDistance_);
          glUniform1f(shade_.uniform("uIsmBias"), params_.ismBias);
          glUniform1i(shade_.uniform("uVisibility"), exact() ? 2 : usesIsms() ? 1 : 0);
          glBindVertexArray(emptyVao_.id());
          glDrawArrays(GL_TRIANGLES, 0, 3);
        });

    g.addPass(
        "vpl_filter", frame::Scope::Tile,
        [this](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "vpl_indirect",
                                "vpl_clamp_loss", "radiance"})
            b.read(t);
          b.write("radiance_gi");
          b.margin(params_.interleave / 2 + 1);
        },
        [this, &f](const frame::PassContext& ctx) {
          ctx.bindFramebuffer();
          glDisable(GL_DEPTH_TEST);
          filter_.use();
          f.bindSceneBuffers();
          ctx.bindTexture("depth", 0);
          ctx.bindTexture("base_colour", 1);
          ctx.bindTexture("normal", 2);
          ctx.bindTexture("material", 3);
          ctx.bindTexture("vpl_indirect", 4);
          ctx.bindTexture("vpl_clamp_loss", 5);
          ctx.bindTexture("radiance", 6);
          glUniform1i(filter_.uniform("uInterleave"), params_.interleave);
          glBindVertexArray(emptyVao_.id());
          glDrawArrays(GL_TRIANGLES, 0, 3);
        });
  }

  // Embree's visibility for every (pixel, VPL of its subset) pair of the tile, as bits; the
  // receiver and the VPL are lifted off their surfaces by their disc radii and 1e-3 of the
  // scene's extent.
  void exactVisibility(const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const int w = tile.width, h = tile.height;
    const frame::FrameBlock& u = ctx.uniforms();
    std::vector<float> depth(size_t(w) * h), base(size_t(w) * h * 4), normal(size_t(w) * h * 4);
    glGetTextureSubImage(ctx.target("depth").id(), 0, 0, 0, 0, w, h, 1, GL_DEPTH_COMPONENT,
                         GL_FLOAT, GLsizei(depth.size() * 4), depth.data());
    glGetTextureSubImage(ctx.target("base_colour").id(), 0, 0, 0, 0, w, h, 1, GL_RGBA, GL_FLOAT,
                         GLsizei(base.size() * 4), base.data());
    glGetTextureSubImage(ctx.target("normal").id(), 0, 0, 0, 0, w, h, 1, GL_RGBA, GL_FLOAT,
                         GLsizei(normal.size() * 4), normal.data());
    const int total = params_.count * generationsRun_;
    std::vector<VplRecord> vpls(size_t(std::max(total, 1)));
    if (total > 0)
      glGetNamedBufferSubData(records_.id(), 0, GLsizeiptr(size_t(total) * sizeof(VplRecord)),
                              vpls.data());
    const int N = params_.interleave;
    const int perSubset = (total + N * N - 1) / (N * N);
    exactWords_ = std::max(1, (perSubset + 31) / 32);
    std::vector<uint32_t> bits(size_t(w) * h * size_t(exactWords_), 0xffffffffu);
    const float eps = 1e-3f * exactScene_->extent();
    const glm::vec3 eye(u.eye);
    tbb::parallel_for(0, h, [&](int y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        if (!(depth[i] < 1.0f)) continue;
        const glm::vec2 ndc = (glm::vec2(x, y) + 0.5f) / glm::vec2(w, h) * 2.0f - 1.0f;
        const glm::vec4 wp = u.worldFromClip * glm::vec4(ndc, depth[i] * 2 - 1, 1);
        const glm::vec3 p = glm::vec3(wp) / wp.w;
        const glm::vec3 wo = glm::normalize(eye - p);
        glm::vec3 n(normal[4 * i], normal[4 * i + 1], normal[4 * i + 2]);
        n = normal[4 * i + 3] > 0 ? glm::normalize(n) : wo;
        if (glm::dot(n, wo) < 0) n = -n;
        const float radius = base[4 * i + 3];
        const glm::ivec2 g = glm::ivec2(int(u.tile.x) + x, int(u.tile.y) + y);
        const int subset = (g.x % N) + N * (g.y % N);
        for (int k = subset, slot = 0; k < total; k += N * N, ++slot) {
          const VplRecord& v = vpls[size_t(k)];
          if (v.flux.x == 0 && v.flux.y == 0 && v.flux.z == 0) continue;
          const glm::vec3 x0(v.position), nv(v.normal);
          const glm::vec3 d = p - x0;
          const float dist = glm::length(d);
          if (!(dist > 0)) continue;
          const glm::vec3 dir = d / dist;
          if (glm::dot(nv, dir) <= 0 || glm::dot(n, dir) >= 0) continue;  // no light either way
          // Both ends lifted off their surfaces along the normals: positions read back from
          // depth buffers sit a little above or below them.
          const glm::vec3 from = x0 + nv * (v.position.w + eps), to = p + n * (radius + eps);
          const glm::vec3 seg = to - from;
          const float len = glm::length(seg);
          if (!(len > 2 * eps)) continue;
          if (exactScene_->occluded(from, seg / len, len - eps))
            bits[i * size_t(exactWords_) + size_t(slot / 32)] &= ~(1u << (slot % 32));
        }
      }
    });
    exactBits_.reserve(bits.size() * 4);
    exactBits_.upload(bits.data(), bits.size() * 4);
  }

  // Radiance-cache mode: the first generation drawn on the scans' emitting points, by luminance x
  // area (hierarchical warping over the pool laid out as a square). Without inserted objects
  // there is nothing for them to light (scan pixels take no indirect light in this mode).
  void emitFromScans() {
    const bool any = scanPoints_ > 0 && surfelPoints_.size() > 0;
    if (!any) {
      std::vector<VplRecord> dark(size_t(params_.count));
      records_.upload(dark.data(), dark.size() * sizeof(VplRecord), 0);
      return;
    }
    const float zero = 0;
    glClearNamedBufferData(emitPyramid_.id(), GL_R32F, GL_RED, GL_FLOAT, &zero);
    pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
    emitPyramid_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, emitPyramid_.bytes());
    emitImportance_.use();
    glUniform1i(emitImportance_.uniform("uScanPoints"), int(scanPoints_));
    glDispatchCompute(GLuint((scanPoints_ + 127) / 128), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    warp_->run(emitPyramid_, emitSide_, 1, params_.count, samples_);
    samples_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_SAMPLES, 0, samples_.bytes());
    records_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_RECORDS, 0, records_.bytes());
    pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
    emit_.use();
    glUniform1i(emit_.uniform("uCount"), params_.count);
    glUniform1i(emit_.uniform("uSide"), emitSide_);
    const glm::vec3 c = 0.5f * (objectsLo_ + objectsHi_);
    glUniform3f(emit_.uniform("uObjectsCentre"), c.x, c.y, c.z);
    glDispatchCompute(GLuint((params_.count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }

  void bindLightTextures(const frame::PassContext& ctx) const {
    ctx.bindTexture("light_depth", 0);
    ctx.bindTexture("light_base", 1);
    ctx.bindTexture("light_normal", 2);
    ctx.bindTexture("light_material", 3);
  }

  // The flux generation `gen` re-emits: the sum over its VPLs of their flux times their surface's
  // albedo (luminance). Read back: a few tens of kilobytes.
  // Also folds the generation into the frame's VPL checksum (FNV-1a of the records: equal
  // checksums, the same VPLs) and counts its live VPLs.
  double emittedFlux(int gen) {
    std::vector<VplRecord> r(size_t(params_.count));
    glGetNamedBufferSubData(records_.id(), GLintptr(size_t(gen) * r.size() * sizeof(VplRecord)),
                            GLsizeiptr(r.size() * sizeof(VplRecord)), r.data());
    const auto* bytes = reinterpret_cast<const unsigned char*>(r.data());
    for (size_t i = 0; i < r.size() * sizeof(VplRecord); ++i)
      vplChecksum_ = (vplChecksum_ ^ bytes[i]) * 1099511628211ull;
    double sum = 0;
    for (const auto& v : r) {
      if (v.flux.x != 0 || v.flux.y != 0 || v.flux.z != 0) ++liveVpls_;
      const glm::vec3 flux(v.flux), base(v.baseColour);
      const float metallic = v.flux.w;
      const glm::vec3 albedo =
          int(v.baseColour.w) == NL_MATERIAL_LAMBERT
              ? base
              : (1 - metallic) * base + glm::mix(glm::vec3(0.04f), base, metallic);
      const double e = luminance(flux * albedo);
      if (std::isfinite(e)) sum += e;
    }
    return sum;
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
  std::unique_ptr<ImportanceWarp> warp_;
  gl::Framebuffer lightFbo_;
  gl::VertexArray emptyVao_;
};

}  // namespace

std::unique_ptr<Method> createVplMethod(const Scene& scene, const MethodContext& ctx) {
  auto ext = std::make_unique<VplExtension>(scene);
  return createRasterMethod(scene, ctx, std::move(ext));
}

std::vector<WarpedSample> warpImportanceOnGpu(const std::vector<float>& importance, int size,
                                              int layers, int count) {
  NL_CHECK(size > 0 && (size & (size - 1)) == 0 && layers > 0 && count > 0);
  NL_CHECK(importance.size() == size_t(size) * size_t(size) * size_t(layers));
  const size_t stride = pyramidLayerFloats(size);
  std::vector<float> levels(stride * size_t(layers), 0.0f);
  for (int l = 0; l < layers; ++l)
    std::copy(importance.begin() + ptrdiff_t(size_t(l) * size * size),
              importance.begin() + ptrdiff_t(size_t(l + 1) * size * size),
              levels.begin() + ptrdiff_t(size_t(l) * stride));
  gl::Buffer pyramid(levels.size() * 4, levels.data());
  gl::Buffer samples(size_t(count) * sizeof(WarpSample));
  ImportanceWarp warp;
  warp.run(pyramid, size, layers, count, samples);
  std::vector<WarpSample> raw(static_cast<size_t>(count));
  glGetNamedBufferSubData(samples.id(), 0, GLsizeiptr(raw.size() * sizeof(WarpSample)), raw.data());
  std::vector<WarpedSample> out;
  for (const auto& r : raw) {
    WarpedSample s;
    s.x = r.texel.x, s.y = r.texel.y, s.layer = r.texel.z, s.valid = r.texel.w == 1,
    s.probability = r.where.z;
    out.push_back(s);
  }
  return out;
}

}  // namespace nestlight::gi
