// The `ibl` method (nestlight/gi/ibl/ibl_method.h): Kronander, Dahlin, Jönsson, Kok, Schön and
// Unger, "Real-time video based lighting using GPU raytracing" (2014), sections 4 to 7, as a pass
// of the raster frame: per frame the environment's CDF tables (built on the CPU and uploaded, as
// the paper does), then one compute pass over the G-buffer's receivers (shaders/gi/ibl/).
#include "nestlight/gi/ibl/ibl_method.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/ibl/environment_table.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/gi/shared/bsh_layer.h"
#include "nestlight/gi/shared/cut_hierarchies.h"
#include "nestlight/gi/shared/triangle_bvh.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace {

int estimatorCode(IblParameters::Estimator e) {
  switch (e) {
    case IblParameters::Estimator::Mis:
      return IBL_MIS;
    case IblParameters::Estimator::Bis:
      return IBL_BIS;
    case IblParameters::Estimator::Smc:
      return IBL_SMC;
    case IblParameters::Estimator::Environment:
      return IBL_ENVIRONMENT;
    case IblParameters::Estimator::Brdf:
      return IBL_BRDF;
  }
  return IBL_MIS;
}

// SMC's bridges between two frames' maps. A frame's update weighs each carried sample by
// gamma_t / gamma_t-1 = L_t / L_t-1 (the BSDF cancels), whose relative variance over the samples is
// the chi-square divergence of the two maps' light, chi2 = sum p_t^2 / p_t-1 - 1 (p: a texel's
// luminance times solid angle over the power). Under a moving sun that is e^(d^2/s^2) - 1 for a
// shift of d at width s: about 14 for the bench's sun moving 1.6 of its widths a frame, so the
// samples that would find the sun's new position carry weights far above the rest, and the
// estimate of Z_t / Z_t-1 is heavy-tailed (usually far too small, rarely far too large: Z lags the
// light, and the reinitialisation on a jump cuts the rare large ones off, so it also drifts
// down). K geometric bridges divide the log of the ratio by K, its variance by K^2, and each
// brings one Metropolis-Hastings move that carries the samples along: K is chosen so that every
// bridge's weights have chi2 at most kBridgeChi2 (an effective sample size of 95%) under that
// model, K = sqrt(ln(1 + chi2) / ln(1 + kBridgeChi2)), at least `smc_intermediate` and at most
// kBridgesMax. The count depends on the maps alone, never on the samples, so the update stays
// unbiased. A texel lit now and black before (p_t-1 = 0) has no finite chi2: the most bridges.
constexpr double kBridgeChi2 = 0.05;
constexpr int kBridgesMax = 16;
int smcBridges(const EnvironmentMap& previous, const EnvironmentMap& current, int least) {
  const HdrImage &a = previous.image(), &b = current.image();
  if (&previous == &current) return least;
  if (a.width != b.width || a.height != b.height || a.pixels() == 0)
    return std::max(least, kBridgesMax);
  std::vector<double> pa(a.pixels()), pb(b.pixels());
  double sa = 0, sb = 0;
  for (int y = 0; y < a.height; ++y) {
    const double band =
        std::cos(double(kPi) * y / a.height) - std::cos(double(kPi) * (y + 1) / a.height);
    for (int x = 0; x < a.width; ++x) {
      const size_t i = size_t(y) * size_t(a.width) + size_t(x);
      sa += pa[i] = std::max(0.0, double(luminance(a.get(x, y)))) * band;
      sb += pb[i] = std::max(0.0, double(luminance(b.get(x, y)))) * band;
    }
  }
  if (!(sa > 0) || !(sb > 0)) return least;  // a black frame: the samples start afresh
  double chi2 = -1;
  for (size_t i = 0; i < pa.size(); ++i) {
    if (pb[i] <= 0) continue;
    if (pa[i] <= 0) return std::max(least, kBridgesMax);
    chi2 += (pb[i] / sb) * (pb[i] / sb) / (pa[i] / sa);
  }
  const int k =
      int(std::ceil(std::sqrt(std::log1p(std::max(chi2, 0.0)) / std::log1p(kBridgeChi2))));
  return std::clamp(k, least, std::max(least, kBridgesMax));
}

// The scan's hierarchies as rays read them: pbgi's, unpruned (every leaf a point's disc, below),
// with each inner node's slab, the heights above and below its sphere's centre along its normal
// cone's axis between which every disc under it lies, in colour.x and colour.y (colour.z 1; 0
// where the node has no axis). Visibility needs no colour. A ray whose heights along its chord
// through the sphere miss the slab meets nothing under the node: exact, so the images are the
// unpruned traversal's. It stops where pbgi's pruning stopped (a receiver's own flat patch, for a
// ray leaving it; a distant patch a ray passes over) without standing a cluster's disc in for its
// points, which shadowed curved scans (see setUp).
class SlabBshLayer : public frame::NodeLayer {
 public:
  SlabBshLayer(const Metadata& meta, std::shared_ptr<const ScanColours> colours,
               std::shared_ptr<const ClipSet> clip)
      : inner_(meta, unpruned(), std::move(colours), std::move(clip)) {}
  std::string name() const override { return "ibl_bsh"; }
  void prepare(const NodeKey& key, const PointBuffer& points, const std::vector<uint8_t>& gpuPoints,
               std::vector<uint8_t>& out) const override {
    inner_.prepare(key, points, gpuPoints, out);
    const size_t count = out.size() / sizeof(BshNode);
    std::vector<BshNode> nodes(count);
    if (count) std::memcpy(nodes.data(), out.data(), count * sizeof(BshNode));
    // Depth first: a node's sub-tree is [i, end), its right child's sub-tree ending it.
    std::vector<uint32_t> end(count);
    for (size_t i = count; i-- > 0;)
      end[i] = nodes[i].links.x == BSH_LEAF ? uint32_t(i + 1) : end[nodes[i].links.y];
    for (size_t i = 0; i < count; ++i) {
      BshNode& n = nodes[i];
      if (n.links.x == BSH_LEAF) continue;
      const glm::vec3 axis = frame::unpackNormal(n.links.w), c(n.sphere);
      if (n.links.w == 0 || !(glm::length(axis) > 0.5f)) {
        n.colour = glm::vec4(0, 0, 0, n.colour.w);
        continue;
      }
      float lo = INFINITY, hi = -INFINITY;
      for (uint32_t k = uint32_t(i + 1); k < end[i]; ++k) {
        const BshNode& l = nodes[k];
        if (l.links.x != BSH_LEAF) continue;
        const float disc = std::min(std::bit_cast<float>(l.links.y), l.sphere.w);
        const glm::vec3 m = frame::unpackNormal(l.links.w);
        // A disc about m reaches disc * sin(angle to the axis) either side of its centre's height;
        // one without a normal faces each ray: its whole sphere.
        const float cosA = glm::dot(m, axis);
        const float reach =
            l.links.w == 0 ? l.sphere.w : disc * std::sqrt(std::max(0.0f, 1.0f - cosA * cosA));
        const float h = glm::dot(glm::vec3(l.sphere) - c, axis);
        lo = std::min(lo, h - reach), hi = std::max(hi, h + reach);
      }
      // Float rounding of the centres, the heights and the decoded axes, as the shader will meet
      // them.
      const float mag = std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z), n.sphere.w});
      const float pad = 1e-4f * n.sphere.w + 8.0f * mag * 1.2e-7f;
      n.colour = glm::vec4(lo - pad, hi + pad, 1.0f, n.colour.w);
    }
    if (count) std::memcpy(out.data(), nodes.data(), count * sizeof(BshNode));
  }

 private:
  static BshOptions unpruned() {
    BshOptions o;
    o.prune = false;
    return o;
  }
  BshLayer inner_;
};

class IblExtension : public FrameExtension {
 public:
  explicit IblExtension(const Scene& scene)
      : params_(iblParameters(scene)), seed_(uint32_t(scene.gi.seed)) {}

  std::string name() const override { return "ibl"; }
  // The environment's visibility is traced, not read from shadow maps: the scene's lights are
  // raster's direct light, read at the camera's pixels only.
  bool shadowsForTheCameraOnly() const override { return true; }
  std::vector<std::string> parameterKeys() const override {
    return parameterNames(iblParameterSpecs());
  }

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    return {{"estimator", estimatorName(params_.estimator)},
            {"brdf_samples", std::to_string(params_.brdfSamples)},
            {"env_samples", std::to_string(params_.envSamples)},
            {"bis_proposals", std::to_string(params_.bisProposals)},
            {"bis_samples", std::to_string(params_.bisSamples)},
            {"smc_particles", std::to_string(params_.smcParticles)},
            {"smc_intermediate", std::to_string(params_.smcIntermediate)},
            {"smc_local_probability", std::to_string(params_.smcLocalProbability)},
            {"smc_local_degrees", std::to_string(params_.smcLocalDegrees)},
            {"smc_reinit_ratio", std::to_string(params_.smcReinitRatio)},
            {"smc_reinit_on_drop", params_.smcReinitOnDrop ? "true" : "false"},
            {"visibility", params_.visibility ? "true" : "false"},
            {"smc_statistics", params_.smcStatistics ? "true" : "false"},
            {"smc_band_rows", std::to_string(params_.smcBandRows)}};
  }

  std::string setUp(SceneFrame& f) override {
    const Scene& scene = f.scene();
    // This pass owns the environment's light on every receiver, occluded: direct light must not
    // add its unshadowed irradiance too.
    f.setSkyInDirectLight(false);
    // The scan occludes through the hierarchies pbgi gathers from (built per node on the loader
    // threads, joined under a top tree when the cut changes), but unpruned: every leaf is a point's
    // disc, as the reference's. pbgi's pruning makes a flat-enough sub-tree one disc in its points'
    // mean plane; on a curved scan that plane stands above the points at the cluster's rim (by up
    // to a fifth of its radius at pbgi's normal agreement), far above the lift a receiver leaves
    // its own surface by, and the receivers there lost their sky: dark rings on the object scene's
    // scanned sphere, 7% of a scanned 10 m dome's light (tests/gi/ibl/ibl_scan_test.cpp).
    // Pruned sub-trees' discs cost less than every point's; their slabs (SlabBshLayer) win that
    // time back exactly.
    layer_ = f.addNodeLayer([](const Metadata& meta, std::shared_ptr<const ScanColours> colours,
                               std::shared_ptr<const ClipSet> clip) {
      return std::make_shared<SlabBshLayer>(meta, std::move(colours), std::move(clip));
    });
    std::vector<glm::vec3> corners;
    const auto& meshes = f.meshes();
    for (size_t i = 0; i < meshes.size() && i < scene.meshes.size(); ++i) {
      const glm::mat4 localFromObject = scene.localFromObject(scene.meshes[i]);
      for (uint32_t idx : meshes[i].indices)
        corners.push_back(glm::vec3(localFromObject * glm::vec4(meshes[i].positions[idx], 1.0f)));
    }
    const auto t0 = std::chrono::steady_clock::now();
    TriangleBvh bvh = buildTriangleBvh(corners);
    bvhMs_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    bvhNodes_ = bvh.nodes.size();
    bvhTriangles_ = bvh.triangles.size();
    bvhDepth_ = bvh.depth;
    NL_CHECK_MSG(bvh.nodes.size() * sizeof(BvhNode) <= gl::kMaxSsboRange &&
                     bvh.triangles.size() * sizeof(BvhTriangle) <= gl::kMaxSsboRange,
                 "ibl: the meshes' BVH exceeds one 128 MiB buffer range");
    bvh_ = gl::Buffer(std::max<size_t>(bvh.nodes.size(), 1) * sizeof(BvhNode),
                      bvh.nodes.empty() ? nullptr : bvh.nodes.data(), 0);
    triangles_ = gl::Buffer(std::max<size_t>(bvh.triangles.size(), 1) * sizeof(BvhTriangle),
                            bvh.triangles.empty() ? nullptr : bvh.triangles.data(), 0);
    program_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/ibl/ibl_shade.comp"}},
                                 {{"IBL_SMC_N", std::to_string(params_.smcParticles)}});
    stats_ = gl::Buffer(IBL_STAT_COUNT * 4);
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    llvmpipe_ = renderer && std::strstr(renderer, "llvmpipe");
    frame::FrameGraph& g = f.graph();
    g.addTarget("radiance_ibl", {GL_RGBA32F});
    g.addPass(
        "ibl_shade", frame::Scope::Tile,
        [](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
            b.read(t);
          b.write("radiance_ibl");
        },
        [this, &f](const frame::PassContext& ctx) { shade(f, ctx); });
    return "radiance_ibl";
  }

  void beforeFrame(SceneFrame& f) override {
    if (f.cutGeneration() != generation_) {
      generation_ = f.cutGeneration();
      hier_.assemble(f, layer_);
    }
    std::shared_ptr<const EnvironmentMap> current = f.environmentMap();
    if (current != tableMap_) {
      const ibl::EnvironmentTable t = ibl::buildEnvironmentTable(*current);
      tableMs_ = t.buildSeconds * 1e3;
      tableBuilds_++;
      envTable_.reserve(t.data.size() * sizeof(float));
      envTable_.upload(t.data.data(), t.data.size() * sizeof(float));
      tableMap_ = current;
    }
    // SMC's previous target: the map the last frame lit with (this frame's on the first).
    const std::shared_ptr<const EnvironmentMap> previous = lastMap_ ? lastMap_ : current;
    if (params_.estimator == IblParameters::Estimator::Smc && previous != prevTextureMap_) {
      uploadPrevious(*previous);
      prevTextureMap_ = previous;
    }
    if (params_.estimator == IblParameters::Estimator::Smc &&
        (current != bridgesMap_ || previous != bridgesPrev_)) {
      bridges_ = smcBridges(*previous, *current, params_.smcIntermediate);
      bridgesMap_ = current, bridgesPrev_ = previous;
    }
    prevEnvScale_ = previous->scale();
    lastMap_ = current;
    std::array<uint32_t, IBL_STAT_COUNT> zeros{};
    stats_.upload(zeros.data(), sizeof zeros);
    hasPrevious_ = stateValid_;
    frameClip_ = false;
  }

  void describe(const SceneFrame&, MethodFrame& mf) const override {
    std::array<uint32_t, IBL_STAT_COUNT> s{};
    glGetNamedBufferSubData(stats_.id(), 0, sizeof s, s.data());
    mf.attributes["nestlight:ibl_estimator"] = estimatorName(params_.estimator);
    mf.attributes["nestlight:ibl_receivers"] = std::to_string(s[IBL_STAT_RECEIVERS]);
    mf.attributes["nestlight:ibl_rays"] = std::to_string(s[IBL_STAT_RAYS]);
    mf.attributes["nestlight:ibl_table_ms"] = std::to_string(tableMs_);
    mf.attributes["nestlight:ibl_table_builds"] = std::to_string(tableBuilds_);
    mf.attributes["nestlight:ibl_bvh_triangles"] = std::to_string(bvhTriangles_);
    mf.attributes["nestlight:ibl_bvh_nodes"] = std::to_string(bvhNodes_);
    mf.attributes["nestlight:ibl_bvh_ms"] = std::to_string(bvhMs_);
    mf.attributes["nestlight:ibl_scan_hierarchy_nodes"] = std::to_string(hier_.nodeCount());
    mf.attributes["nestlight:ibl_scan_cut_nodes"] = std::to_string(hier_.cutNodes());
    mf.attributes["nestlight:ibl_scan_nodes_left_out"] = std::to_string(hier_.leftOut());
    mf.rays += s[IBL_STAT_RAYS];
    mf.attributes["nestlight:ibl_loop_limit_pixels"] = std::to_string(s[IBL_STAT_LOOP_LIMIT]);
    char line[256];
    std::snprintf(
        line, sizeof line, "; ibl %s: %u receivers, %u visibility rays; CDF tables %.2f ms",
        estimatorName(params_.estimator), s[IBL_STAT_RECEIVERS], s[IBL_STAT_RAYS], tableMs_);
    mf.summary += line;
    if (s[IBL_STAT_LOOP_LIMIT] && llvmpipe_)
      mf.summary += "; warning: " + std::to_string(s[IBL_STAT_LOOP_LIMIT]) +
                    " pixels neared llvmpipe's 65,535 loop iterations per invocation (their "
                    "estimates may be cut "
                    "short): use fewer samples per pixel";
    if (params_.estimator == IblParameters::Estimator::Smc) {
      mf.attributes["nestlight:ibl_smc_reprojected"] = std::to_string(s[IBL_STAT_REPROJECTED]);
      mf.attributes["nestlight:ibl_smc_reinit_jump"] = std::to_string(s[IBL_STAT_REINIT_JUMP]);
      mf.attributes["nestlight:ibl_smc_reinit_new"] = std::to_string(s[IBL_STAT_REINIT_NEW]);
      mf.attributes["nestlight:ibl_smc_resampled"] = std::to_string(s[IBL_STAT_RESAMPLED]);
      mf.attributes["nestlight:ibl_smc_moves"] = std::to_string(s[IBL_STAT_MOVES]);
      mf.attributes["nestlight:ibl_smc_accepted"] = std::to_string(s[IBL_STAT_ACCEPTED]);
      mf.attributes["nestlight:ibl_smc_bridges"] = std::to_string(bridges_);
      std::snprintf(line, sizeof line,
                    "; smc: %d bridges, %u carried, %u reinitialised on a jump, %u started afresh, "
                    "%u resampled, %u of %u moves accepted",
                    bridges_, s[IBL_STAT_REPROJECTED], s[IBL_STAT_REINIT_JUMP],
                    s[IBL_STAT_REINIT_NEW], s[IBL_STAT_RESAMPLED], s[IBL_STAT_ACCEPTED],
                    s[IBL_STAT_MOVES]);
      mf.summary += line;
      if (params_.smcStatistics) {
        // The carried normalising constants Z_t of the frame just rendered (afterFrame, before
        // this, swapped it into stateIn_), over the pixels holding samples.
        std::vector<uint32_t> words(stateIn_.bytes() / 4);
        glGetNamedBufferSubData(stateIn_.id(), 0, GLsizeiptr(words.size() * 4), words.data());
        const size_t stride = size_t(8 + 2 * params_.smcParticles);
        const size_t rowWords = (size_t(stateW_) * stride + 63) / 64 * 64;
        std::vector<float> z;
        for (int y = 0; y < stateH_; ++y)
          for (int x = 0; x < stateW_; ++x) {
            const size_t base = size_t(y) * rowWords + size_t(x) * stride;
            if (base + 5 < words.size() && words[base + 5] == 1u)
              z.push_back(std::bit_cast<float>(words[base + 3]));
          }
        double mean = 0;
        for (float v : z) mean += v;
        mean = z.empty() ? 0 : mean / double(z.size());
        std::nth_element(z.begin(), z.begin() + std::ptrdiff_t(z.size() / 2), z.end());
        mf.attributes["nestlight:ibl_smc_z_pixels"] = std::to_string(z.size());
        mf.attributes["nestlight:ibl_smc_z_mean"] = std::to_string(mean);
        mf.attributes["nestlight:ibl_smc_z_median"] =
            std::to_string(z.empty() ? 0.0f : z[z.size() / 2]);
      }
    }
  }

  bool afterFrame(double, bool) override {
    if (params_.estimator == IblParameters::Estimator::Smc && frameClip_) {
      std::swap(stateIn_, stateOut_);
      stateValid_ = true;
      prevClipFromWorld_ = clipFromWorld_;
    }
    return false;
  }

 private:
  void uploadPrevious(const EnvironmentMap& map) {
    const HdrImage& img = map.image();
    const int w = std::max(img.width, 1), h = std::max(img.height, 1);
    std::vector<float> rgba = img.rgba();
    rgba.resize(size_t(w) * size_t(h) * 4, 0.0f);  // no environment: one black texel
    if (prevTexture_.width() != w || prevTexture_.height() != h)
      prevTexture_ = gl::Texture(GL_RGBA32F, w, h);
    glTextureSubImage2D(prevTexture_.id(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, rgba.data());
  }

  void shade(SceneFrame& f, const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const bool smc = params_.estimator == IblParameters::Estimator::Smc;
    f.bindSceneBuffers();
    ctx.bindTexture("depth", 0);
    ctx.bindTexture("base_colour", 1);
    ctx.bindTexture("normal", 2);
    ctx.bindTexture("material", 3);
    ctx.bindTexture("radiance", 4);
    glBindImageTexture(0, ctx.target("radiance_ibl").id(), 0, GL_FALSE, 0, GL_READ_WRITE,
                       GL_RGBA32F);
    program_.use();
    f.bindEnvironment(program_);
    envTable_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_ENV);
    bvh_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_BVH);
    triangles_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_TRIANGLES);
    stats_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_STATS);
    glUniform1i(program_.uniform("uEstimator"), estimatorCode(params_.estimator));
    glUniform1i(program_.uniform("uBrdfSamples"), params_.brdfSamples);
    glUniform1i(program_.uniform("uEnvSamples"), params_.envSamples);
    glUniform1i(program_.uniform("uBisM"), params_.bisProposals);
    glUniform1i(program_.uniform("uBisN"), params_.bisSamples);
    glUniform1i(program_.uniform("uIntermediate"), bridges_);
    glUniform1f(program_.uniform("uLocalProbability"), params_.smcLocalProbability);
    glUniform1f(program_.uniform("uLocalCos"), std::cos(glm::radians(params_.smcLocalDegrees)));
    glUniform1f(program_.uniform("uReinitRatio"), params_.smcReinitRatio);
    glUniform1i(program_.uniform("uReinitOnDrop"), params_.smcReinitOnDrop ? 1 : 0);
    glUniform1i(program_.uniform("uVisibility"), params_.visibility ? 1 : 0);
    glUniform1ui(program_.uniform("uSeed"), seed_);
    glUniform1i(program_.uniform("uBvhNodes"), int(bvhNodes_));
    glUniform1i(program_.uniform("uTopCount"), int(hier_.topCount()));
    hier_.top().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TOP);
    hier_.nodes().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
    hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    const GLbitfield barriers = GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT |
                                GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT |
                                GL_FRAMEBUFFER_BARRIER_BIT;
    glUniform1i(program_.uniform("uPass"), 0);
    glUniform1i(program_.uniform("uPasses"), 1);
    if (!smc) {
      // Bound all the same (the shader declares them).
      if (stateIn_.bytes() == 0) stateIn_.reserve(16), stateOut_.reserve(16);
      stateIn_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_STATE_IN);
      stateOut_.bindBase(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_STATE_OUT);
      glUniform1i(program_.uniform("uHasPrevious"), 0);
      glUniform1i(program_.uniform("uRowOffset"), 0);
      glUniform1i(program_.uniform("uRows"), tile.height);
      const int passes = passCount();
      glUniform1i(program_.uniform("uPasses"), passes);
      for (int pass = 0; pass < passes; ++pass) {
        glUniform1i(program_.uniform("uPass"), pass);
        glDispatchCompute(GLuint((tile.width + 7) / 8), GLuint((tile.height + 7) / 8), 1);
        glMemoryBarrier(barriers);
      }
      return;
    }
    // The full image's clip-from-world, for the next frame's reprojection.
    clipFromWorld_ = glm::inverse(tile.clipFromFullClip) * ctx.uniforms().clipFromWorld;
    frameClip_ = true;
    glBindTextureUnit(6, prevTexture_.id());
    glUniform1f(program_.uniform("uPrevEnvScale"), prevEnvScale_);
    glUniformMatrix4fv(program_.uniform("uPrevClipFromWorld"), 1, GL_FALSE,
                       &prevClipFromWorld_[0][0]);
    glUniform1i(program_.uniform("uHasPrevious"), hasPrevious_ ? 1 : 0);
    const int bandRows = allocateState(tile.fullWidth, tile.fullHeight);
    for (int r0 = 0; r0 < tile.height; r0 += bandRows) {
      const int rows = std::min(bandRows, tile.height - r0);
      bindBand(tile.y0 + r0, rows);
      glUniform1i(program_.uniform("uRowOffset"), r0);
      glUniform1i(program_.uniform("uRows"), rows);
      glDispatchCompute(GLuint((tile.width + 7) / 8), GLuint((rows + 7) / 8), 1);
    }
    glMemoryBarrier(barriers);
  }

  // Dispatches per tile: every pass shades at most IBL_PASS_SAMPLES samples (MIS, baselines) or
  // IBL_PASS_PROPOSALS proposals (BIS) a pixel.
  int passCount() const {
    auto ceilDiv = [](int a, int b) { return (a + b - 1) / b; };
    switch (params_.estimator) {
      case IblParameters::Estimator::Mis:
        return std::max(1, ceilDiv(params_.brdfSamples + params_.envSamples, IBL_PASS_SAMPLES));
      case IblParameters::Estimator::Environment:
        return std::max(1, ceilDiv(params_.envSamples, IBL_PASS_SAMPLES));
      case IblParameters::Estimator::Brdf:
        return std::max(1, ceilDiv(params_.brdfSamples, IBL_PASS_SAMPLES));
      case IblParameters::Estimator::Bis:
        // Each pass resamples at least one of the N.
        return std::clamp(ceilDiv(params_.bisProposals, IBL_PASS_PROPOSALS), 1, params_.bisSamples);
      case IblParameters::Estimator::Smc:
        return 1;
    }
    return 1;
  }

  // The SMC state: a row of IBL_STATE_STRIDE words per pixel, padded to 256 bytes, two buffers
  // (last frame's, read; this frame's, written). When the image's rows exceed one 128 MiB range
  // (1920 x 1080 at 8 samples does), the frame is shaded in bands of rows: each band writes its
  // own rows and reads the previous state of the rows about it (a pixel whose reprojection lands
  // further away starts afresh). Returns the band height.
  int allocateState(int W, int H) {
    const size_t stride = size_t(8 + 2 * params_.smcParticles);
    rowWords_ = (size_t(W) * stride + 63) / 64 * 64;
    const size_t bytes = rowWords_ * 4 * size_t(H);
    if (W != stateW_ || H != stateH_ || stateOut_.bytes() < bytes) {
      stateIn_ = gl::Buffer(bytes);
      stateOut_ = gl::Buffer(bytes);
      stateW_ = W, stateH_ = H;
      stateValid_ = hasPrevious_ = false;
      glUniform1i(program_.uniform("uHasPrevious"), 0);
    }
    maxRows_ = int(std::max<size_t>(gl::kMaxSsboRange / (rowWords_ * 4), 2));
    if (params_.smcBandRows > 0) maxRows_ = std::min(maxRows_, 2 * params_.smcBandRows);
    glUniform1i(program_.uniform("uStateRowWords"), int(rowWords_));
    return H <= maxRows_ ? std::max(H, 1) : std::max(maxRows_ / 2, 1);
  }

  // Binds the state for image rows [first, first + rows) (GL rows, bottom up).
  void bindBand(int first, int rows) {
    const int H = stateH_;
    const size_t rowBytes = rowWords_ * 4;
    int inFirst = 0, inRows = H, outFirst = 0, outRows = H;
    if (H > maxRows_) {
      outFirst = std::clamp(first, 0, H - 1);
      outRows = std::clamp(first + rows, outFirst + 1, H) - outFirst;
      const int margin = std::max((maxRows_ - outRows) / 2, 0);
      inFirst = std::max(outFirst - margin, 0);
      inRows = std::min(maxRows_, H - inFirst);
    }
    stateIn_.bindRange(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_STATE_IN, size_t(inFirst) * rowBytes,
                       size_t(inRows) * rowBytes);
    stateOut_.bindRange(GL_SHADER_STORAGE_BUFFER, IBL_SSBO_STATE_OUT, size_t(outFirst) * rowBytes,
                        size_t(outRows) * rowBytes);
    glUniform1i(program_.uniform("uStateRowIn"), inFirst);
    glUniform1i(program_.uniform("uStateRowsIn"), inRows);
    glUniform1i(program_.uniform("uStateRowOut"), outFirst);
    glUniform1i(program_.uniform("uStateRowsOut"), outRows);
  }

  IblParameters params_;
  uint32_t seed_ = 1;
  size_t layer_ = 0;
  uint64_t generation_ = ~0ull;
  CutHierarchies hier_;
  gl::ShaderProgram program_;
  gl::Buffer envTable_, bvh_, triangles_, stats_, stateIn_, stateOut_;
  gl::Texture prevTexture_;
  std::shared_ptr<const EnvironmentMap> tableMap_, lastMap_, prevTextureMap_, bridgesMap_,
      bridgesPrev_;
  int bridges_ = 3;  // SMC: bridges from the last frame's map to this one's (smcBridges)
  float prevEnvScale_ = 1;
  double tableMs_ = 0, bvhMs_ = 0;
  uint64_t tableBuilds_ = 0, bvhNodes_ = 0, bvhTriangles_ = 0;
  int bvhDepth_ = 0;
  int stateW_ = 0, stateH_ = 0, maxRows_ = 1;
  size_t rowWords_ = 0;
  bool stateValid_ = false, hasPrevious_ = false, frameClip_ = false, llvmpipe_ = false;
  glm::mat4 clipFromWorld_{1.0f}, prevClipFromWorld_{1.0f};
};

}  // namespace

const char* estimatorName(IblParameters::Estimator e) {
  switch (e) {
    case IblParameters::Estimator::Mis:
      return "mis";
    case IblParameters::Estimator::Bis:
      return "bis";
    case IblParameters::Estimator::Smc:
      return "smc";
    case IblParameters::Estimator::Environment:
      return "env";
    case IblParameters::Estimator::Brdf:
      return "brdf";
  }
  return "?";
}

std::unique_ptr<Method> createIblMethod(const Scene& scene, const MethodContext& ctx) {
  return createRasterMethod(scene, ctx, std::make_unique<IblExtension>(scene));
}

}  // namespace nestlight::gi
