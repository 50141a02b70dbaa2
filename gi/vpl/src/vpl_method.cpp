// The `vpl` method (nestlight/gi/vpl/vpl_method.h): Preiner, "Real-Time Global Illumination in
// Point Clouds" (light G-buffer, Halton VPLs with hierarchical warping, imperfect shadow maps
// with parabolic projection and pull-push, interleaved shading with a geometry-aware filter,
// multiple bounces), on the raster frame. ISMs: Ritschel, Grosch, Kim, Seidel, Dachsbacher and
// Kautz 2008, "Imperfect Shadow Maps for Efficient Computation of Indirect Illumination".
// Warping: Clarberg, Jarosz, Akenine-Moeller and Jensen 2005, "Wavelet Importance Sampling".
// Interleaved sampling: Keller and Heidrich 2001, "Interleaved Sampling".
#include "nestlight/gi/vpl/vpl_method.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nestlight/gi/sampling.h"
#include "nestlight/octree/error.h"
#include "vpl_extension.h"

namespace nestlight::gi::vpl {

std::vector<std::pair<std::string, std::string>> VplExtension::parameters() const {
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

std::string VplExtension::setUp(SceneFrame& f) {
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

void VplExtension::beforeFrame(SceneFrame& f) {
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

void VplExtension::describe(const SceneFrame& f, MethodFrame& out) const {
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

void VplExtension::afterReadBack(const std::vector<float>& rgba, MethodFrame& out) {
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
    out.attributes["nestlight:ism_false_shadow"] = std::to_string(c[1] ? double(c[2]) / c[1] : 0.0);
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

// The lights' views' inverses, and the clamp's distance, relative to the clusters they span
// (SceneFrame::lightViewBoundsLo): a mesh 1000 km away, in a cluster of its own, would
// otherwise clamp every VPL's light. Again whenever the frame refits the views.
void VplExtension::setUpLightViews(SceneFrame& f) {
  lightViewsGeneration_ = f.lightViewsGeneration();
  radius_ = 0.5f * glm::length(f.lightViewBoundsHi() - f.lightViewBoundsLo());
  clampDistance_ = std::max(params_.clampFraction * radius_, 1e-6f);
  layerOwner_.clear();
  const auto& clips = f.lightClipFromWorld();
  const int S = f.frameParameters().shadowMapSize;
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

void VplExtension::compile() {
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
    pyramid_ =
        gl::Buffer(pyramidLayerFloats(params_.lightResolution) * size_t(std::max(layers_, 1)) * 4);
  }
  bounce_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/vpl_bounce.comp"}});
  gather_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_gather.comp"}});
  splat_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_splat.comp"}});
  pull_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_pull.comp"}});
  push_ = ShaderProgram({{GL_COMPUTE_SHADER, "gi/vpl/ism_push.comp"}});
  shade_ = ShaderProgram(
      {{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "gi/vpl/vpl_shade.frag"}},
      {{"VPL_EXACT_VISIBILITY", "0"}});
  filter_ = ShaderProgram({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                           {GL_FRAGMENT_SHADER, "gi/vpl/vpl_filter.frag"}});
  warp_ = std::make_unique<ImportanceWarp>();
  emptyVao_ = gl::VertexArray::create();
  allocateCountBuffers();
}

// The buffers whose size follows the VPL count.
void VplExtension::allocateCountBuffers() {
  samples_ = gl::Buffer(size_t(params_.count) * sizeof(WarpSample));
  records_ =
      gl::Buffer(size_t(params_.count) * size_t(std::max(generations_, 1)) * sizeof(VplRecord));
  if (usesIsms()) {
    const size_t isms = size_t(params_.count) * size_t(std::max(generations_, 1));
    ism_ = gl::Buffer(isms * size_t(params_.ismSize) * size_t(params_.ismSize) * 4);
    ismLevels_ = gl::Buffer(std::max<size_t>(isms * ismPyramidFloats(params_.ismSize) * 4, 16));
  }
}

// "vpls": "auto". Stills: a warm-up frame, then frames at 64 and 256 VPLs give a + b x count,
// then the count that fits target_ms. Interactive: the frame time, smoothed, halves or doubles
// the count when it leaves [0.5, 1.25] x target (at most every 8 frames: the VPLs change only
// then).
bool VplExtension::afterFrame(double seconds, bool still) {
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

void VplExtension::addPasses(SceneFrame& f) {
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

// ISMs, pull-push, (exact visibility,) shading and the filter.
void VplExtension::addVisibilityAndShadingPasses(SceneFrame& f) {
  if (usesIsms()) {
    addIsmPass(f);
    addPullPushPass(f);
  }
  if (exact()) addExactPass(f);
  addShadePass(f);
  addFilterPass(f);
}

void VplExtension::generateVpls(SceneFrame& f, const frame::PassContext& ctx) {
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

// The flux generation `gen` re-emits: the sum over its VPLs of their flux times their surface's
// albedo (luminance). Read back: a few tens of kilobytes.
// Also folds the generation into the frame's VPL checksum (FNV-1a of the records: equal
// checksums, the same VPLs) and counts its live VPLs.
double VplExtension::emittedFlux(int gen) {
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

}  // namespace nestlight::gi::vpl

namespace nestlight::gi {

std::unique_ptr<Method> createVplMethod(const Scene& scene, const MethodContext& ctx) {
  auto ext = std::make_unique<vpl::VplExtension>(scene);
  return createRasterMethod(scene, ctx, std::move(ext));
}

}  // namespace nestlight::gi
