// The `projection` method (nestlight/gi/projection/projection_method.h): Maletz, Wang and
// Bowers, "Importance-Driven Point Projection for GPU-based Final Gathering" (2011), sections 3.1
// (the point set), 3.2 (importance-driven splatting) and 4 (clusters, micro-buffers), on the
// raster frame, with section 3.3's image-space adaptive sampling and section 4's progressive
// rendering (interactive frames refine while the view rests).
#include "nestlight/gi/projection/projection_method.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <glm/gtc/packing.hpp>
#include <map>
#include <nanoflann.hpp>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/interface.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/material.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/projection/clusters.h"
#include "nestlight/gi/projection/hemi_octahedral.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace glsl {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
#include "gi/projection/projection_interface.glsl"
}  // namespace glsl

namespace {

using ProjectionPoint = glsl::ProjectionPoint;
static_assert(sizeof(ProjectionPoint) == 48, "ProjectionPoint must keep std430's layout");

// Each point's area from its neighbours' spacing (a Poisson process of density rho has
// E[pi d_k^2] = k / rho for the distance d_k to its k-th neighbour): S is the union of whole
// octree levels, each of which covers the surface, so no level's spacing alone says how much
// surface a point of S stands for; its neighbours in S do, whatever the scan's sampling.
constexpr size_t kAreaNeighbours = 8;

struct PositionCloud {
  const std::vector<glm::vec3>& p;
  size_t kdtree_get_point_count() const { return p.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return p[i][int(dim)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using PositionTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PositionCloud>,
                                        PositionCloud, 3, uint32_t>;

std::vector<float> areasFromSpacing(const std::vector<glm::vec3>& p, float fallback) {
  std::vector<float> area(p.size(), fallback);
  if (p.size() <= kAreaNeighbours) return area;
  const PositionCloud cloud{p};
  PositionTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      uint32_t idx[kAreaNeighbours + 1];
                      float d2[kAreaNeighbours + 1];
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        const size_t found = tree.knnSearch(&p[i].x, kAreaNeighbours + 1, idx, d2);
                        if (found == kAreaNeighbours + 1 && d2[kAreaNeighbours] > 0)
                          area[i] = float(M_PI) * d2[kAreaNeighbours] / float(kAreaNeighbours);
                      }
                    });
  return area;
}

class ProjectionExtension : public FrameExtension {
 public:
  explicit ProjectionExtension(const Scene& scene)
      : params_(projectionParameters(scene)), seed_(uint32_t(scene.gi.seed)) {}

  std::string name() const override { return "projection"; }
  std::vector<std::string> parameterKeys() const override {
    return parameterNames(projectionParameterSpecs());
  }

  const char* samplingName() const {
    return params_.sampling == ProjectionParameters::Sampling::Random  ? "random"
           : params_.sampling == ProjectionParameters::Sampling::Brute ? "brute"
                                                                       : "importance";
  }

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    const char* sampling = samplingName();
    return {{"points", std::to_string(params_.points)},
            {"clusters", std::to_string(params_.clusters)},
            {"random_per_cluster", std::to_string(params_.randomPerCluster)},
            {"samples_per_cluster", std::to_string(params_.samplesPerCluster)},
            {"micro_buffer", std::to_string(params_.microBuffer)},
            {"sampling", sampling},
            {"splat", params_.splat == 0 ? "adaptive" : std::to_string(params_.splat)},
            {"fill", std::to_string(params_.fillPasses)},
            {"adaptive", params_.adaptive ? "true" : "false"},
            {"grid", std::to_string(params_.grid)},
            {"lambda", std::to_string(params_.lambda)},
            {"epsilon", std::to_string(params_.epsilon)},
            {"epsilon_level_factor", std::to_string(params_.epsilonLevelFactor)},
            {"post_filter", params_.postFilter < 0 ? "auto" : std::to_string(params_.postFilter)},
            {"supersample", std::to_string(params_.supersample)},
            {"glossy_to_glossy", params_.glossyToGlossy ? "true" : "false"},
            {"bounce_receivers", std::to_string(params_.bounceReceivers)}};
  }

  std::string setUp(SceneFrame& f) override {
    const Scene& scene = f.scene();
    albedo_ = scene.gi.mode == RadianceMode::Albedo;
    bounces_ = std::max(scene.gi.maxBounces, 1);
    gathers_ = !albedo_ || bounces_ >= 2;
    // Empty texels that see the sky gather it occluded by the scan, on every lobe of the
    // receiver's BSDF: direct light then leaves it off every receiver.
    skyOwned_ = f.hasEnvironment() && gathers_;
    if (skyOwned_) f.setSkyInDirectLight(false);
    const int m = params_.microBuffer;
    const std::vector<double> omega = projection::hemiOctTexelSolidAngles(m);
    std::vector<float> omegaF(omega.begin(), omega.end());
    solid_ = gl::Buffer(omegaF.size() * sizeof(float), omegaF.data(), 0);
    const int samples = params_.clusters * (params_.randomPerCluster + params_.samplesPerCluster);
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"PROJECTION_MB", std::to_string(m)},
        {"PROJECTION_K", std::to_string(params_.clusters)},
        {"PROJECTION_SAMPLES", std::to_string(std::max(samples, 1))}};
    pointsProgram_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_points.comp"}});
    lightProgram_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_light.comp"}});
    gather_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_gather.comp"}}, defines);
    const std::vector<std::pair<std::string, std::string>> mb = {
        {"PROJECTION_MB", std::to_string(m)}};
    select_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_select.comp"}}, mb);
    upsample_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_upsample.comp"}}, mb);
    compose_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_compose.comp"}}, mb);
    if (albedo_ && bounces_ >= 3)
      bounceProgram_ =
          gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_bounce.comp"}});
    if (params_.postFilter != 0)
      filter_ =
          gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/projection/projection_filter.comp"}}, mb);
    stats_ = gl::Buffer(32);
    sampleMeshSurfels(f);
    // The paper estimates importance from a few points per cluster, which suits BRDFs up to Phong
    // exponent 50 (GGX roughness 0.44: n = 2 / alpha^2 - 2, alpha = roughness^2); sharper
    // lobes alias.
    std::vector<bool> seen(scene.materials.size(), false);
    for (const SceneMesh& m : scene.meshes) {
      if (m.material >= seen.size() || seen[m.material]) continue;
      seen[m.material] = true;
      const Material& mat = scene.materials[m.material];
      if (mat.type != MaterialType::Lambert && mat.roughness < 0.44f)
        warnings_.push_back("material \"" + mat.name + "\" has roughness " +
                            std::to_string(mat.roughness) +
                            ", glossier than the paper's Phong exponent 50 (roughness 0.44): its "
                            "reflections of the scan may alias");
    }
    if (!f.quiet())
      for (const std::string& w : warnings_)
        std::fprintf(stderr, "projection: warning: %s\n", w.c_str());
    addPasses(f);
    return "radiance_gi";
  }

  int supersample() const override { return params_.supersample; }

  void beforeFrame(SceneFrame& f) override {
    const uint32_t zeros[8] = {};
    stats_.upload(zeros, sizeof zeros);
    std::fill(std::begin(gatheredPerLevel_), std::end(gatheredPerLevel_), 0);
    const frame::FrameBlock& u = f.graph().uniforms();
    // Interactive frames refine one view over several frames while nothing it depends on
    // changes: the camera, the nodes drawn, the lights' cut and views, the environment.
    progressive_ = !f.still() && params_.progressiveMs > 0;
    ViewKey key;
    key.viewFromWorld = u.viewFromWorld;
    key.clipFromView = u.clipFromView;
    key.generations = glm::u64vec4(f.viewGeneration(), f.cutGeneration(), f.lightViewsGeneration(),
                                   f.environmentGeneration());
    if (!progressive_ || !progressStarted_ || !(key == viewKey_)) {
      viewKey_ = key;
      progressStarted_ = false;
      progressLevel_ = 0;
      levelListed_ = false;
    }
    budgetStarted_ = false;
  }

  void describe(const SceneFrame&, MethodFrame& f) const override {
    uint32_t s[8] = {};
    glGetNamedBufferSubData(stats_.id(), 0, sizeof s, s);
    f.attributes["nestlight:projection_points"] = std::to_string(pointCount_);
    f.attributes["nestlight:projection_mesh_surfels"] = std::to_string(surfels_.size());
    f.attributes["nestlight:projection_glossy_surfels"] = std::to_string(lobeSlots_);
    f.attributes["nestlight:projection_further_bounces"] = std::to_string(furtherBounces_);
    f.attributes["nestlight:projection_lit"] = litThisFrame_ ? "true" : "false";
    f.attributes["nestlight:projection_bounce_receivers"] = std::to_string(bounceList_.size());
    f.attributes["nestlight:projection_levels"] = std::to_string(levelsTaken_);
    f.attributes["nestlight:projection_stride"] = std::to_string(stride_);
    f.attributes["nestlight:projection_clusters"] = std::to_string(clusterCount_);
    f.attributes["nestlight:projection_points_ms"] = std::to_string(pointsMs_);
    f.attributes["nestlight:projection_cluster_ms"] = std::to_string(clusterMs_);
    f.attributes["nestlight:projection_receivers"] = std::to_string(s[0]);
    f.attributes["nestlight:projection_unweighted"] = std::to_string(s[1]);
    f.attributes["nestlight:projection_empty_texels"] = std::to_string(s[2]);
    f.attributes["nestlight:projection_splats"] = std::to_string(s[3]);
    f.attributes["nestlight:projection_filled_texels"] = std::to_string(s[4]);
    f.attributes["nestlight:projection_shaded_pixels"] = std::to_string(s[5]);
    f.attributes["nestlight:projection_gathered_share"] =
        std::to_string(s[5] ? double(s[0]) / double(s[5]) : 0.0);
    std::string perLevel;
    for (size_t l = 0; l < std::min<size_t>(steps_.size(), 8); ++l)
      perLevel += (l ? "," : "") + std::to_string(gatheredPerLevel_[l]);
    f.attributes["nestlight:projection_gathered_per_level"] = perLevel;
    if (progressive_) {
      const bool done = progressLevel_ >= gatheringLevels();
      f.attributes["nestlight:projection_converged"] = done ? "true" : "false";
      f.attributes["nestlight:projection_progress_level"] = std::to_string(progressLevel_);
    }
    const double texels = double(s[0]) * params_.microBuffer * params_.microBuffer;
    f.attributes["nestlight:projection_coverage"] =
        std::to_string(texels > 0 ? 1.0 - double(s[2]) / texels : 0.0);
    char line[256];
    std::snprintf(line, sizeof line,
                  "; projection: %llu points (levels 0-%d, every %d-th of the next), %u clusters, "
                  "%u of %u receiver pixels gathered (%.1f%% of their texels covered)",
                  (unsigned long long)pointCount_, levelsTaken_ - 1, stride_, clusterCount_, s[0],
                  s[5], texels > 0 ? 100.0 * (1.0 - double(s[2]) / texels) : 0.0);
    f.summary += line;
    if (clusterCount_ < uint32_t(params_.clusters) && pointCount_ > 0)
      f.summary += "; fewer points than clusters: " + std::to_string(clusterCount_) + " clusters";
    if (!gathers_) f.summary += "; albedo mode with max_bounces 1: direct light only";
    if (furtherBounces_)
      f.summary += "; " + std::to_string(furtherBounces_) + " further bounce(s) gathered at " +
                   std::to_string(bounceList_.size()) + " points of S";
    if (progressive_) {
      char p[160];
      if (progressLevel_ >= gatheringLevels())
        std::snprintf(p, sizeof p, "progressive: converged (the still's image)");
      else
        std::snprintf(p, sizeof p, "progressive: level %zu of %zu (step %d), %u of %u pixels",
                      progressLevel_ + 1, gatheringLevels(), steps_[progressLevel_],
                      levelListed_ ? levelOffset_ : 0u, levelListed_ ? levelCount_ : 0u);
      f.summary += std::string("; ") + p;
      f.attributes["nestlight:progress"] = p;  // the viewer's panel shows it
    }
    if (params_.levels > 0 && size_t(params_.levels) < steps_.size())
      f.summary += "; levels: the first " + std::to_string(params_.levels) + " of " +
                   std::to_string(steps_.size()) + " gather, the rest interpolate";
    if (params_.supersample > 1)
      f.summary += "; " + std::to_string(params_.supersample) + "x" +
                   std::to_string(params_.supersample) + " subpixels a pixel (stills)";
    if (!dumpFiles_.empty()) {
      std::string files;
      for (const std::string& d : dumpFiles_) files += (files.empty() ? "" : ",") + d;
      f.attributes["nestlight:projection_dumped"] = files;
      f.summary += "; " + std::to_string(dumpFiles_.size()) + " micro-buffer(s) written to " +
                   params_.dumpFolder;
    }
    for (const std::string& p : notReceivers_)
      f.summary += "; dump_pixels: pixel " + p + " shows no receiver (sky or background)";
    for (const std::string& w : warnings_) f.summary += "; warning: " + w;
    f.attributes["nestlight:projection_truncated"] = std::to_string(s[6]);
    if (s[6])
      f.summary += "; " + std::to_string(s[6]) +
                   " receivers' splats stopped at llvmpipe's loop limit (brute force over a large "
                   "S near a surface: their micro-buffers are incomplete)";
    if (s[1])
      f.summary +=
          "; " + std::to_string(s[1]) + " receivers saw no cluster's importance (uniform pdf)";
  }

 private:
  void addPasses(SceneFrame& f) {
    frame::FrameGraph& g = f.graph();
    g.addBuffer("projection_points");
    g.addPass(
        "projection_points", frame::Scope::Frame,
        [](frame::PassBuilder& b) { b.write("projection_points"); },
        [this, &f](const frame::PassContext&) { gatherPoints(f); });
    g.addBuffer("projection_clusters");
    g.addPass(
        "projection_cluster", frame::Scope::Frame,
        [](frame::PassBuilder& b) {
          b.read("projection_points");
          b.write("projection_clusters");
        },
        [this](const frame::PassContext&) { cluster(); });
    g.addBuffer("projection_radiance");
    g.addPass(
        "projection_light", frame::Scope::Frame,
        [](frame::PassBuilder& b) {
          b.read("shadow_maps");
          b.read("projection_clusters");
          b.write("projection_radiance");
        },
        [this, &f](const frame::PassContext& ctx) { light(f, ctx); });
    g.addTarget("radiance_gi", {GL_RGBA32F});
    // Per tile, level by level of the adaptive sampling (section 3.3): the grid, then every
    // halving of its step down to single pixels (without adaptive sampling, one level of single
    // pixels: every receiver). Each level selects the pixels it gathers, gathers them and (below
    // the grid) interpolates the rest, each its own pass, so their times are the levels' (the
    // paper's Fig. 11). A level reads its parents up to twice its step away: its margin.
    steps_.clear();
    for (int st = params_.adaptive ? params_.grid : 1; st >= 1; st /= 2) steps_.push_back(st);
    std::string previous;
    for (size_t level = 0; level < steps_.size(); ++level) {
      const std::string step = std::to_string(steps_[level]);
      const int margin = level == 0 ? 0 : 2 * steps_[level];
      const std::string list = "projection_list_" + step, gathered = "projection_gathered_" + step,
                        pixels = "projection_pixels_" + step;
      g.addBuffer(list);
      g.addBuffer(gathered);
      if (level > 0) g.addBuffer(pixels);
      g.addPass(
          "projection_select_" + step, frame::Scope::Tile,
          [=](frame::PassBuilder& b) {
            for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
              b.read(t);
            if (!previous.empty()) b.read(previous);
            b.write(list);
            b.margin(margin);
          },
          [this, &f, level](const frame::PassContext& ctx) { select(f, ctx, level); });
      g.addPass(
          "projection_gather_" + step, frame::Scope::Tile,
          [=](frame::PassBuilder& b) {
            for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
              b.read(t);
            b.read("projection_radiance");
            b.read(list);
            b.write(gathered);
          },
          [this, &f, level](const frame::PassContext& ctx) { gather(f, ctx, level); });
      if (level == 0) {
        previous = gathered;
        continue;
      }
      g.addPass(
          "projection_upsample_" + step, frame::Scope::Tile,
          [=](frame::PassBuilder& b) {
            for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
              b.read(t);
            b.read(gathered);
            b.write(pixels);
            b.margin(margin);
          },
          [this, &f, level](const frame::PassContext& ctx) { upsample(f, ctx, level); });
      previous = pixels;
    }
    if (params_.postFilter != 0) {
      g.addBuffer("projection_filtered");
      const int radius = params_.postFilter < 0 ? 3 : params_.postFilter / 2;
      g.addPass(
          "projection_filter", frame::Scope::Tile,
          [=](frame::PassBuilder& b) {
            for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
              b.read(t);
            b.read(previous);
            b.write("projection_filtered");
            b.margin(radius);
          },
          [this, &f](const frame::PassContext& ctx) { filter(f, ctx); });
      previous = "projection_filtered";
    }
    g.addPass(
        "projection_compose", frame::Scope::Tile,
        [=](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
            b.read(t);
          b.read(previous);
          b.write("radiance_gi");
        },
        [this, &f](const frame::PassContext& ctx) { compose(f, ctx); });
  }

  // The meshes' surfels join S (paper section 3.1: the scene's surfaces sampled by Poisson disks,
  // each point its area): they occlude, reflect the lights and emit. Their albedo is the
  // material's directional albedo (as pbgi's surfels), their radiance lit each frame.
  void sampleMeshSurfels(SceneFrame& f) {
    const Scene& scene = f.scene();
    const std::vector<TriangleMesh>& meshes = f.meshes();
    for (size_t i = 0; i < scene.meshes.size() && i < meshes.size(); ++i) {
      const SceneMesh& m = scene.meshes[i];
      SurfelOptions o;
      o.method = m.surfelMethod;
      o.count = m.surfelCount;
      o.material = m.material;
      o.baseColor = Rgb(1.0f);
      const Surfels sf = sampleSurfels(meshes[i], scene.localFromObject(m), o);
      const Material& mat = scene.materials.at(m.material);
      const Rgb rho =
          glm::clamp(directionalAlbedo(mat, glm::vec3(0, 0, 1), 4096), Rgb(0.0f), Rgb(1.0f));
      // Glossy surfels keep lobes (glossy_to_glossy): the diffuse lobe's colour apart.
      const bool lobes = params_.glossyToGlossy && mat.type != MaterialType::Lambert;
      const Rgb diffuse =
          mat.type == MaterialType::Lambert ? mat.baseColor : (1.0f - mat.metallic) * mat.baseColor;
      for (size_t k = 0; k < sf.positions.size(); ++k) {
        ProjectionPoint p;
        p.positionArea = glm::vec4(sf.positions[k], sf.area[k]);
        const glm::vec3 n = sf.normals[k];
        p.normalColour = glm::vec4(std::bit_cast<float>(frame::packNormal(n.x, n.y, n.z)),
                                   glm::vec3(sf.albedo[k]) * glm::vec3(rho));
        p.source = glm::uvec4(m.material + 1, 0, 0, 0);
        if (lobes) {
          const glm::vec3 d = glm::clamp(glm::vec3(sf.albedo[k]) * glm::vec3(diffuse), 0.0f, 1.0f);
          p.source.y = 1;  // its slot is given once S is sorted
          p.source.z = glm::packHalf2x16(glm::vec2(d.r, d.g));
          p.source.w = glm::packHalf2x16(glm::vec2(d.b, 0.0f));
        }
        surfels_.push_back(p);
      }
    }
  }

  // S from the lights' cut (when it changed): whole levels from the root while they fit the
  // budget, then every stride-th point of the next level; unsorted, read back for the clusters.
  void gatherPoints(SceneFrame& f) {
    if (f.cutGeneration() == generation_ && built_) return;
    const auto t0 = std::chrono::steady_clock::now();
    generation_ = f.cutGeneration();
    built_ = true;
    rebuilt_ = true;
    const std::vector<CutNode>& cut = f.lightsCut();
    // Levels by spacing, coarsest first (scans of different spacing interleave by it).
    std::map<float, uint64_t, std::greater<float>> perLevel;
    for (const CutNode& c : cut) perLevel[c.spacing] += c.numPoints;
    uint64_t taken = 0;
    float finest = INFINITY, partial = -1;
    stride_ = 1;
    levelsTaken_ = 0;
    for (const auto& [spacing, count] : perLevel) {
      if (taken + count <= uint64_t(params_.points)) {
        taken += count, finest = spacing, levelsTaken_++;
        continue;
      }
      const uint64_t room = uint64_t(params_.points) - taken;
      if (room > 0) {
        stride_ = int((count + room - 1) / room);
        partial = spacing;
      }
      break;
    }
    std::vector<size_t> nodes;
    std::vector<uint32_t> kept, offset;
    uint32_t total = 0;
    for (size_t i = 0; i < cut.size(); ++i) {
      const CutNode& c = cut[i];
      uint32_t k = 0;
      if (c.spacing >= finest)
        k = c.numPoints;
      else if (c.spacing == partial)
        k = (c.numPoints + uint32_t(stride_) - 1) / uint32_t(stride_);
      if (k == 0) continue;
      nodes.push_back(i), kept.push_back(k), offset.push_back(total);
      total += k;
    }
    pointCount_ = total;
    unsorted_.reserve(std::max<size_t>(total, 1) * sizeof(ProjectionPoint));
    unsorted_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_POINTS);
    pointsProgram_.use();
    int boundScan = -1;
    for (size_t j = 0; j < nodes.size(); ++j) {
      const CutNode& c = cut[nodes[j]];
      if (c.scan != boundScan) f.bindScanClip(boundScan = c.scan);
      glUniform1i(pointsProgram_.uniform("uClipTest"), c.clipTest);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, c.buffer, 0,
                        GLsizeiptr(size_t(c.numPoints) * frame::kGpuPointBytes));
      glUniform3f(pointsProgram_.uniform("uOrigin"), c.origin.x, c.origin.y, c.origin.z);
      glUniform1ui(pointsProgram_.uniform("uStride"),
                   c.spacing == partial ? uint32_t(stride_) : 1u);
      glUniform1ui(pointsProgram_.uniform("uOffset"), offset[j]);
      glUniform1ui(pointsProgram_.uniform("uKept"), kept[j]);
      glUniform1f(pointsProgram_.uniform("uColourScale"), c.colourScale);
      glUniform1i(pointsProgram_.uniform("uHdrColour"), c.hdrColour);
      glDispatchCompute((kept[j] + 63) / 64, 1, 1);
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    host_.resize(total);
    if (total)
      glGetNamedBufferSubData(unsorted_.id(), 0, GLsizeiptr(total * sizeof(ProjectionPoint)),
                              host_.data());
    // The points the clipping volumes removed (projection_points.comp marks them). The budget's
    // stride counted them: how many a partly clipped node keeps is known only after the test.
    std::erase_if(host_, [](const ProjectionPoint& p) { return p.positionArea.w < 0; });
    scanPoints_ = host_.size();
    host_.insert(host_.end(), surfels_.begin(), surfels_.end());
    pointCount_ = host_.size();
    fallbackArea_ = std::isfinite(finest) ? finest * finest : (partial > 0 ? partial * partial : 0);
    pointsMs_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  // The clusters of S and its points' areas; S uploaded cluster by cluster.
  void cluster() {
    if (!rebuilt_) return;
    rebuilt_ = false;
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<glm::vec3> position(host_.size());
    for (size_t i = 0; i < host_.size(); ++i) position[i] = glm::vec3(host_[i].positionArea);
    // The scan's points' areas from their neighbours among the scan's points; the surfels have
    // theirs.
    std::vector<float> area = areasFromSpacing(
        std::vector<glm::vec3>(position.begin(), position.begin() + std::ptrdiff_t(scanPoints_)),
        fallbackArea_);
    for (size_t i = scanPoints_; i < host_.size(); ++i) area.push_back(host_[i].positionArea.w);
    const projection::Clusters c = projection::buildClusters(position, uint32_t(params_.clusters));
    clusterCount_ = c.count;
    std::vector<ProjectionPoint> sorted(c.order.size());
    lobeSlots_ = 0;
    for (size_t j = 0; j < c.order.size(); ++j) {
      sorted[j] = host_[c.order[j]];
      sorted[j].positionArea.w = area[c.order[j]];
      if (sorted[j].source.y != 0) sorted[j].source.y = ++lobeSlots_;
    }
    // The shader takes K clusters: those the points could not fill are empty.
    std::vector<uint32_t> first(size_t(params_.clusters) + 1, uint32_t(sorted.size()));
    std::copy(c.first.begin(), c.first.end(), first.begin());
    points_.reserve(std::max<size_t>(sorted.size(), 1) * sizeof(ProjectionPoint));
    if (!sorted.empty()) points_.upload(sorted.data(), sorted.size() * sizeof(ProjectionPoint));
    clusters_.reserve(first.size() * 4);
    clusters_.upload(first.data(), first.size() * 4);
    // Each point's radiance, then the glossy surfels' lobes (projection_interface.glsl).
    radiance_.reserve(std::max<size_t>(sorted.size() + 2 * PROJECTION_LOBES * lobeSlots_, 1) * 16);
    sortedCount_ = uint32_t(sorted.size());
    chooseBounceReceivers(sorted, first);
    lit_ = false;  // a new S: its light too
    clusterMs_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  // The points of S that gather for the further bounces: bounce_receivers of them, spread over
  // the clusters (each cluster's points are neighbours: evenly through its list), and for every
  // point the receiver of its cluster it takes its gathered light from: the nearest whose normal
  // agrees within 45 degrees, else the nearest.
  void chooseBounceReceivers(const std::vector<ProjectionPoint>& sorted,
                             const std::vector<uint32_t>& first) {
    bounceList_.clear();
    receiverOf_.assign(sorted.size(), 0u);
    if (!albedo_ || bounces_ < 3 || sorted.empty()) return;
    const size_t K = first.size() - 1;
    const size_t perCluster = std::max<size_t>(1, (size_t(params_.bounceReceivers) + K - 1) / K);
    for (size_t k = 0; k < K; ++k) {
      const uint32_t lo = first[k], hi = first[k + 1];
      if (hi <= lo) continue;
      const size_t m = std::min<size_t>(perCluster, hi - lo);
      const size_t base = bounceList_.size();
      for (size_t j = 0; j < m; ++j) bounceList_.push_back(lo + uint32_t(j * (hi - lo) / m));
      for (uint32_t i = lo; i < hi; ++i) {
        const glm::vec3 p(sorted[i].positionArea);
        const glm::vec3 n = frame::unpackNormal(std::bit_cast<uint32_t>(sorted[i].normalColour.x));
        float best = INFINITY, bestAgreeing = INFINITY;
        uint32_t pick = uint32_t(base), pickAgreeing = UINT32_MAX;
        for (size_t j = base; j < bounceList_.size(); ++j) {
          const ProjectionPoint& r = sorted[bounceList_[j]];
          const glm::vec3 d = glm::vec3(r.positionArea) - p;
          const float d2 = glm::dot(d, d);
          if (d2 < best) best = d2, pick = uint32_t(j);
          const glm::vec3 rn = frame::unpackNormal(std::bit_cast<uint32_t>(r.normalColour.x));
          if (glm::dot(rn, n) > 0.7071f && d2 < bestAgreeing)
            bestAgreeing = d2, pickAgreeing = uint32_t(j);
        }
        receiverOf_[i] = pickAgreeing != UINT32_MAX ? pickAgreeing : pick;
      }
    }
    std::vector<uint32_t> list(4 + bounceList_.size(), 0u);
    list[0] = uint32_t(bounceList_.size());
    std::copy(bounceList_.begin(), bounceList_.end(), list.begin() + 4);
    bounceListBuffer_.reserve(list.size() * 4);
    bounceListBuffer_.upload(list.data(), list.size() * 4);
    receiverOfBuffer_.reserve(receiverOf_.size() * 4);
    receiverOfBuffer_.upload(receiverOf_.data(), receiverOf_.size() * 4);
  }

  // Each point's radiance: its colour (radiance cache), or its direct light (albedo), and the
  // further bounces; kept while S, the lights' views and the environment stay (the paper: the
  // points' bounces take seconds, and the view may then change at will).
  void light(SceneFrame& f, const frame::PassContext& ctx) {
    litThisFrame_ = false;
    if (sortedCount_ == 0) return;
    const glm::u64vec3 key(f.cutGeneration(), f.lightViewsGeneration(), f.environmentGeneration());
    if (lit_ && key == litKey_) return;
    lit_ = true, litKey_ = key, litThisFrame_ = true;
    const gl::Texture& maps = ctx.target("shadow_maps");
    maps.setFilter(GL_LINEAR, GL_LINEAR);
    maps.setDepthCompare(true);
    glBindTextureUnit(4, maps.id());
    f.bindSceneBuffers();
    lightProgram_.use();
    f.bindEnvironment(lightProgram_);
    points_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_POINTS);
    radiance_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_RADIANCE);
    glUniform1ui(lightProgram_.uniform("uCount"), sortedCount_);
    glUniform1i(lightProgram_.uniform("uAlbedo"), albedo_ ? 1 : 0);
    glUniform1f(lightProgram_.uniform("uSplatScale"), f.frameParameters().splatScale);
    glDispatchCompute((sortedCount_ + 63) / 64, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    furtherBounces_ = 0;
    if (bounceList_.empty()) return;
    // The further bounces (gi.max_bounces beyond the gathered one): the points' radiance is their
    // direct light plus what their receivers gather from the points' radiance of the bounce before.
    const size_t bytes = size_t(sortedCount_) * 16;
    direct_.reserve(bytes);
    glCopyNamedBufferSubData(radiance_.id(), direct_.id(), 0, 0, GLsizeiptr(bytes));
    bounceE_.reserve(bounceList_.size() * 32);
    const uint32_t count = uint32_t(bounceList_.size());
    for (int b = 0; b + 2 < bounces_; ++b) {
      bindGather(f);
      points_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_POINTS);
      radiance_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_RADIANCE);
      bounceListBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_LIST);
      bounceE_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_PIXELS);
      glUniform1i(gather_.uniform("uPointReceivers"), 1);
      const uint32_t row = std::min<uint32_t>(count, 65535u);
      glUniform1ui(gather_.uniform("uRowItems"), row);
      glDispatchCompute(row, (count + row - 1) / row, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      bounceProgram_.use();
      direct_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_FILTERED);
      receiverOfBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_LIST);
      glUniform1ui(bounceProgram_.uniform("uCount"), sortedCount_);
      glDispatchCompute((sortedCount_ + 63) / 64, 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      furtherBounces_++;
    }
  }

  // The gather's program and the buffers and uniforms every use of it shares.
  void bindGather(SceneFrame& f) {
    if (clusters_.bytes() == 0) {
      std::vector<uint32_t> none(size_t(params_.clusters) + 1, 0u);
      clusters_.reserve(none.size() * 4);
      clusters_.upload(none.data(), none.size() * 4);
    }
    if (points_.bytes() == 0) points_.reserve(sizeof(ProjectionPoint));
    if (radiance_.bytes() == 0) radiance_.reserve(16);
    points_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_POINTS);
    clusters_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_CLUSTERS);
    solid_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_SOLID);
    radiance_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_RADIANCE);
    stats_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_STATS);
    gather_.use();
    f.bindEnvironment(gather_);
    glUniform1i(gather_.uniform("uRandomPerCluster"), params_.randomPerCluster);
    glUniform1i(gather_.uniform("uSamplesPerCluster"), params_.samplesPerCluster);
    glUniform1i(gather_.uniform("uSampling"), int(params_.sampling));
    glUniform1i(gather_.uniform("uSplat"), params_.splat);
    const glm::vec3 diag = f.boundsHi() - f.boundsLo();
    glUniform1f(gather_.uniform("uMaxDistance"), std::max(glm::length(diag), 1e-6f));
    glUniform1i(gather_.uniform("uSkyOwned"), skyOwned_ ? 1 : 0);
    glUniform1ui(gather_.uniform("uSeed"), seed_);
    glUniform1i(gather_.uniform("uFillPasses"), params_.fillPasses);
    glUniform1i(gather_.uniform("uPointReceivers"), 0);
    glUniform1i(gather_.uniform("uDump"), 0);
    glUniform1i(gather_.uniform("uHasLobes"), lobeSlots_ > 0 ? 1 : 0);
    glUniform1ui(gather_.uniform("uListOffset"), 0u);
    glUniform1ui(gather_.uniform("uListEnd"), UINT32_MAX);
  }

  // What every per-tile pass binds: the G-buffer and the direct light, the per-pixel light
  // (pixels_: irradiance and glossy rest, each pixel's state in .w) and the list of pixels to
  // gather.
  void bindTile(SceneFrame& f, const frame::PassContext& ctx) {
    f.bindSceneBuffers();
    ctx.bindTexture("depth", 0);
    ctx.bindTexture("base_colour", 1);
    ctx.bindTexture("normal", 2);
    ctx.bindTexture("material", 3);
    ctx.bindTexture("radiance", 4);
    work_->bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_PIXELS);
    list_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_LIST);
    stats_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_STATS);
  }

  static void dispatchOverTile(const frame::Tile& tile) {
    glDispatchCompute(GLuint((tile.width + 7) / 8), GLuint((tile.height + 7) / 8), 1);
  }

  // The levels that gather: all, or the first `levels`.
  size_t gatheringLevels() const {
    return params_.levels > 0 ? std::min(steps_.size(), size_t(params_.levels)) : steps_.size();
  }

  // One level's choice of the pixels it gathers (the first level: its whole grid). A progressive
  // frame keeps its pixels in committed_, which holds exactly what a still's levels would have
  // made so far: it selects a level once, when it reaches it.
  void select(SceneFrame& f, const frame::PassContext& ctx, size_t level) {
    const frame::Tile& tile = ctx.tile();
    const size_t pixels = size_t(tile.width) * size_t(tile.height);
    listCount_ = 0;
    if (level == 0 && progressive_ &&
        (tile.width != tile.fullWidth || tile.height != tile.fullHeight))
      progressive_ = false;  // tiled frames start afresh per tile: no state to carry
    work_ = progressive_ ? &committed_ : &pixels_;
    if (progressive_ && level == 0 &&
        (tile.fullWidth != progressWidth_ || tile.fullHeight != progressHeight_)) {
      progressWidth_ = tile.fullWidth, progressHeight_ = tile.fullHeight;
      progressLevel_ = 0, levelListed_ = false;  // a new size: a new view
    }
    if (progressive_ && (level != progressLevel_ || levelListed_)) return;
    if (level == 0) {
      work_->reserve(pixels * 32);
      const float zero[4] = {0, 0, 0, 0};
      glClearNamedBufferData(work_->id(), GL_RGBA32F, GL_RGBA, GL_FLOAT, zero);
      list_.reserve((4 + pixels) * 4);
      progressStarted_ = true;
    }
    if (progressive_ && level >= gatheringLevels()) return;
    runSelect(f, ctx, level, level >= gatheringLevels());
    if (level >= gatheringLevels()) return;
    // The gather's dispatch is sized by the count (a workgroup per listed pixel).
    glGetNamedBufferSubData(list_.id(), 0, 4, &listCount_);
    if (progressive_) levelListed_ = true, levelCount_ = listCount_, levelOffset_ = 0;
  }

  void runSelect(SceneFrame& f, const frame::PassContext& ctx, size_t level, bool interpolateOnly) {
    const uint32_t zeros[4] = {0, 0, 0, 0};
    if (!interpolateOnly) list_.upload(zeros, sizeof zeros);
    bindTile(f, ctx);
    const glm::vec3 diag = f.boundsHi() - f.boundsLo();
    select_.use();
    glUniform1i(select_.uniform("uStep"), steps_[level]);
    glUniform1i(select_.uniform("uFirstLevel"), level == 0 ? 1 : 0);
    glUniform1i(select_.uniform("uInterpolateOnly"), interpolateOnly ? 1 : 0);
    glUniform1f(select_.uniform("uEpsilon"),
                params_.epsilon * std::pow(params_.epsilonLevelFactor, float(level) - 1.0f));
    glUniform1f(select_.uniform("uLambda"), params_.lambda);
    glUniform1f(select_.uniform("uHalfDiagonal"), std::max(0.5f * glm::length(diag), 1e-6f));
    glUniform1i(select_.uniform("uGathers"), gathers_ ? 1 : 0);
    dispatchOverTile(ctx.tile());
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
  }

  // The listed pixels' micro-buffers: a workgroup each. A progressive frame gathers the first
  // level whole, then its level's pixels in chunks for at most progressive_ms (at least one
  // chunk a frame, so the view always refines).
  void gather(SceneFrame& f, const frame::PassContext& ctx, size_t level) {
    if (!progressive_) {
      if (listCount_ == 0) return;
      gatheredPerLevel_[std::min<size_t>(level, 7)] += listCount_;
      runGather(f, ctx, 0, listCount_);
      return;
    }
    if (level != progressLevel_ || !levelListed_) return;
    using Clock = std::chrono::steady_clock;
    if (level > 0 && !budgetStarted_) budgetStarted_ = true, budgetStart_ = Clock::now();
    bool first = true;
    while (levelOffset_ < levelCount_) {
      uint32_t n = levelCount_ - levelOffset_;
      if (level > 0) {
        const double left =
            params_.progressiveMs -
            std::chrono::duration<double, std::milli>(Clock::now() - budgetStart_).count();
        if (left <= 0 && !first) break;
        const double want = msPerPixel_ > 0 ? std::max(left, 0.0) / msPerPixel_ : 16.0;
        n = std::min<uint32_t>(n, uint32_t(std::clamp(want, 16.0, 1e7)));
      }
      const auto t0 = Clock::now();
      runGather(f, ctx, levelOffset_, n);
      glFinish();
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      msPerPixel_ = msPerPixel_ > 0 ? 0.5 * (msPerPixel_ + ms / n) : ms / n;
      levelOffset_ += n;
      gatheredPerLevel_[std::min<size_t>(level, 7)] += n;
      first = false;
    }
    if (levelOffset_ < levelCount_) return;
    // The level is complete: its interpolation, as a still's, then on to the next.
    if (level > 0) runUpsample(f, ctx, level, false);
    levelListed_ = false;
    progressLevel_++;
  }

  void runGather(SceneFrame& f, const frame::PassContext& ctx, uint32_t offset, uint32_t count) {
    bindTile(f, ctx);
    bindGather(f);
    const uint32_t row = std::min<uint32_t>(count, 65535u);
    glUniform1ui(gather_.uniform("uRowItems"), row);
    glUniform1ui(gather_.uniform("uListOffset"), offset);
    glUniform1ui(gather_.uniform("uListEnd"), offset + count);
    glDispatchCompute(row, (count + row - 1) / row, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

  // The level's pixels not gathered, interpolated from their cell's corners (levels beyond
  // `levels`: those pixels are listed by an interpolating select first).
  void upsample(SceneFrame& f, const frame::PassContext& ctx, size_t level) {
    if (progressive_) return;  // committed_'s levels upsample as they complete
    runUpsample(f, ctx, level, level >= gatheringLevels());
  }

  void runUpsample(SceneFrame& f, const frame::PassContext& ctx, size_t level, bool fallback) {
    bindTile(f, ctx);
    upsample_.use();
    glUniform1i(upsample_.uniform("uStep"), steps_[level]);
    glUniform1i(upsample_.uniform("uGathers"), gathers_ ? 1 : 0);
    glUniform1i(upsample_.uniform("uFallback"), fallback ? 1 : 0);
    dispatchOverTile(ctx.tile());
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

  // A progressive frame's image: committed_ copied, the level in progress interpolated (its
  // pixels not gathered yet too) and the levels after it interpolated from it.
  void buildProgressiveView(SceneFrame& f, const frame::PassContext& ctx) {
    if (!progressive_) return;
    const frame::Tile& tile = ctx.tile();
    const size_t bytes = size_t(tile.width) * size_t(tile.height) * 32;
    pixels_.reserve(bytes);
    glCopyNamedBufferSubData(committed_.id(), pixels_.id(), 0, 0, GLsizeiptr(bytes));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    work_ = &pixels_;
    for (size_t level = std::max<size_t>(progressLevel_, 1); level < steps_.size(); ++level) {
      if (!(level == progressLevel_ && levelListed_)) runSelect(f, ctx, level, true);
      runUpsample(f, ctx, level, true);
    }
  }

  // The joint bilateral post filter, into filtered_ (which then stands for pixels_).
  void filter(SceneFrame& f, const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    buildProgressiveView(f, ctx);
    work_ = &pixels_;
    bindTile(f, ctx);
    filtered_.reserve(size_t(tile.width) * size_t(tile.height) * 32);
    filtered_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_FILTERED);
    filter_.use();
    const int r = params_.postFilter < 0 ? 3 : params_.postFilter / 2;
    glUniform1i(filter_.uniform("uRadius"), r);
    glUniform1i(filter_.uniform("uGlossyRadius"), params_.postFilter < 0 ? 1 : r);
    glUniform1i(filter_.uniform("uGathers"), gathers_ ? 1 : 0);
    dispatchOverTile(tile);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }

  // The tile's output: direct light plus each pixel's albedo times its light.
  void compose(SceneFrame& f, const frame::PassContext& ctx) {
    if (params_.postFilter == 0) buildProgressiveView(f, ctx);
    work_ = &pixels_;
    bindTile(f, ctx);
    if (params_.postFilter != 0)
      filtered_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_PIXELS);
    glBindImageTexture(0, ctx.target("radiance_gi").id(), 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    compose_.use();
    glUniform1i(compose_.uniform("uGathers"), gathers_ ? 1 : 0);
    dispatchOverTile(ctx.tile());
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT |
                    GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT |
                    GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    // Stills only: a progressive frame's list of the level in progress must survive the dump's.
    if (!params_.dumpPixels.empty() && gathers_ && !progressive_) dumpMicroBuffers(f, ctx);
  }

  // dump_pixels: the first frame's micro-buffers of the listed pixels this tile holds, gathered
  // again (the same samples: they are drawn per image pixel) with the texels written out, one EXR
  // each: texel (i, j) of the hemi-octahedral map (eq. 2) at pixel (i, j), its light in RGB; the
  // header says which texels a sample covers (the rest are holes).
  void dumpMicroBuffers(SceneFrame& f, const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    if (dumped_.size() != params_.dumpPixels.size()) dumped_.assign(params_.dumpPixels.size(), 0);
    std::vector<uint32_t> words(4, 0u);
    std::vector<size_t> which;
    for (size_t i = 0; i < params_.dumpPixels.size(); ++i) {
      const int x = params_.dumpPixels[i][0], glY = tile.fullHeight - 1 - params_.dumpPixels[i][1];
      const int lx = x - tile.x0, ly = glY - tile.y0;
      if (dumped_[i] || lx < 0 || ly < 0 || lx >= tile.width || ly >= tile.height) continue;
      words.push_back(uint32_t(lx) | (uint32_t(ly) << 16));
      which.push_back(i);
    }
    if (which.empty()) return;
    words[0] = uint32_t(which.size());
    list_.reserve(words.size() * 4);
    list_.upload(words.data(), words.size() * 4);
    // M x M texels and a word saying whether the receiver was truncated, per pixel.
    const size_t texels = size_t(params_.microBuffer) * size_t(params_.microBuffer) + 1;
    dump_.reserve(which.size() * texels * 16);
    bindTile(f, ctx);
    bindGather(f);
    dump_.bindBase(GL_SHADER_STORAGE_BUFFER, PROJECTION_SSBO_FILTERED);
    glUniform1i(gather_.uniform("uDump"), 1);
    glUniform1ui(gather_.uniform("uRowItems"), uint32_t(which.size()));
    glDispatchCompute(GLuint(which.size()), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    glUniform1i(gather_.uniform("uDump"), 0);
    std::vector<float> texel(which.size() * texels * 4);
    glGetNamedBufferSubData(dump_.id(), 0, GLsizeiptr(texel.size() * sizeof(float)), texel.data());
    std::filesystem::create_directories(params_.dumpFolder);
    const int M = params_.microBuffer;
    for (size_t j = 0; j < which.size(); ++j) {
      const auto& px = params_.dumpPixels[which[j]];
      dumped_[which[j]] = 1;
      if (texel[j * texels * 4 + 3] < 0) {  // no receiver there
        notReceivers_.push_back(std::to_string(px[0]) + " " + std::to_string(px[1]));
        continue;
      }
      HdrImage img(M, M);
      std::string covered;
      size_t holes = 0;
      const bool truncated = texel[(j * texels + texels - 1) * 4] > 0.5f;
      for (int t = 0; t < M * M; ++t) {
        const float* v = &texel[(j * texels + size_t(t)) * 4];
        img.set(t % M, t / M, Rgb(v[0], v[1], v[2]));
        covered += v[3] > 0.5f ? '1' : '0';
        holes += v[3] <= 0.5f;
      }
      const std::string path =
          (std::filesystem::path(params_.dumpFolder) / microBufferFileName(px[0], px[1])).string();
      writeExr(path, img,
               {{"nestlight:pixel", std::to_string(px[0]) + " " + std::to_string(px[1])},
                {"nestlight:micro_buffer", std::to_string(M)},
                {"nestlight:covered", covered},
                {"nestlight:holes", std::to_string(holes)},
                {"nestlight:truncated", truncated ? "true" : "false"},
                {"nestlight:sampling", samplingName()}});
      dumpFiles_.push_back(path);
    }
  }

  ProjectionParameters params_;
  uint32_t seed_ = 1;
  bool albedo_ = false, gathers_ = true, skyOwned_ = false;
  int bounces_ = 1;
  gl::ShaderProgram pointsProgram_, lightProgram_, gather_, select_, upsample_, filter_, compose_,
      bounceProgram_;
  gl::Buffer direct_, bounceE_, bounceListBuffer_, receiverOfBuffer_;
  std::vector<uint32_t> bounceList_, receiverOf_;
  int furtherBounces_ = 0;
  bool lit_ = false;  // S's radiance is up to date for litKey_ (lights' cut, views, environment)
  bool litThisFrame_ = false;
  glm::u64vec3 litKey_{0};
  gl::Buffer unsorted_, points_, clusters_, radiance_, solid_, stats_, pixels_, list_, filtered_;
  // Progressive frames: the pixels as a still's levels leave them so far (committed_), the
  // level in progress, its list's size and how far its gather got; pixels_ then holds the frame.
  struct ViewKey {
    glm::mat4 viewFromWorld{0.0f}, clipFromView{0.0f};
    glm::u64vec4 generations{0};
    bool operator==(const ViewKey& o) const {
      return viewFromWorld == o.viewFromWorld && clipFromView == o.clipFromView &&
             generations == o.generations;
    }
  };
  gl::Buffer committed_;
  gl::Buffer* work_ = &pixels_;  // what the per-tile passes bind as the pixels
  bool progressive_ = false, progressStarted_ = false, levelListed_ = false;
  ViewKey viewKey_;
  size_t progressLevel_ = 0;
  uint32_t levelCount_ = 0, levelOffset_ = 0;
  int progressWidth_ = 0, progressHeight_ = 0;
  double msPerPixel_ = 0;
  bool budgetStarted_ = false;
  std::chrono::steady_clock::time_point budgetStart_;
  uint64_t gatheredPerLevel_[8] = {};
  std::vector<int> steps_;  // the adaptive sampling's levels, coarsest first
  uint32_t listCount_ = 0;  // pixels the current level's gather takes
  gl::Buffer dump_;
  std::vector<char> dumped_;
  std::vector<std::string> dumpFiles_, notReceivers_;
  std::vector<ProjectionPoint> host_, surfels_;
  std::vector<std::string> warnings_;
  size_t scanPoints_ = 0;
  float fallbackArea_ = 0;
  uint64_t generation_ = ~0ull;
  bool built_ = false, rebuilt_ = false;
  uint64_t pointCount_ = 0;
  uint32_t sortedCount_ = 0, clusterCount_ = 0, lobeSlots_ = 0;
  int levelsTaken_ = 0, stride_ = 1;
  double pointsMs_ = 0, clusterMs_ = 0;
};

}  // namespace

std::unique_ptr<Method> createProjectionMethod(const Scene& scene, const MethodContext& ctx) {
  return createRasterMethod(scene, ctx, std::make_unique<ProjectionExtension>(scene));
}

}  // namespace nestlight::gi
