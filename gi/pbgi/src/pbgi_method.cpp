// The `pbgi` method (nestlight/gi/pbgi/pbgi_method.h): Sabbadin, Palma, Banterle, Boubekeur and
// Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 5: the
// classic traversal (section 5.2) with micro-buffers and BRDF convolution (section 5.3), over the
// resident cut's per-node hierarchies joined by a top tree.
#include "nestlight/gi/pbgi/pbgi_method.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "nestlight/frame/frame_graph.h"
#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/pbgi/micro_buffer.h"
#include "nestlight/gi/shared/bsh.h"
#include "nestlight/gi/shared/bsh_layer.h"
#include "nestlight/gi/shared/cut_hierarchies.h"
#include "nestlight/gi/shared/mesh_trees.h"
#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight::gi {

namespace {

static_assert(sizeof(PbgiNode) == 32, "PbgiNode must keep std430's layout");

class PbgiExtension : public FrameExtension {
 public:
  explicit PbgiExtension(const Scene& scene) : params_(pbgiParameters(scene)) {}

  std::string name() const override { return "pbgi"; }
  std::vector<std::string> parameterKeys() const override {
    return parameterNames(pbgiParameterSpecs());
  }

  std::vector<std::pair<std::string, std::string>> parameters() const override {
    return {{"variant", variantName()},
            {"pair_capacity", std::to_string(params_.pairCapacity)},
            {"micro_buffer", std::to_string(params_.microBuffer)},
            {"conservative", params_.conservative ? "true" : "false"},
            {"empty", emptyName()},
            {"prune", params_.prune ? "true" : "false"},
            {"meshes", params_.meshes ? "true" : "false"},
            {"bounce_points", std::to_string(params_.bouncePoints)},
            {"steps_per_dispatch", std::to_string(budget_)}};
  }

  const char* variantName() const {
    switch (params_.variant) {
      case PbgiParameters::Variant::Classic:
        return "classic";
      case PbgiParameters::Variant::Mip:
        return "mip";
      case PbgiParameters::Variant::X:
        return "x";
    }
    return "?";
  }

  const char* emptyName() const {
    switch (params_.empty) {
      case PbgiParameters::Empty::Auto:
        return "auto";
      case PbgiParameters::Empty::Average:
        return "average";
      case PbgiParameters::Empty::Environment:
        return "environment";
      case PbgiParameters::Empty::Black:
        return "black";
    }
    return "?";
  }

  std::string setUp(SceneFrame& f) override {
    const Scene& scene = f.scene();
    if (params_.empty == PbgiParameters::Empty::Auto)
      params_.empty =
          f.hasEnvironment() ? PbgiParameters::Empty::Environment : PbgiParameters::Empty::Average;
    albedo_ = scene.gi.mode == RadianceMode::Albedo;
    bounces_ = std::max(scene.gi.maxBounces, 1);
    // Empty m-pixels that see the sky gather it occluded by the scan, on every lobe of the
    // receiver's BRDF: direct light then leaves it off the receivers (every pixel direct light
    // shades is a receiver here).
    skyOwned_ = params_.empty == PbgiParameters::Empty::Environment && f.hasEnvironment() &&
                (!albedo_ || bounces_ >= 2);
    if (skyOwned_) f.setSkyInDirectLight(false);
    BshOptions options;
    options.prune = params_.prune;
    layer_ = f.addNodeLayer([options, this](const Metadata& meta,
                                            std::shared_ptr<const ScanColours> colours,
                                            std::shared_ptr<const ClipSet> clip) {
      auto layer = std::make_shared<BshLayer>(meta, options, std::move(colours), std::move(clip));
      layers_.push_back(layer);
      return layer;
    });
    if (params_.meshes) meshTrees_ = buildMeshTrees(scene, f.meshes());
    // The coarsest meshes lift only the receivers in their own bounds (pbgi_common.glsl): a mesh
    // of few surfels has discs as wide as itself.
    std::vector<size_t> byDisc(meshTrees_.size());
    for (size_t k = 0; k < byDisc.size(); ++k) byDisc[k] = k;
    std::stable_sort(byDisc.begin(), byDisc.end(), [&](size_t a, size_t b) {
      return meshTrees_[a].discRadius > meshTrees_[b].discRadius;
    });
    liftBoxes_.clear();
    for (size_t k : byDisc) {
      const MeshTree& t = meshTrees_[k];
      if (liftBoxes_.size() < 2 * PBGI_LIFT_BOXES && t.lo.x <= t.hi.x) {
        liftBoxes_.push_back(glm::vec4(t.lo, t.discRadius));
        liftBoxes_.push_back(glm::vec4(t.hi, float(t.material)));
        continue;
      }
      meshLiftMax_ = std::max(meshLiftMax_, t.discRadius);
      if (t.material < meshLift_.size())
        meshLift_[t.material] = std::max(meshLift_[t.material], t.discRadius);
    }
    for (const auto& t : meshTrees_) meshSurfels_ += t.surfels;
    hier_.setMeshTrees(meshTrees_);
    // The gather reads lit copies of the hierarchies when anything needs lighting: every node in
    // the albedo mode, the meshes' surfels in both.
    lit_ = albedo_ || !meshTrees_.empty();
    const pbgi::MicroBufferTable table = pbgi::microBufferTable(params_.microBuffer);
    micro_ = gl::Buffer(table.texels.size() * sizeof(glm::vec4), table.texels.data(), 0);
    const std::vector<std::pair<std::string, std::string>> defines = {
        {"PBGI_MB", std::to_string(params_.microBuffer)}};
    receiversProgram_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_receivers.comp"}}, defines);
    classic_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_classic.comp"}}, defines);
    if (lit_) {
      lightProgram_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_light.comp"}}, defines);
      lightUpProgram_ =
          gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_light_up.comp"}}, defines);
      if (albedo_ && bounces_ >= 3) {
        selectProgram_ =
            gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_bounce_select.comp"}}, defines);
        downProgram_ =
            gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_bounce_down.comp"}}, defines);
      }
    }
    if (params_.variant != PbgiParameters::Variant::Classic) {
      pyramidProgram_ =
          gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_pyramid.comp"}}, defines);
      pairsProgram_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/pbgi/pbgi_pairs.comp"}}, defines);
    }
    // llvmpipe ends a shader invocation's loops after 65,535 iterations in all (see
    // pbgi_classic.comp): its dispatches take fewer steps, leaving room for the micro-buffer's
    // clearing and convolution loops.
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    const int m2 = params_.microBuffer * params_.microBuffer;
    budget_ = renderer && std::strstr(renderer, "llvmpipe") ? 65535 - 2 * m2 - 256 : (1 << 20);
    if (params_.stepsPerDispatch > 0) budget_ = std::min(budget_, params_.stepsPerDispatch);
    addPasses(f);
    return "radiance_gi";
  }

  void beforeFrame(SceneFrame& f) override {
    if (f.cutGeneration() != generation_ || topCount_ == 0) rebuild(f);
    receiverCount_ = dispatches_ = stackOverflows_ = 0;
    pairGenerations_ = pairOverflows_ = pairBytes_ = listEntries_ = 0;
  }

  void describe(const SceneFrame&, MethodFrame& f) const override {
    f.attributes["nestlight:pbgi_variant"] = variantName();
    f.attributes["nestlight:pbgi_pair_generations"] = std::to_string(pairGenerations_);
    f.attributes["nestlight:pbgi_pair_overflows"] = std::to_string(pairOverflows_);
    f.attributes["nestlight:pbgi_pair_bytes"] = std::to_string(pairBytes_);
    f.attributes["nestlight:pbgi_list_entries"] = std::to_string(listEntries_);
    f.attributes["nestlight:pbgi_micro_buffer"] = std::to_string(params_.microBuffer);
    f.attributes["nestlight:pbgi_empty"] = emptyName();
    f.attributes["nestlight:pbgi_cut_nodes"] = std::to_string(cutNodes_);
    f.attributes["nestlight:pbgi_nodes_left_out"] = std::to_string(leftOut_);
    f.attributes["nestlight:pbgi_bsh_nodes"] = std::to_string(bshNodes_);
    f.attributes["nestlight:pbgi_top_nodes"] = std::to_string(topCount_);
    f.attributes["nestlight:pbgi_top_ms"] = std::to_string(topMs_);
    f.attributes["nestlight:pbgi_mesh_trees"] = std::to_string(meshTrees_.size());
    f.attributes["nestlight:pbgi_bounces_gathered"] =
        std::to_string(albedo_ && bounces_ >= 2 ? 1 + gatheredBounces_ : 0);
    f.attributes["nestlight:pbgi_bounce_receivers"] = std::to_string(bounceReceivers_);
    f.attributes["nestlight:pbgi_mesh_surfels"] = std::to_string(meshSurfels_);
    BshLayer::Totals built;
    for (const auto& l : layers_) {
      const auto t = l->totals();
      built.builds += t.builds, built.points += t.points, built.nodes += t.nodes,
          built.nanoseconds += t.nanoseconds;
    }
    f.attributes["nestlight:pbgi_bsh_builds"] = std::to_string(built.builds);
    f.attributes["nestlight:pbgi_bsh_points"] = std::to_string(built.points);
    f.attributes["nestlight:pbgi_bsh_built_nodes"] = std::to_string(built.nodes);
    f.attributes["nestlight:pbgi_bsh_seconds"] = std::to_string(double(built.nanoseconds) * 1e-9);
    f.attributes["nestlight:pbgi_receivers"] = std::to_string(receiverCount_);
    f.attributes["nestlight:pbgi_dispatches"] = std::to_string(dispatches_);
    f.attributes["nestlight:pbgi_traversal_bytes"] = std::to_string(stateBytes_);
    f.attributes["nestlight:pbgi_stack_overflows"] = std::to_string(stackOverflows_);
    char line[256];
    std::snprintf(line, sizeof line,
                  "; pbgi %s, %dx%d micro-buffers, %llu hierarchy nodes over %llu cut nodes",
                  variantName(), params_.microBuffer, params_.microBuffer,
                  (unsigned long long)bshNodes_, (unsigned long long)cutNodes_);
    f.summary += line;
    if (!meshTrees_.empty())
      f.summary += "; " + std::to_string(meshTrees_.size()) + " mesh hierarchies (" +
                   std::to_string(meshSurfels_) + " surfels)";
    if (params_.variant != PbgiParameters::Variant::Classic)
      f.summary += "; " + std::to_string(pairGenerations_) + " pair generations, " +
                   std::to_string(pairBytes_ >> 10) + " KiB of pairs and lists";
    if (pairOverflows_)
      f.summary += "; pairs outgrew pair_capacity (" + std::to_string(pairOverflows_) +
                   " not written): gathered from the root instead";
    f.summary += "; " + std::to_string(receiverCount_) + " receivers in " +
                 std::to_string(dispatches_) + " dispatches";
    if (albedo_ && bounces_ > 2)
      f.summary += "; albedo mode: " + std::to_string(gatheredBounces_) +
                   " further bounce(s) gathered at " + std::to_string(bounceReceivers_) +
                   " hierarchy nodes of at most " + std::to_string(params_.bouncePoints) +
                   " points";
    if (leftOut_)
      f.summary += "; " + std::to_string(leftOut_) +
                   " cut nodes left out (their hierarchies exceed one 128 MiB range)";
    if (stackOverflows_)
      f.summary +=
          "; " + std::to_string(stackOverflows_) + " traversal stack overflows (nodes skipped)";
  }

 private:
  // The cut's hierarchies into one buffer, their roots into the top tree.
  void rebuild(SceneFrame& f) {
    const auto t0 = std::chrono::steady_clock::now();
    generation_ = f.cutGeneration();
    hier_.assemble(f, layer_);
    std::vector<PbgiNode> table = hier_.entries();
    cutNodes_ = hier_.cutNodes();
    leftOut_ = hier_.leftOut();
    scanTrees_ = hier_.scanTrees();
    bshNodes_ = hier_.nodeCount();
    topCount_ = hier_.topCount();
    tableCount_ = table.size();
    maxRange_ = 0;
    treeSizes_.clear();
    treeStart_.clear();
    for (const auto& e : table) {
      maxRange_ = std::max<uint64_t>(maxRange_, e.range.y);
      treeSizes_.push_back(e.range.y);
      treeStart_.push_back(e.range.x);
    }
    if (lit_) {
      // The albedo mode's lit copies are in the scene's units already: the gather scales them by
      // 1. In the radiance-cache mode the scan's nodes are copied as they are, scales kept.
      if (albedo_)
        for (auto& e : table) e.origin.w = 1.0f;
      tableLit_.reserve(std::max<size_t>(table.size(), 1) * sizeof(PbgiNode));
      if (!table.empty()) tableLit_.upload(table.data(), table.size() * sizeof(PbgiNode));
      nodesLit_.reserve(hier_.nodes().bytes());
      topLit_.reserve(hier_.top().bytes());
      // The radiance-cache mode lights only the meshes' surfels: the scan's nodes are copied once
      // per cut, not every frame.
      if (!albedo_ && bshNodes_ > 0)
        glCopyNamedBufferSubData(hier_.nodes().id(), nodesLit_.id(), 0, 0,
                                 GLsizeiptr(bshNodes_ * sizeof(BshNode)));
    }
    meshRoots_.assign(hier_.roots().begin() + std::ptrdiff_t(scanTrees_), hier_.roots().end());
    average_ = topCount_ ? scanAverage(hier_.topRoot(), meshRoots_) : glm::vec3(0);
    topMs_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }

  void addPasses(SceneFrame& f) {
    frame::FrameGraph& g = f.graph();
    g.addTarget("radiance_gi", {GL_RGBA32F});
    if (lit_) {
      g.addBuffer("pbgi_lit");
      g.addPass(
          "pbgi_light", frame::Scope::Frame,
          [](frame::PassBuilder& b) {
            b.read("shadow_maps");
            b.write("pbgi_lit");
          },
          [this, &f](const frame::PassContext& ctx) { lightNodes(f, ctx); });
    }
    g.addPass(
        "pbgi_gather", frame::Scope::Tile,
        [this](frame::PassBuilder& b) {
          for (const char* t : {"depth", "base_colour", "normal", "material", "radiance"})
            b.read(t);
          if (lit_) b.read("pbgi_lit");
          b.write("radiance_gi");
        },
        [this, &f](const frame::PassContext& ctx) { gather(f, ctx); });
  }

  // Lit copies of the hierarchies and the top tree, which the gather reads instead: in the albedo
  // mode every node's radiance from the lights (pbgi_light.comp); in the radiance-cache mode the
  // scan's nodes as they are (their colour is their radiance) and the meshes' surfels lit.
  void lightNodes(SceneFrame& f, const frame::PassContext& ctx) {
    gatheredBounces_ = bounceReceivers_ = 0;
    if (topCount_ == 0) return;
    const size_t firstLit = albedo_ ? 0 : scanTrees_;  // the scan's were copied at rebuild()
    uint64_t litRange = 0;
    for (size_t k = firstLit; k < treeSizes_.size(); ++k)
      litRange = std::max<uint64_t>(litRange, treeSizes_[k]);
    const gl::Texture& maps = ctx.target("shadow_maps");
    maps.setFilter(GL_LINEAR, GL_LINEAR);
    maps.setDepthCompare(true);
    glBindTextureUnit(4, maps.id());
    f.bindSceneBuffers();
    lightProgram_.use();
    f.bindEnvironment(lightProgram_);
    hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    glUniform1i(lightProgram_.uniform("uFirstTree"), int(firstLit));
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    if (tableCount_ > firstLit && litRange > 0) {
      hier_.nodes().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_IN);
      nodesLit_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_OUT);
      glDispatchCompute(GLuint((litRange + 63) / 64), GLuint(tableCount_ - firstLit), 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    receivers_.reserve(16);
    std::vector<uint32_t> start = treeSizes_;
    std::fill(start.begin(), start.begin() + std::ptrdiff_t(firstLit),
              0u);  // the scan's, copied as they were
    sweepUp(start);
    if (albedo_ && bounces_ >= 3) gatherBounces(f);
  }

  // Bottom-up sweeps: the hierarchies from `start` (each one's node count, or 0 to leave it), then
  // the top tree over their lit roots; then the empty m-pixels' average.
  void sweepUp(const std::vector<uint32_t>& start) {
    const int budget = std::max(budget_ - 1024, 1024);
    receivers_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_RECEIVERS);
    lightUpProgram_.use();
    glUniform1i(lightUpProgram_.uniform("uTrees"), int(tableCount_));
    glUniform1i(lightUpProgram_.uniform("uTopCount"), int(topCount_));
    glUniform1i(lightUpProgram_.uniform("uBudget"), budget);
    auto sweep = [&](bool topTree, const gl::Buffer& tree, size_t trees,
                     const std::vector<uint32_t>& from) {
      cursors_.reserve(std::max<size_t>(trees, 1) * 4);
      cursors_.upload(from.data(), from.size() * 4);
      cursors_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_CURSORS);
      tree.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_OUT);
      nodesLit_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_IN);
      glUniform1i(lightUpProgram_.uniform("uTopTree"), topTree ? 1 : 0);
      runUntilDone(trees, "a light sweep");
    };
    hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    if (tableCount_ > 0) sweep(false, nodesLit_, tableCount_, start);
    // The top tree's leaves take their nodes' lit roots, scaled as the gather scales them.
    tableLit_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    glCopyNamedBufferSubData(hier_.top().id(), topLit_.id(), 0, 0,
                             GLsizeiptr(topCount_ * sizeof(BshNode)));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    sweep(true, topLit_, 1, {uint32_t(topCount_)});
    BshNode root;
    glGetNamedBufferSubData(topLit_.id(), 0, sizeof root, &root);
    std::vector<BshNode> meshRoots = meshRoots_;
    for (size_t j = 0; j < meshRoots.size(); ++j) {
      const GLintptr at = GLintptr(size_t(treeStart_[scanTrees_ + j]) * sizeof(BshNode));
      glGetNamedBufferSubData(nodesLit_.id(), at, sizeof(BshNode), &meshRoots[j]);
    }
    averageLit_ = scanAverage(root, meshRoots);
  }

  // Dispatches the program in use over `invocations` (64 a group) until none reports unfinished
  // work in receivers_[1] (the resumable sweeps).
  void runUntilDone(size_t invocations, const char* what) {
    for (int dispatch = 0;; ++dispatch) {
      const uint32_t zero = 0;
      receivers_.upload(&zero, 4, 4);
      glDispatchCompute(GLuint((invocations + 63) / 64), 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
      uint32_t unfinished = 0;
      glGetNamedBufferSubData(receivers_.id(), 4, 4, &unfinished);
      if (unfinished == 0) break;
      NL_CHECK_MSG(dispatch < 100000, std::string("pbgi: ") + what + " did not end");
    }
  }

  // The albedo mode's bounces beyond the one every pixel gathers: the nodes standing for at most
  // `bounce_points` points gather the lit hierarchies (pbgi_bounce_select.comp, then the classic
  // traversal with nodes as receivers), every leaf below takes its direct light plus its albedo
  // times what its receiver gathered (pbgi_bounce_down.comp), and the sweeps rebuild the inner
  // nodes: each pass adds one bounce to the light the pixels then gather.
  void gatherBounces(SceneFrame& f) {
    if (tableCount_ == 0 || bshNodes_ == 0) return;
    nodesDirect_.reserve(nodesLit_.bytes());
    glCopyNamedBufferSubData(nodesLit_.id(), nodesDirect_.id(), 0, 0,
                             GLsizeiptr(bshNodes_ * sizeof(BshNode)));
    receivers_.reserve((4 + 2 * bshNodes_) * 4);
    const uint32_t zeros[4] = {0, 0, 0, 0};
    receivers_.upload(zeros, sizeof zeros);
    receivers_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_RECEIVERS);
    selectProgram_.use();
    glUniform1ui(selectProgram_.uniform("uPoints"), GLuint(params_.bouncePoints));
    hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    hier_.nodes().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
    glDispatchCompute(GLuint((maxRange_ + 63) / 64), GLuint(tableCount_), 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    uint32_t count = 0;
    glGetNamedBufferSubData(receivers_.id(), 0, 4, &count);
    bounceReceivers_ = count;
    gathered_.reserve(bshNodes_ * 16);
    const std::vector<uint32_t> zeroCursors(tableCount_, 0u);
    for (int b = 0; b + 2 < bounces_; ++b) {
      const float none[4] = {0, 0, 0, 0};
      glClearNamedBufferData(gathered_.id(), GL_RGBA32F, GL_RGBA, GL_FLOAT, none);
      glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
      gathered_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_BOUNCE);
      traverse(f, count, true, false, topLit_, nodesLit_, tableLit_);
      downProgram_.use();
      glUniform1i(downProgram_.uniform("uTrees"), int(tableCount_));
      glUniform1i(downProgram_.uniform("uBudget"), std::max(budget_ - 1024, 1024));
      cursors_.reserve(tableCount_ * 4);
      cursors_.upload(zeroCursors.data(), zeroCursors.size() * 4);
      cursors_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_CURSORS);
      hier_.table().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
      hier_.nodes().bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_IN);
      nodesDirect_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
      nodesLit_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIGHT_OUT);
      receivers_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_RECEIVERS);
      runUntilDone(tableCount_, "a bounce's down sweep");
      sweepUp(treeSizes_);
      gatheredBounces_++;
      // traverse() reads the receivers' list again next time: the sweeps only used its header.
      receivers_.upload(&count, 4);
    }
  }

  // The paper's colour for empty m-pixels is the cloud's average: the top tree's root holds the
  // count-weighted mean over the scan and the meshes' surfels, so the meshes' share comes out.
  static glm::vec3 scanAverage(const BshNode& root, const std::vector<BshNode>& meshRoots) {
    glm::dvec3 sum = glm::dvec3(glm::vec3(root.colour)) * double(root.links.z);
    double count = double(root.links.z);
    for (const BshNode& m : meshRoots)
      sum -= glm::dvec3(glm::vec3(m.colour)) * double(m.links.z), count -= m.links.z;
    return count > 0.5 ? glm::max(glm::vec3(sum / count), glm::vec3(0.0f)) : glm::vec3(0.0f);
  }

  // Lists the tile's receivers, then gathers for them in chunks that fit one buffer range, each
  // dispatched until every receiver of the chunk has finished its traversal.
  void gather(SceneFrame& f, const frame::PassContext& ctx) {
    const frame::Tile& tile = ctx.tile();
    const size_t pixels = size_t(tile.width) * size_t(tile.height);
    receivers_.reserve((4 + pixels) * 4);
    const uint32_t zeros[4] = {0, 0, 0, 0};
    receivers_.upload(zeros, sizeof zeros);
    f.bindSceneBuffers();
    ctx.bindTexture("depth", 0);
    ctx.bindTexture("base_colour", 1);
    ctx.bindTexture("normal", 2);
    ctx.bindTexture("material", 3);
    ctx.bindTexture("radiance", 4);
    glBindImageTexture(0, ctx.target("radiance_gi").id(), 0, GL_FALSE, 0, GL_WRITE_ONLY,
                       GL_RGBA32F);
    receivers_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_RECEIVERS);
    receiversProgram_.use();
    glDispatchCompute(GLuint((tile.width + 7) / 8), GLuint((tile.height + 7) / 8), 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT |
                    GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    uint32_t count = 0;
    glGetNamedBufferSubData(receivers_.id(), 0, 4, &count);
    receiverCount_ += count;
    // Albedo mode: the lit copies; one bounce asked (direct light only): nothing to gather.
    const gl::Buffer& topIn = lit_ ? topLit_ : hier_.top();
    const gl::Buffer& nodesIn = lit_ ? nodesLit_ : hier_.nodes();
    const gl::Buffer& tableIn = lit_ ? tableLit_ : hier_.table();
    if (albedo_ && bounces_ < 2) count = 0;
    bool lists = false;
    if (count > 0 && topCount_ > 0 && params_.variant != PbgiParameters::Variant::Classic) {
      topIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TOP);
      nodesIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
      tableIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
      lists = refinePairs(tile);
      receivers_.upload(zeros, sizeof zeros);  // the pairs' counters reused the receivers' header
    }
    if (gathered_.bytes() == 0)
      gathered_.reserve(16);  // read only with nodes as receivers; bound all the same
    gathered_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_BOUNCE);
    if (listHead_.bytes() == 0) listHead_.reserve(16);
    if (list_.bytes() == 0) list_.reserve(16);
    listHead_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIST_HEAD);
    list_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIST);
    // With nothing resident a receiver that owns the sky still gathers it (every m-pixel empty).
    if (count > 0 && (topCount_ > 0 || skyOwned_))
      traverse(f, count, false, lists, topIn, nodesIn, tableIn);
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
  }

  // The classic traversal for `count` receivers listed in receivers_ (pixels, or hierarchy nodes),
  // in chunks that fit one buffer range, each dispatched until every receiver has finished.
  void traverse(SceneFrame& f, size_t count, bool nodeReceivers, bool lists,
                const gl::Buffer& topIn, const gl::Buffer& nodesIn, const gl::Buffer& tableIn) {
    const uint32_t zero = 0;
    const size_t m2 = size_t(params_.microBuffer) * size_t(params_.microBuffer);
    const size_t perReceiver = sizeof(glsl::PbgiTraversal) + PBGI_STACK * 8 + m2 * 16;
    size_t chunk = std::min<size_t>(count, gl::kMaxSsboRange / (m2 * 16));
    chunk = std::min<size_t>(chunk, 1 << 16);
    state_.reserve(chunk * sizeof(glsl::PbgiTraversal));
    stack_.reserve(chunk * PBGI_STACK * 8);
    mb_.reserve(chunk * m2 * 16);
    stateBytes_ = std::max<uint64_t>(stateBytes_, chunk * perReceiver);
    topIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TOP);
    nodesIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_NODES);
    tableIn.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_TABLE);
    micro_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_MICRO);
    state_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_STATE);
    stack_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_STACK);
    mb_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_MB);
    classic_.use();
    glUniform1i(classic_.uniform("uBudget"), budget_);
    glUniform1i(classic_.uniform("uTopCount"), int(topCount_));
    glUniform1i(classic_.uniform("uLists"), lists ? 1 : 0);
    glUniform1i(classic_.uniform("uNodeReceivers"), nodeReceivers ? 1 : 0);
    setLift(classic_);
    glUniform1f(classic_.uniform("uOmegaCut"),
                pbgi::mPixelSolidAngle(params_.microBuffer) * (params_.conservative ? 4.0f : 1.0f));
    const glm::vec3 average = lit_ ? averageLit_ : average_;
    const glm::vec3 empty =
        params_.empty == PbgiParameters::Empty::Average ? average : glm::vec3(0);
    // Hierarchy nodes receiving (further bounces) have the sky in their direct light already.
    const glm::vec3 e = nodeReceivers ? glm::vec3(0) : empty;
    glUniform3f(classic_.uniform("uEmpty"), e.r, e.g, e.b);
    glUniform1i(classic_.uniform("uEmptyEnvironment"),
                !nodeReceivers && params_.empty == PbgiParameters::Empty::Environment ? 1 : 0);
    f.bindEnvironment(classic_);
    for (size_t first = 0; first < count; first += chunk) {
      const size_t n = std::min(chunk, count - first);
      glUniform1i(classic_.uniform("uFirst"), int(first));
      glUniform1i(classic_.uniform("uCount"), int(n));
      for (int dispatch = 0;; ++dispatch) {
        receivers_.upload(&zero, 4, 4);  // unfinished receivers, counted by this dispatch
        glUniform1i(classic_.uniform("uInit"), dispatch == 0 ? 1 : 0);
        glDispatchCompute(GLuint((n + 63) / 64), 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT |
                        GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        dispatches_++;
        uint32_t unfinished = 0;
        glGetNamedBufferSubData(receivers_.id(), 4, 4, &unfinished);
        if (unfinished == 0) break;
        if (dispatch > 1000000)
          throw Error(
              "pbgi: a traversal did not finish after a million dispatches (a cycle in a "
              "hierarchy?)");
      }
    }
    uint32_t overflow = 0;
    glGetNamedBufferSubData(receivers_.id(), 8, 4, &overflow);
    stackOverflows_ += overflow;
  }

  // MIP-PBGI / X-PBGI: the receivers' pyramid, then (node, block) pairs refined generation by
  // generation until every pair has reached a single receiver's list. Returns false when the
  // pairs or the lists outgrew their buffers (counted): the frame then gathers from the root.
  bool refinePairs(const frame::Tile& tile) {
    std::vector<glm::ivec2> sizes{{tile.width, tile.height}};
    while ((sizes.back().x > 1 || sizes.back().y > 1) && sizes.size() < 16)
      sizes.push_back({(sizes.back().x + 1) / 2, (sizes.back().y + 1) / 2});
    std::vector<int> offsets;
    int texels = 0;
    for (const auto& sz : sizes) offsets.push_back(texels), texels += sz.x * sz.y;
    const int levels = int(sizes.size());
    pyramid_.reserve(size_t(texels) * 32);
    pyramid_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_PYRAMID);
    pyramidProgram_.use();
    setLift(pyramidProgram_);
    for (int l = 0; l < levels; ++l) {
      glUniform1i(pyramidProgram_.uniform("uLevel"), l);
      glUniform2i(pyramidProgram_.uniform("uSize"), sizes[size_t(l)].x, sizes[size_t(l)].y);
      glUniform1i(pyramidProgram_.uniform("uOffset"), offsets[size_t(l)]);
      if (l > 0) {
        glUniform2i(pyramidProgram_.uniform("uChildSize"), sizes[size_t(l) - 1].x,
                    sizes[size_t(l) - 1].y);
        glUniform1i(pyramidProgram_.uniform("uChildOffset"), offsets[size_t(l) - 1]);
      }
      glDispatchCompute(GLuint((sizes[size_t(l)].x + 7) / 8), GLuint((sizes[size_t(l)].y + 7) / 8),
                        1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    const size_t capacity = size_t(params_.pairCapacity);
    pairsA_.reserve(capacity * 16);
    pairsB_.reserve(capacity * 16);
    list_.reserve(capacity * 16);
    listHead_.reserve(size_t(tile.width) * size_t(tile.height) * 4);
    const uint32_t end = PBGI_END;
    glClearNamedBufferData(listHead_.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, &end);
    const uint32_t top = uint32_t(levels - 1);
    const glm::uvec4 root(0, 0, top << 28, 0);
    pairsA_.upload(&root, sizeof root);
    const uint32_t zeros[4] = {0, 0, 0, 0};
    receivers_.upload(zeros, sizeof zeros);
    listHead_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIST_HEAD);
    list_.bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_LIST);
    pairsProgram_.use();
    const float omegaM =
        pbgi::mPixelSolidAngle(params_.microBuffer) * (params_.conservative ? 4.0f : 1.0f);
    glUniform1f(pairsProgram_.uniform("uOmegaTr"),
                params_.variant == PbgiParameters::Variant::X
                    ? 32.0f * pbgi::mPixelSolidAngle(params_.microBuffer)
                    : omegaM);
    glUniform1ui(pairsProgram_.uniform("uPairCapacity"), GLuint(capacity));
    glUniform1ui(pairsProgram_.uniform("uListCapacity"), GLuint(capacity));
    glUniform1iv(pairsProgram_.uniform("uLevelOffset"), levels, offsets.data());
    glUniform2iv(pairsProgram_.uniform("uLevelSize"), levels, &sizes[0].x);
    uint32_t inCount = 1;
    gl::Buffer* in = &pairsA_;
    gl::Buffer* out = &pairsB_;
    uint64_t peak = 1;
    for (int generation = 0; inCount > 0; ++generation) {
      NL_CHECK_MSG(generation < 4096,
                   "pbgi: pair refinement did not end (a cycle in a hierarchy?)");
      receivers_.upload(zeros, 8);  // pairs written, pairs that did not fit
      in->bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_PAIRS_IN);
      out->bindBase(GL_SHADER_STORAGE_BUFFER, PBGI_SSBO_PAIRS_OUT);
      glUniform1i(pairsProgram_.uniform("uInCount"), int(inCount));
      glDispatchCompute(GLuint((inCount + 63) / 64), 1, 1);
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
      pairGenerations_++;
      uint32_t c[4];
      glGetNamedBufferSubData(receivers_.id(), 0, sizeof c, c);
      if (c[1] > 0 || c[3] > 0) {
        pairOverflows_ += c[1] + c[3];
        return false;
      }
      inCount = c[0];
      peak = std::max<uint64_t>(peak, inCount);
      listEntries_ = c[2];
      std::swap(in, out);
    }
    pairBytes_ =
        std::max<uint64_t>(pairBytes_, 2 * peak * 16 + listEntries_ * 16 + uint64_t(texels) * 32);
    return true;
  }

  PbgiParameters params_;
  size_t layer_ = 0;
  std::vector<std::shared_ptr<const BshLayer>> layers_;  // one per scan, for their build totals
  gl::ShaderProgram receiversProgram_, classic_, pyramidProgram_, pairsProgram_;
  gl::Buffer micro_, receivers_, state_, stack_, mb_;
  CutHierarchies hier_;
  gl::Buffer pyramid_, pairsA_, pairsB_, list_, listHead_;
  gl::ShaderProgram lightProgram_, lightUpProgram_, selectProgram_, downProgram_;
  gl::Buffer nodesDirect_,
      gathered_;  // further bounces: the leaves' direct light, each node's gathered light
  uint64_t gatheredBounces_ = 0, bounceReceivers_ = 0;
  gl::Buffer cursors_;
  std::vector<uint32_t> treeSizes_, treeStart_;
  std::vector<BshNode> meshRoots_;  // the meshes' roots as the top tree holds them (scene frame)
  gl::Buffer nodesLit_, topLit_, tableLit_;  // albedo mode: the hierarchies with their lit radiance
  bool albedo_ = false;
  bool lit_ = false;  // the gather reads lit copies (albedo mode, or meshes' surfels)
  std::vector<MeshTree> meshTrees_;
  uint64_t meshSurfels_ = 0;
  // Mesh receivers leave from this far above their surface (pbgi_common.glsl): per box, else per
  // material.
  std::array<float, PBGI_LIFTS> meshLift_{};
  float meshLiftMax_ = 0;
  std::vector<glm::vec4>
      liftBoxes_;  // per mesh lifting its own receivers: (lo, lift), (hi, material)
  void setLift(const gl::ShaderProgram& p) const {
    glUniform1i(p.uniform("uLiftBoxes"), int(liftBoxes_.size() / 2));
    if (!liftBoxes_.empty())
      glUniform4fv(p.uniform("uLiftBox[0]"), GLsizei(liftBoxes_.size()), &liftBoxes_[0].x);
    glUniform1fv(p.uniform("uMeshLift[0]"), PBGI_LIFTS, meshLift_.data());
    glUniform1f(p.uniform("uMeshLiftMax"), meshLiftMax_);
  }
  size_t scanTrees_ = 0;   // the table's first entries are the cut's nodes, then the meshes'
  bool skyOwned_ = false;  // the gather, not direct light, gives receivers the sky
  int bounces_ = 1;
  size_t tableCount_ = 0;
  uint64_t maxRange_ = 0;
  glm::vec3 averageLit_{0};
  uint64_t pairGenerations_ = 0, pairOverflows_ = 0, pairBytes_ = 0, listEntries_ = 0;
  int budget_ = 1 << 20;
  uint64_t receiverCount_ = 0, dispatches_ = 0, stateBytes_ = 0, stackOverflows_ = 0;
  uint64_t generation_ = ~0ull;
  uint64_t cutNodes_ = 0, leftOut_ = 0, bshNodes_ = 0;
  size_t topCount_ = 0;
  double topMs_ = 0;
  glm::vec3 average_{0};
};

}  // namespace

std::unique_ptr<Method> createPbgiMethod(const Scene& scene, const MethodContext& ctx) {
  return createRasterMethod(scene, ctx, std::make_unique<PbgiExtension>(scene));
}

}  // namespace nestlight::gi
