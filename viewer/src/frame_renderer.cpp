#include "nestlight/viewer/frame_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <glm/gtc/type_ptr.hpp>
#include <unordered_map>

#include "nestlight/octree/error.h"

namespace nestlight::viewer {

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

FrameRenderer::FrameRenderer()
    : points_(
          {{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/points.frag"}}),
      hqsDepth_({{GL_VERTEX_SHADER, "points/points.vert"},
                 {GL_FRAGMENT_SHADER, "points/hqs_depth.frag"}}),
      hqsAccum_({{GL_VERTEX_SHADER, "points/points.vert"},
                 {GL_FRAGMENT_SHADER, "points/hqs_accum.frag"}}),
      hqsResolve_({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                   {GL_FRAGMENT_SHADER, "points/hqs_resolve.frag"}}),
      depthPass_({{GL_COMPUTE_SHADER, "points/raster_depth.comp"}}),
      colourPass_({{GL_COMPUTE_SHADER, "points/raster_colour.comp"}}),
      resolve_({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                {GL_FRAGMENT_SHADER, "points/raster_resolve.frag"}}),
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
      "points", frame::Scope::Tile,
      [](frame::PassBuilder& b) {
        for (const char* t : {"depth", "colour", "normal", "hqs_colour", "hqs_normal"}) b.write(t);
      },
      [this](const frame::PassContext& ctx) { rasterise(ctx); });
  graph_.addPass(
      "eye_dome_lighting", frame::Scope::Tile,
      [](frame::PassBuilder& b) {
        b.read("colour");
        b.read("depth");
        b.write("output");
        b.margin(int(std::ceil(RenderSettings::kMaxEdlRadius)) + 2);
      },
      [this](const frame::PassContext& ctx) {
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
  if (epoxy_has_gl_extension("GL_NV_shader_atomic_int64") &&
      epoxy_has_gl_extension("GL_ARB_gpu_shader_int64")) {
    try {
      atomic64_ = std::make_unique<gl::ShaderProgram>(std::vector<gl::ShaderProgram::Stage>{
          {GL_COMPUTE_SHADER, "points/raster_atomic64.comp"}});
      resolve64_ = std::make_unique<gl::ShaderProgram>(std::vector<gl::ShaderProgram::Stage>{
          {GL_VERTEX_SHADER, "common/fullscreen.vert"},
          {GL_FRAGMENT_SHADER, "points/raster_resolve64.frag"}});
    } catch (const Error& e) {
      // A driver that offers the extension but rejects the shader: the 32-bit path still works.
      std::fprintf(stderr,
                   "nestlight: 64-bit compute rasteriser unavailable, using two passes: %s\n",
                   e.what());
      atomic64_.reset();
      resolve64_.reset();
    }
  }
}

FrameRenderer::~FrameRenderer() = default;

void FrameRenderer::rasterise(const frame::PassContext& ctx) {
  const std::vector<streaming::DrawNode>& nodes = *nodes_;
  const frame::GlNodeStore& store = *store_;
  const Camera& camera = camera_;
  const RenderSettings& s = settings_;
  DrawTimings* t = timings_;
  const frame::Tile& tile = ctx.tile();
  const int fullW = tile.fullWidth, fullH = tile.fullHeight, x0 = tile.x0, y0 = tile.y0,
            w = tile.width, h = tile.height;
  const bool compute = s.rasteriser == Rasteriser::Compute;
  if (compute) ensureSsbos(size_t(w) * h);
  // The G-buffer and the HQS sums, on this run's targets (the graph reallocates them with size).
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("colour"));
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("normal"));
  gbufferFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
  gbufferFbo_.finish(2, "the point view's G-buffer");
  hqsFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("hqs_colour"));
  hqsFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("hqs_normal"));
  hqsFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
  hqsFbo_.finish(2, "the point view's HQS sums");
  const GLuint gbuffer_ = gbufferFbo_.id(), hqsFbo = hqsFbo_.id();
  const glm::dmat4 clipFromView =
      tileFromClip(fullW, fullH, x0, y0, w, h) * camera.projection(double(fullW) / fullH);
  const glm::dmat4 viewFromCamRel = camera.viewRotation();
  const double pixelsPerUnit = fullH / (2.0 * std::tan(glm::radians(camera.fovYDegrees) * 0.5));

  glViewport(0, 0, w, h);
  const float clearColour[4] = {0, 0, 0, 0}, clearNormal[4] = {0, 0, 0, 0};
  const float clearDepth = 1.0f;
  glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
  glClearNamedFramebufferfv(gbuffer_, GL_COLOR, 0, clearColour);
  glClearNamedFramebufferfv(gbuffer_, GL_COLOR, 1, clearNormal);
  glClearNamedFramebufferfv(gbuffer_, GL_DEPTH, 0, &clearDepth);
  glBindVertexArray(vao_.id());

  auto nodeOffset = [&](const streaming::DrawNode& n) {
    const glm::dvec3 origin(n.worldBounds.min.x, n.worldBounds.min.y, n.worldBounds.min.z);
    return glm::vec3(origin - camera.eye);  // the difference is small: float keeps it exact enough
  };
  // One compute pass over every node: a dispatch per node with its buffer and camera offset.
  auto dispatchNodes = [&](const gl::ShaderProgram& pass, bool countPoints) {
    const GLuint p = pass.id();
    pass.use();
    setMat4(p, "uClipFromView", clipFromView);
    setMat4(p, "uViewFromCamRel", viewFromCamRel);
    glProgramUniform2i(p, pass.uniform("uViewport"), w, h);
    glProgramUniform1i(p, pass.uniform("uHdrColour"), store.hdrColour());
    const GLint offLoc = pass.uniform("uNodeOffset"), nLoc = pass.uniform("uNumPoints");
    for (const auto& n : nodes) {
      if (!n.numPoints) continue;
      const glm::vec3 off = nodeOffset(n);
      glProgramUniform3f(p, offLoc, off.x, off.y, off.z);
      glProgramUniform1ui(p, nLoc, n.numPoints);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, store.buffer(n.handle), 0,
                        GLsizeiptr(n.numPoints) * GLsizeiptr(frame::kGpuPointBytes));
      glDispatchCompute((n.numPoints + 127) / 128, 1, 1);
      if (t && countPoints) t->points += n.numPoints;
    }
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  };

  if (!compute) {
    const bool hqs = s.splatting == Splatting::Hqs;
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
      setMat4(p, "uViewFromCamRel", viewFromCamRel);
      glProgramUniform1f(p, prog.uniform("uPixelsPerUnit"), float(pixelsPerUnit));
      glProgramUniform1f(p, prog.uniform("uSizeScale"), s.sizeScale);
      glProgramUniform2f(p, prog.uniform("uSizeRange"), s.minPointSize, s.maxPointSize);
      glProgramUniform1f(p, prog.uniform("uFixedSize"), s.fixedPointSize);
      glProgramUniform1i(p, prog.uniform("uHdrColour"), store.hdrColour());
      const GLint offLoc = prog.uniform("uNodeOffset"), idxLoc = prog.uniform("uNodeIndex"),
                  sizeLoc = prog.uniform("uNodeSize"), nLoc = prog.uniform("uNumPoints");
      drawTree_.bind();
      for (size_t k = 0; k < nodes.size(); ++k) {
        const auto& n = nodes[k];
        if (!n.numPoints) continue;
        const glm::vec3 off = nodeOffset(n);
        glProgramUniform3f(p, offLoc, off.x, off.y, off.z);
        glProgramUniform1i(p, idxLoc, GLint(k));
        glProgramUniform1f(p, sizeLoc, float(n.worldBounds.max.x - n.worldBounds.min.x));
        glProgramUniform1ui(p, nLoc, n.numPoints);
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_NODE_POINTS, store.buffer(n.handle), 0,
                          GLsizeiptr(n.numPoints) * GLsizeiptr(frame::kGpuPointBytes));
        glDrawArrays(GL_POINTS, 0, GLsizei(n.numPoints));
        if (t && countPoints) t->points += n.numPoints;
      }
    };
    glEnable(GL_PROGRAM_POINT_SIZE);
    glEnable(GL_DEPTH_TEST);
    glViewport(-guard, -guard, w + 2 * guard, h + 2 * guard);
    if (!hqs) {
      glProgramUniform1i(points_.id(), points_.uniform("uRound"),
                         s.roundPoints && s.fixedPointSize != 1.0f);
      glDepthFunc(GL_LESS);
      glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
      drawSplats(points_, true);
      glViewport(0, 0, w, h);
    } else {
      // Pass 1: depth pushed back by epsilon. Pass 2: weighted sums of what lies in front of it.
      glProgramUniform1f(hqsDepth_.id(), hqsDepth_.uniform("uDepthEpsilon"), s.hqsDepthEpsilon);
      glDepthFunc(GL_LESS);
      glBindFramebuffer(GL_FRAMEBUFFER, hqsFbo);
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      drawSplats(hqsDepth_, true);
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      const float zero[4] = {0, 0, 0, 0};
      glClearNamedFramebufferfv(hqsFbo, GL_COLOR, 0, zero);
      glClearNamedFramebufferfv(hqsFbo, GL_COLOR, 1, zero);
      glDepthFunc(GL_LEQUAL);
      glDepthMask(GL_FALSE);
      glEnable(GL_BLEND);
      glBlendFunc(GL_ONE, GL_ONE);
      drawSplats(hqsAccum_, false);
      glDisable(GL_BLEND);
      glDepthMask(GL_TRUE);
      glViewport(0, 0, w, h);
      // Pass 3: normalise into the G-buffer, depth included (pixels no splat covered keep the
      // cleared far depth).
      const GLuint r = hqsResolve_.id();
      hqsResolve_.use();
      setMat4(r, "uClipFromView", clipFromView);
      glBindTextureUnit(0, ctx.target("hqs_colour").id());
      glBindTextureUnit(1, ctx.target("hqs_normal").id());
      glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
      glDepthFunc(GL_ALWAYS);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glDisable(GL_DEPTH_TEST);
  } else if (atomic64_ && s.allowAtomic64) {
    // One pass: min over (depth << 32 | colour); all ones is "empty".
    const size_t pixels = size_t(w) * h;
    const uint32_t empty[2] = {0xffffffffu, 0xffffffffu};
    glClearNamedBufferSubData(packedSsbo_.id(), GL_RG32UI, 0, GLsizeiptr(pixels * 8), GL_RG_INTEGER,
                              GL_UNSIGNED_INT, empty);
    glClearNamedBufferSubData(packedNormalSsbo_.id(), GL_RG32UI, 0, GLsizeiptr(pixels * 8),
                              GL_RG_INTEGER, GL_UNSIGNED_INT, empty);
    packedSsbo_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_PACKED, 0, pixels * 8);
    packedNormalSsbo_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_PACKED_NORMAL, 0,
                                pixels * 8);
    dispatchNodes(*atomic64_, true);
    const GLuint r = resolve64_->id();
    resolve64_->use();
    glProgramUniform1i(r, resolve64_->uniform("uHdrColour"), store.hdrColour());
    setMat4(r, "uClipFromView", clipFromView);
    setMat4(r, "uViewFromCamRel", viewFromCamRel);
    glProgramUniform2i(r, resolve64_->uniform("uViewport"), w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_DEPTH_TEST);
  } else {
    const size_t pixels = size_t(w) * h;
    const uint32_t far = 0xffffffffu, zero = 0;
    glClearNamedBufferSubData(depthSsbo_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 4), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &far);
    glClearNamedBufferSubData(accumSsbo_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 16), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
    glClearNamedBufferSubData(normalSsbo_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 4), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
    depthSsbo_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_DEPTH, 0, pixels * 4);
    accumSsbo_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_ACCUM, 0, pixels * 16);
    normalSsbo_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_NORMAL, 0, pixels * 4);
    dispatchNodes(depthPass_, true);
    dispatchNodes(colourPass_, false);
    const GLuint r = resolve_.id();
    resolve_.use();
    glProgramUniform1i(r, resolve_.uniform("uHdrColour"), store.hdrColour());
    setMat4(r, "uClipFromView", clipFromView);
    setMat4(r, "uViewFromCamRel", viewFromCamRel);
    glProgramUniform2i(r, resolve_.uniform("uViewport"), w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_DEPTH_TEST);
  }
  glViewport(0, 0, w, h);
}

void FrameRenderer::ensureSsbos(size_t pixels) {
  if (pixels <= ssboPixels_) return;
  NL_CHECK(pixels * 16 <= gl::kMaxSsboRange);
  depthSsbo_ = gl::Buffer(pixels * 4);
  accumSsbo_ = gl::Buffer(pixels * 16);
  normalSsbo_ = gl::Buffer(pixels * 4);
  if (atomic64_) {
    packedSsbo_ = gl::Buffer(pixels * 8);
    packedNormalSsbo_ = gl::Buffer(pixels * 8);
  }
  ssboPixels_ = pixels;
}

void FrameRenderer::begin(const std::vector<streaming::DrawNode>& nodes,
                          const frame::GlNodeStore& store, const Camera& camera,
                          const RenderSettings& s, DrawTimings* t) {
  nodes_ = &nodes;
  store_ = &store;
  camera_ = camera;
  settings_ = s;
  timings_ = t;
  drawTree_.upload(nodes);
}

GLuint FrameRenderer::outputFramebuffer() {
  outputFbo_.attach(GL_COLOR_ATTACHMENT0, graph_.target("output"));
  return outputFbo_.id();
}

GLuint FrameRenderer::renderToTexture(const std::vector<streaming::DrawNode>& nodes,
                                      const frame::GlNodeStore& store, const Camera& camera,
                                      int width, int height, const RenderSettings& s,
                                      DrawTimings* t) {
  const auto t0 = std::chrono::steady_clock::now();
  begin(nodes, store, camera, s, t);
  graph_.executeToTarget(width, height);
  if (t) {
    glFinish();
    t->msDraw +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  return graph_.target("output").id();
}

Image FrameRenderer::render(const std::vector<streaming::DrawNode>& nodes,
                            const frame::GlNodeStore& store, const Camera& camera, int width,
                            int height, const RenderSettings& s, DrawTimings* t) {
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
  if (t)
    t->msDraw +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

}  // namespace nestlight::viewer
