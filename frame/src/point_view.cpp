#include "nestlight/frame/point_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <unordered_map>

#include "nestlight/octree/error.h"

namespace nestlight::frame {

namespace {
void setMat4(GLuint prog, const char* name, const glm::dmat4& m) {
  const glm::mat4 f(m);
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, name), 1, GL_FALSE, glm::value_ptr(f));
}
}  // namespace

const char* rasteriserName(Rasteriser r) {
  return r == Rasteriser::Points ? "points" : "compute";
}
Rasteriser parseRasteriser(const std::string& name) {
  if (name == "points") return Rasteriser::Points;
  if (name == "compute") return Rasteriser::Compute;
  throw Error("unknown rasteriser '" + name + "' (points, compute)");
}

const char* splattingName(Splatting s) {
  return s == Splatting::Basic ? "basic" : "hqs";
}
Splatting parseSplatting(const std::string& name) {
  if (name == "basic") return Splatting::Basic;
  if (name == "hqs") return Splatting::Hqs;
  throw Error("unknown splatting '" + name + "' (basic, hqs)");
}

PointView::PointView()
    : splatting_(SplatFrame::PointView, true),
      edl_(
          {{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "points/edl.frag"}}) {
  vao_ = gl::VertexArray::create();
  gbufferFbo_ = gl::Framebuffer::create();
  hqsFbo_ = gl::Framebuffer::create();
  outputFbo_ = gl::Framebuffer::create();
  // GPU timers would stall every pass; the point view reports its wall time instead.
  graph_.setTiming(false);
  graph_.addTarget("depth", {GL_DEPTH_COMPONENT32F});
  graph_.addTarget("colour", {GL_RGBA16F});      // linear scan colour (recorded sRGB decoded)
  graph_.addTarget("normal", {GL_RGBA16F});      // view-space normal, a = 1 when known
  graph_.addTarget("hqs_colour", {GL_RGBA32F});  // HQS sums: rgb w, w
  graph_.addTarget("hqs_normal", {GL_RGBA32F});  // HQS sums: normal w, depth w
  graph_.addTarget("output", {GL_RGBA16F});  // display-referred (sRGB), or linear (linearOutput)
  graph_.addPass(
      "points", Scope::Tile,
      [](PassBuilder& b) {
        for (const char* t : {"depth", "colour", "normal", "hqs_colour", "hqs_normal"}) b.write(t);
      },
      [this](const PassContext& ctx) { rasterise(ctx); });
  graph_.addPass(
      "eye_dome_lighting", Scope::Tile,
      [](PassBuilder& b) {
        b.read("colour");
        b.read("depth");
        b.write("output");
        b.margin(int(std::ceil(RenderSettings::kMaxEdlRadius)) + 2);
      },
      [this](const PassContext& ctx) {
        const RenderSettings& s = settings_;
        const GLuint e = edl_.id();
        edl_.use();
        ctx.bindTexture("colour", 0);
        ctx.bindTexture("depth", 1);
        glProgramUniform1i(e, edl_.uniform("uColour"), 0);
        glProgramUniform1i(e, edl_.uniform("uDepth"), 1);
        glProgramUniform1f(e, edl_.uniform("uNear"), float(camera_.nearPlane));
        glProgramUniform1f(e, edl_.uniform("uFar"), float(camera_.farPlane));
        glProgramUniform1f(e, edl_.uniform("uStrength"), s.edlStrength);
        glProgramUniform1f(e, edl_.uniform("uRadius"),
                           std::min(s.edlRadius, RenderSettings::kMaxEdlRadius));
        glProgramUniform3f(e, edl_.uniform("uBackground"), s.background.x, s.background.y,
                           s.background.z);
        glProgramUniform1i(e, edl_.uniform("uLinearOutput"), s.linearOutput);
        glProgramUniform1f(e, edl_.uniform("uExposure"), std::exp2(s.exposureStops));
        glProgramUniform2f(e, edl_.uniform("uViewport"), float(ctx.tile().width),
                           float(ctx.tile().height));
        ctx.bindFramebuffer();
        glDisable(GL_DEPTH_TEST);
        glBindVertexArray(vao_.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
      });
  graph_.compile("output");
}

PointView::~PointView() = default;

// The tile's views: clipFromView maps the tile's pixels, viewFromCamRel rotates camera-relative
// positions into view space.
struct PointView::TileView {
  glm::dmat4 clipFromView, viewFromCamRel;
  int w = 0, h = 0;
};

void PointView::rasterise(const PassContext& ctx) {
  const Camera& camera = camera_;
  const Tile& tile = ctx.tile();
  const int fullW = tile.fullWidth, fullH = tile.fullHeight;
  // The G-buffer and the HQS sums, on this run's targets (the graph reallocates them with size).
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("colour"));
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("normal"));
  gbufferFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
  gbufferFbo_.finish(2, "the point view's G-buffer");
  hqsFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("hqs_colour"));
  hqsFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("hqs_normal"));
  hqsFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
  hqsFbo_.finish(2, "the point view's HQS sums");
  TileView v;
  v.w = tile.width, v.h = tile.height;
  v.clipFromView = tileFromClip(fullW, fullH, tile.x0, tile.y0, v.w, v.h) *
                   camera.projection(double(fullW) / fullH);
  v.viewFromCamRel = camera.viewRotation();

  glViewport(0, 0, v.w, v.h);
  const GLuint gbuffer = gbufferFbo_.id();
  const float clearColour[4] = {0, 0, 0, 0}, clearNormal[4] = {0, 0, 0, 0};
  const float clearDepth = 1.0f;
  glBindFramebuffer(GL_FRAMEBUFFER, gbuffer);
  glClearNamedFramebufferfv(gbuffer, GL_COLOR, 0, clearColour);
  glClearNamedFramebufferfv(gbuffer, GL_COLOR, 1, clearNormal);
  glClearNamedFramebufferfv(gbuffer, GL_DEPTH, 0, &clearDepth);
  glBindVertexArray(vao_.id());
  if (settings_.rasteriser == Rasteriser::Compute)
    computePoints(v);
  else
    splatPoints(ctx, v);
  glDisable(GL_DEPTH_TEST);
  glViewport(0, 0, v.w, v.h);
}

glm::vec3 PointView::nodeOffset(const streaming::DrawNode& n) const {
  const glm::dvec3 origin(n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z);
  return glm::vec3(origin - camera_.eye);  // the difference is small: float keeps it exact enough
}

// The GL_POINTS rasteriser: basic splats or high-quality splatting (PointSplatting).
void PointView::splatPoints(const PassContext& ctx, const TileView& v) {
  const std::vector<streaming::DrawNode>& nodes = *nodes_;
  const GlNodeStore& store = *store_;
  const Camera& camera = camera_;
  const RenderSettings& s = settings_;
  DrawTimings* t = timings_;
  const Tile& tile = ctx.tile();
  const int fullW = tile.fullWidth, fullH = tile.fullHeight, x0 = tile.x0, y0 = tile.y0;
  const int w = v.w, h = v.h;
  const double pixelsPerUnit = fullH / (2.0 * std::tan(glm::radians(camera.fovYDegrees) * 0.5));
  // GL clips a point by its centre, so a splat whose centre lies just outside the frame would
  // leave its part inside uncovered (holes along the edges). The splats are drawn into a
  // viewport larger by half the largest splat on every side, with the projection widened to
  // match: pixels inside the frame map exactly as before.
  const int guard =
      int(std::ceil(0.5 * (s.fixedPointSize > 0 ? s.fixedPointSize : s.maxPointSize))) + 1;
  const glm::dmat4 splatClipFromView =
      tileFromClip(fullW, fullH, x0 - guard, y0 - guard, w + 2 * guard, h + 2 * guard) *
      camera.projection(double(fullW) / fullH);
  // One draw of every node with `prog`: the splat vertex shader's uniforms and each node's
  // buffer, offset and place in the draw tree.
  auto drawSplats = [&](const gl::ShaderProgram& prog, bool countPoints) {
    const GLuint p = prog.id();
    prog.use();
    setMat4(p, "uClipFromView", splatClipFromView);
    setMat4(p, "uViewFromCamRel", v.viewFromCamRel);
    glProgramUniform1f(p, prog.uniform("uPixelsPerUnit"), float(pixelsPerUnit));
    glProgramUniform1f(p, prog.uniform("uSizeScale"), s.sizeScale);
    glProgramUniform2f(p, prog.uniform("uSizeRange"), s.minPointSize, s.maxPointSize);
    glProgramUniform1f(p, prog.uniform("uFixedSize"), s.fixedPointSize);
    glProgramUniform1i(p, prog.uniform("uHdrColour"), store.hdrColour());
    const GLint offLoc = prog.uniform("uNodeOffset"), idxLoc = prog.uniform("uNodeIndex"),
                sizeLoc = prog.uniform("uNodeSize"), nLoc = prog.uniform("uNumPoints"),
                clipLoc = prog.uniform("uClipTest");
    drawTree_.bind();
    for (size_t k = 0; k < nodes.size(); ++k) {
      const auto& n = nodes[k];
      if (!n.numPoints) continue;
      const glm::vec3 off = nodeOffset(n);
      glProgramUniform3f(p, offLoc, off.x, off.y, off.z);
      glProgramUniform1i(p, clipLoc, clipTest_[k]);
      glProgramUniform1i(p, idxLoc, GLint(k));
      glProgramUniform1f(p, sizeLoc, float(n.worldBounds.max.x - n.worldBounds.min.x));
      glProgramUniform1ui(p, nLoc, n.numPoints);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, store.buffer(n.handle), 0,
                        GLsizeiptr(n.numPoints) * GLsizeiptr(kGpuPointBytes));
      glDrawArrays(GL_POINTS, 0, GLsizei(n.numPoints));
      if (t && countPoints) t->points += n.numPoints;
    }
  };
  glEnable(GL_PROGRAM_POINT_SIZE);
  glEnable(GL_DEPTH_TEST);
  glViewport(-guard, -guard, w + 2 * guard, h + 2 * guard);
  if (s.splatting == Splatting::Basic) {
    const gl::ShaderProgram& basic = splatting_.basic();
    glProgramUniform1i(basic.id(), basic.uniform("uRound"),
                       s.roundPoints && s.fixedPointSize != 1.0f);
    glDepthFunc(GL_LESS);
    glBindFramebuffer(GL_FRAMEBUFFER, gbufferFbo_.id());
    drawSplats(basic, true);
    return;
  }
  PointSplatting::HqsTargets targets;
  targets.depthFbo = targets.sumFbo = hqsFbo_.id();
  targets.sums = 2;
  targets.sumTextures = {ctx.target("hqs_colour").id(), ctx.target("hqs_normal").id()};
  targets.gbufferFbo = gbufferFbo_.id();
  // The G-buffer holds the splats alone; pixels no splat covered keep the cleared far depth.
  targets.resolveDepthFunc = GL_ALWAYS;
  targets.width = w, targets.height = h;
  splatting_.hqs(targets, s.hqsDepthEpsilon, glm::mat4(v.clipFromView), drawSplats);
}

// The compute rasteriser (PointSplatting): one dispatch per node with its buffer and
// camera offset.
void PointView::computePoints(const TileView& v) {
  const std::vector<streaming::DrawNode>& nodes = *nodes_;
  const GlNodeStore& store = *store_;
  DrawTimings* t = timings_;
  auto dispatchNodes = [&](const gl::ShaderProgram& pass, bool countPoints) {
    const GLuint p = pass.id();
    pass.use();
    setMat4(p, "uClipFromView", v.clipFromView);
    setMat4(p, "uViewFromCamRel", v.viewFromCamRel);
    glProgramUniform2i(p, pass.uniform("uViewport"), v.w, v.h);
    glProgramUniform1i(p, pass.uniform("uHdrColour"), store.hdrColour());
    const GLint offLoc = pass.uniform("uNodeOffset"), nLoc = pass.uniform("uNumPoints"),
                clipLoc = pass.uniform("uClipTest");
    for (size_t k = 0; k < nodes.size(); ++k) {
      const auto& n = nodes[k];
      if (!n.numPoints) continue;
      const glm::vec3 off = nodeOffset(n);
      glProgramUniform3f(p, offLoc, off.x, off.y, off.z);
      glProgramUniform1i(p, clipLoc, clipTest_[k]);
      glProgramUniform1ui(p, nLoc, n.numPoints);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, store.buffer(n.handle), 0,
                        GLsizeiptr(n.numPoints) * GLsizeiptr(kGpuPointBytes));
      glDispatchCompute((n.numPoints + 127) / 128, 1, 1);
      if (t && countPoints) t->points += n.numPoints;
    }
  };
  auto resolveUniforms = [&](const gl::ShaderProgram& r) {
    glProgramUniform1i(r.id(), r.uniform("uHdrColour"), store.hdrColour());
    setMat4(r.id(), "uClipFromView", v.clipFromView);
    setMat4(r.id(), "uViewFromCamRel", v.viewFromCamRel);
    glProgramUniform2i(r.id(), r.uniform("uViewport"), v.w, v.h);
  };
  splatting_.compute(v.w, v.h, settings_.allowAtomic64, gbufferFbo_.id(), GL_ALWAYS, dispatchNodes,
                     resolveUniforms);
}

void PointView::begin(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
                      const Camera& camera, const RenderSettings& s, DrawTimings* t) {
  nodes_ = &nodes;
  store_ = &store;
  camera_ = camera;
  settings_ = s;
  timings_ = t;
  clipTest_.assign(nodes.size(), 0);
  if (s.clip && !s.clip->empty()) {
    // Nodes the volumes remove whole are not drawn (nor in the draw tree, so that splats keep
    // their size), nodes they keep whole skip the per-point test.
    clippedNodes_.clear();
    clipTest_.clear();
    for (const auto& n : nodes) {
      const Overlap o = s.clip->keeps(n.worldBounds);
      if (o == Overlap::None) continue;
      clippedNodes_.push_back(n);
      clipTest_.push_back(o == Overlap::Partial ? 1 : 0);
    }
    nodes_ = &clippedNodes_;
    clip_.bind(*s.clip, Vec3d{camera.eye.x, camera.eye.y, camera.eye.z});
  }
  drawTree_.upload(*nodes_);
}

GLuint PointView::outputFramebuffer() {
  outputFbo_.attach(GL_COLOR_ATTACHMENT0, graph_.target("output"));
  return outputFbo_.id();
}

GLuint PointView::renderToTexture(const std::vector<streaming::DrawNode>& nodes,
                                  const GlNodeStore& store, const Camera& camera, int width,
                                  int height, const RenderSettings& s, DrawTimings* t) {
  const auto t0 = std::chrono::steady_clock::now();
  begin(nodes, store, camera, s, t);
  graph_.executeToTarget(width, height);
  lastWidth_ = width, lastHeight_ = height;
  if (t) {
    glFinish();
    t->msDraw +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  return graph_.target("output").id();
}

Image PointView::render(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
                        const Camera& camera, int width, int height, const RenderSettings& s,
                        DrawTimings* t) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw Error("image size " + std::to_string(width) + "x" + std::to_string(height) +
                " is out of range");
  const auto t0 = std::chrono::steady_clock::now();
  begin(nodes, store, camera, s, t);
  // Tiles no larger than the compute path's buffers allow (16 bytes per pixel within an SSBO
  // range), margins included.
  const int margin = int(std::ceil(RenderSettings::kMaxEdlRadius)) + 2;
  int tile = std::max(64, s.maxTile);
  while (size_t(tile + 2 * margin) * (tile + 2 * margin) * 16 > gl::kMaxSsboRange) tile /= 2;
  Image img;
  img.width = width, img.height = height;
  img.linear = s.linearOutput;
  img.rgba = graph_.execute(width, height, tile);
  const bool oneTile = width <= tile && height <= tile;  // as FrameGraph::execute tiles
  lastWidth_ = oneTile ? width : 0, lastHeight_ = oneTile ? height : 0;
  if (t)
    t->msDraw +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

std::optional<DepthWindow> PointView::depthWindow(double x, double y, int radius) {
  if (lastWidth_ <= 0)
    throw Error("picking: the last frame was drawn in tiles; pick in an image of at most " +
                std::to_string(settings_.maxTile) + " pixels a side");
  const int cx = int(std::floor(x)), cy = int(std::floor(y));
  DepthWindow dw;
  dw.x0 = std::max(0, cx - radius), dw.y0 = std::max(0, cy - radius);
  const int x1 = std::min(lastWidth_ - 1, cx + radius), y1 = std::min(lastHeight_ - 1, cy + radius);
  if (dw.x0 > x1 || dw.y0 > y1) return std::nullopt;  // the window lies off the image
  dw.width = x1 - dw.x0 + 1, dw.height = y1 - dw.y0 + 1;
  std::vector<float> d(size_t(dw.width) * dw.height);
  // GL rows go up: image rows [y0, y1] are GL rows [H - 1 - y1, H - 1 - y0].
  glGetTextureSubImage(graph_.target("depth").id(), 0, dw.x0, lastHeight_ - 1 - y1, 0, dw.width,
                       dw.height, 1, GL_DEPTH_COMPONENT, GL_FLOAT,
                       GLsizei(d.size() * sizeof(float)), d.data());
  // The window depth back to the linear depth of glm::perspective's projection.
  const double n = camera_.nearPlane, f = camera_.farPlane;
  dw.depth.resize(d.size());
  bool any = false;
  for (int row = 0; row < dw.height; ++row)
    for (int col = 0; col < dw.width; ++col) {
      const float v = d[size_t(dw.height - 1 - row) * dw.width + col];  // GL row order flipped
      const double z = 2.0 * v - 1.0;
      const bool drawn = v < 1.0f;
      any = any || drawn;
      dw.depth[size_t(row) * dw.width + col] =
          drawn ? 2.0 * n * f / (f + n - z * (f - n)) : INFINITY;
    }
  if (!any) return std::nullopt;
  return dw;
}

}  // namespace nestlight::frame
