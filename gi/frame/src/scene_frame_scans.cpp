// The GI frame's scans: each read by its OctreeReader into a GL node store, with two cuts
// streamed into it under the budgets (nestlight/streaming): the camera's, and the lights' (the
// whole scan at about a shadow map's resolution, so occluders out of the camera's view still
// cast shadows), the latter offered to extensions as one list (SceneFrame::lightsCut); and
// their drawn nodes drawn (shaders/points/points.vert, NL_SCENE_FRAME 1).
#include <algorithm>
#include <glm/gtc/matrix_transform.hpp>
#include <thread>
#include <unordered_map>

#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

void RasterMethod::loadScans() {
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
    if (!o.clipping.empty()) {
      frame::encodeClipBlock(o.clipping, {});  // more than the GPU holds: said before any frame
      s.clip = std::make_shared<const ClipSet>(o.clipping);
      s.gpuClip = std::make_unique<frame::GpuClip>();
      s.shadowView.clip = s.clip.get();
    }
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

size_t RasterMethod::addNodeLayer(const NodeLayerFactory& make) {
  NL_CHECK_MSG(frameNumber_ == 0, "node layers are added before the first frame streams");
  size_t index = 0;
  for (auto& s : scans_) index = s.store->addLayer(make(s.reader->metadata(), s.colours, s.clip));
  return index;
}

// Sets the frame's camera and brings each scan's cut for it in: completely (a still, judged
// against the reference) or one streaming step (interactive). Returns the points drawn.
uint64_t RasterMethod::stream(const SceneCamera& camera, bool complete) {
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
    streaming::View view = streaming::perspectiveView(camera.eye, camera.target, camera.up, fovY, W,
                                                      H, double(nearZ), double(farZ));
    view.clip = s.clip.get();
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
  if (extension_) {  // only extensions read them
    updateLightsCut();
    std::vector<uint64_t> viewCut;
    for (const auto& s : scans_) {
      for (const streaming::DrawNode& n : s.streamer->drawList())
        viewCut.insert(viewCut.end(), {n.handle, uint64_t(NodeKeyHash{}(n.key)), n.numPoints});
      viewCut.push_back(~0ull);  // the scans apart
    }
    if (viewCut != viewCut_) viewCut_ = std::move(viewCut), ++viewGeneration_;
  }

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
void RasterMethod::updateLightsCut() {
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
      c.clipTest = s.clip && s.clip->keeps(n.worldBounds) == Overlap::Partial;
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

void RasterMethod::bindScanClip(int scan) const {
  const auto& s = scans_.at(size_t(scan));
  if (s.clip) s.gpuClip->bind(*s.clip, Vec3d{scene_.origin.x, scene_.origin.y, scene_.origin.z});
}

// Draws every scan's drawn nodes with `program` (shaders/points/points.vert, NL_SCENE_FRAME 1).
void RasterMethod::drawScans(const gl::ShaderProgram& program, const glm::mat4& clipFromWorld,
                             const glm::mat4& viewFromWorld, float pixelsPerUnit, bool orthographic,
                             bool lightsCut) {
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
void RasterMethod::forEachNode(const gl::ShaderProgram& program,
                               const std::function<void(const streaming::DrawNode&)>& draw,
                               bool lightsCut) {
  const GLint nodeOrigin = program.uniform("uNodeOrigin"),
              nodeIndex = program.uniform("uNodeIndex"), nodeSize = program.uniform("uNodeSize"),
              numPoints = program.uniform("uNumPoints"),
              colourScale = program.uniform("uColourScale"),
              hdrColour = program.uniform("uHdrColour"), clipTest = program.uniform("uClipTest");
  for (size_t si = 0; si < scans_.size(); ++si) {
    auto& s = scans_[si];
    (lightsCut ? s.shadowTree : s.tree).bind();
    bindScanClip(int(si));
    glUniform1f(colourScale, s.colourScale);
    glUniform1i(hdrColour, s.store->hdrColour());
    const auto& nodes = (lightsCut ? s.shadowStreamer : s.streamer)->drawList();
    for (size_t k = 0; k < nodes.size(); ++k) {
      const auto& n = nodes[k];
      if (n.numPoints == 0) continue;
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, s.store->buffer(n.handle), 0,
                        GLsizeiptr(size_t(n.numPoints) * frame::kGpuPointBytes));
      const glm::vec3 origin =
          scene_.local({n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z});
      glUniform3f(nodeOrigin, origin.x, origin.y, origin.z);
      glUniform1i(nodeIndex, int(k));
      glUniform1f(nodeSize, float(n.worldBounds.max.x - n.worldBounds.min.x));
      glUniform1ui(numPoints, n.numPoints);
      glUniform1i(clipTest, s.clip && s.clip->keeps(n.worldBounds) == Overlap::Partial ? 1 : 0);
      draw(n);
    }
  }
}

}  // namespace nestlight::gi::frame_detail
