#include "nestlight/viewer/frame_renderer.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <unordered_map>
#include <glm/gtc/type_ptr.hpp>

#include "nestlight/octree/error.h"

namespace nestlight::viewer {

namespace {
// llvmpipe (and the issue) limit SSBO bindings to 128 MiB; the compute rasteriser's largest
// buffer is 16 bytes per pixel, so a tile holds at most 8M pixels.
constexpr size_t kMaxSsboBytes = size_t(128) << 20;

void setMat4(GLuint prog, const char* name, const glm::dmat4& m) {
  const glm::mat4 f(m);
  glProgramUniformMatrix4fv(prog, glGetUniformLocation(prog, name), 1, GL_FALSE, glm::value_ptr(f));
}
}  // namespace

const char* rasteriserName(Rasteriser r) { return r == Rasteriser::Points ? "points" : "compute"; }
Rasteriser parseRasteriser(const std::string& name) {
  if (name == "points") return Rasteriser::Points;
  if (name == "compute") return Rasteriser::Compute;
  throw Error("unknown rasteriser '" + name + "' (points, compute)");
}

const char* splattingName(Splatting s) { return s == Splatting::Basic ? "basic" : "hqs"; }
Splatting parseSplatting(const std::string& name) {
  if (name == "basic") return Splatting::Basic;
  if (name == "hqs") return Splatting::Hqs;
  throw Error("unknown splatting '" + name + "' (basic, hqs)");
}

FrameRenderer::FrameRenderer()
    : points_({{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/points.frag"}}),
      hqsDepth_({{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/hqs_depth.frag"}}),
      hqsAccum_({{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, "points/hqs_accum.frag"}}),
      hqsResolve_({{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "points/hqs_resolve.frag"}}),
      depthPass_({{GL_COMPUTE_SHADER, "points/raster_depth.comp"}}),
      colourPass_({{GL_COMPUTE_SHADER, "points/raster_colour.comp"}}),
      resolve_({{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "points/raster_resolve.frag"}}),
      edl_({{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "points/edl.frag"}}) {
  glCreateVertexArrays(1, &vao_);
  if (epoxy_has_gl_extension("GL_NV_shader_atomic_int64") && epoxy_has_gl_extension("GL_ARB_gpu_shader_int64")) {
    try {
      atomic64_ = std::make_unique<gl::ShaderProgram>(std::vector<gl::ShaderProgram::Stage>{
          {GL_COMPUTE_SHADER, "points/raster_atomic64.comp"}});
      resolve64_ = std::make_unique<gl::ShaderProgram>(std::vector<gl::ShaderProgram::Stage>{
          {GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "points/raster_resolve64.frag"}});
    } catch (const Error& e) {
      // A driver that offers the extension but rejects the shader: the 32-bit path still works.
      std::fprintf(stderr, "nestlight: 64-bit compute rasteriser unavailable, using two passes: %s\n", e.what());
      atomic64_.reset();
      resolve64_.reset();
    }
  }
}

FrameRenderer::~FrameRenderer() {
  GLuint fbos[] = {gbuffer_, outputFbo_, hqsFbo_};
  glDeleteFramebuffers(3, fbos);
  GLuint tex[] = {colourTex_, normalTex_, depthTex_, outputTex_, accColourTex_, accNormalTex_};
  glDeleteTextures(6, tex);
  GLuint bufs[] = {depthSsbo_, accumSsbo_, normalSsbo_, packedSsbo_, packedNormalSsbo_};
  glDeleteBuffers(5, bufs);
  glDeleteVertexArrays(1, &vao_);
}

void FrameRenderer::ensureTargets(int w, int h, bool compute) {
  if (w != w_ || h != h_) {
    GLuint fbos[] = {gbuffer_, outputFbo_, hqsFbo_};
    glDeleteFramebuffers(3, fbos);
    GLuint tex[] = {colourTex_, normalTex_, depthTex_, outputTex_, accColourTex_, accNormalTex_};
    glDeleteTextures(6, tex);
    glCreateTextures(GL_TEXTURE_2D, 1, &colourTex_);
    glTextureStorage2D(colourTex_, 1, GL_RGBA8, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &normalTex_);
    glTextureStorage2D(normalTex_, 1, GL_RGBA16F, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &depthTex_);
    glTextureStorage2D(depthTex_, 1, GL_DEPTH_COMPONENT32F, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &outputTex_);
    glTextureStorage2D(outputTex_, 1, GL_RGBA16F, w, h);
    // HQS sums in 32-bit float: hundreds of weighted colours per pixel at close range.
    glCreateTextures(GL_TEXTURE_2D, 1, &accColourTex_);
    glTextureStorage2D(accColourTex_, 1, GL_RGBA32F, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &accNormalTex_);
    glTextureStorage2D(accNormalTex_, 1, GL_RGBA32F, w, h);
    for (GLuint t : {colourTex_, normalTex_, depthTex_, outputTex_, accColourTex_, accNormalTex_}) {
      glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
      glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
      glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
      glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    }
    glCreateFramebuffers(1, &gbuffer_);
    glNamedFramebufferTexture(gbuffer_, GL_COLOR_ATTACHMENT0, colourTex_, 0);
    glNamedFramebufferTexture(gbuffer_, GL_COLOR_ATTACHMENT1, normalTex_, 0);
    glNamedFramebufferTexture(gbuffer_, GL_DEPTH_ATTACHMENT, depthTex_, 0);
    const GLenum draw[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(gbuffer_, 2, draw);
    glCreateFramebuffers(1, &outputFbo_);
    glNamedFramebufferTexture(outputFbo_, GL_COLOR_ATTACHMENT0, outputTex_, 0);
    glCreateFramebuffers(1, &hqsFbo_);
    glNamedFramebufferTexture(hqsFbo_, GL_COLOR_ATTACHMENT0, accColourTex_, 0);
    glNamedFramebufferTexture(hqsFbo_, GL_COLOR_ATTACHMENT1, accNormalTex_, 0);
    glNamedFramebufferTexture(hqsFbo_, GL_DEPTH_ATTACHMENT, depthTex_, 0);
    glNamedFramebufferDrawBuffers(hqsFbo_, 2, draw);
    for (GLuint f : {gbuffer_, outputFbo_, hqsFbo_})
      if (glCheckNamedFramebufferStatus(f, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
        throw Error("the G-buffer framebuffer is incomplete (" + std::to_string(w) + "x" + std::to_string(h) + ")");
    w_ = w, h_ = h;
  }
  const size_t pixels = size_t(w) * h;
  if (compute && pixels > ssboPixels_) {
    NL_CHECK(pixels * 16 <= kMaxSsboBytes);
    GLuint bufs[] = {depthSsbo_, accumSsbo_, normalSsbo_, packedSsbo_, packedNormalSsbo_};
    glDeleteBuffers(5, bufs);
    glCreateBuffers(1, &depthSsbo_);
    glNamedBufferStorage(depthSsbo_, pixels * 4, nullptr, GL_DYNAMIC_STORAGE_BIT);
    glCreateBuffers(1, &accumSsbo_);
    glNamedBufferStorage(accumSsbo_, pixels * 16, nullptr, GL_DYNAMIC_STORAGE_BIT);
    glCreateBuffers(1, &normalSsbo_);
    glNamedBufferStorage(normalSsbo_, pixels * 4, nullptr, GL_DYNAMIC_STORAGE_BIT);
    packedSsbo_ = packedNormalSsbo_ = 0;
    if (atomic64_) {
      glCreateBuffers(1, &packedSsbo_);
      glNamedBufferStorage(packedSsbo_, pixels * 8, nullptr, GL_DYNAMIC_STORAGE_BIT);
      glCreateBuffers(1, &packedNormalSsbo_);
      glNamedBufferStorage(packedNormalSsbo_, pixels * 8, nullptr, GL_DYNAMIC_STORAGE_BIT);
    }
    ssboPixels_ = pixels;
  }
}

void FrameRenderer::drawTile(const std::vector<streaming::DrawNode>& nodes, const frame::GlNodeStore& store,
                             const Camera& camera, int fullW, int fullH, int x0, int y0, int w, int h,
                             const RenderSettings& s, DrawTimings* t) {
  const bool compute = s.rasteriser == Rasteriser::Compute;
  ensureTargets(w, h, compute);
  const glm::dmat4 clipFromView =
      tileFromClip(fullW, fullH, x0, y0, w, h) * camera.projection(double(fullW) / fullH);
  const glm::dmat4 viewFromCamRel = camera.viewRotation();
  const double pixelsPerUnit = fullH / (2.0 * std::tan(glm::radians(camera.fovYDegrees) * 0.5));

  glViewport(0, 0, w, h);
  const float clearColour[4] = {0, 0, 0, 0}, clearNormal[4] = {0, 0, 0, 0};
  const float clearDepth = 1.0f;
  glClearNamedFramebufferfv(gbuffer_, GL_COLOR, 0, clearColour);
  glClearNamedFramebufferfv(gbuffer_, GL_COLOR, 1, clearNormal);
  glClearNamedFramebufferfv(gbuffer_, GL_DEPTH, 0, &clearDepth);
  glBindVertexArray(vao_);

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
    const GLint offLoc = pass.uniform("uNodeOffset"), nLoc = pass.uniform("uNumPoints");
    for (const auto& n : nodes) {
      if (!n.numPoints) continue;
      const glm::vec3 off = nodeOffset(n);
      glProgramUniform3f(p, offLoc, off.x, off.y, off.z);
      glProgramUniform1ui(p, nLoc, n.numPoints);
      glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, store.buffer(n.handle), 0,
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
    const int guard = int(std::ceil(0.5 * (s.fixedPointSize > 0 ? s.fixedPointSize : s.maxPointSize))) + 1;
    const glm::dmat4 splatClipFromView = tileFromClip(fullW, fullH, x0 - guard, y0 - guard, w + 2 * guard,
                                                      h + 2 * guard) *
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
        glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, store.buffer(n.handle), 0,
                          GLsizeiptr(n.numPoints) * GLsizeiptr(frame::kGpuPointBytes));
        glDrawArrays(GL_POINTS, 0, GLsizei(n.numPoints));
        if (t && countPoints) t->points += n.numPoints;
      }
    };
    glEnable(GL_PROGRAM_POINT_SIZE);
    glEnable(GL_DEPTH_TEST);
    glViewport(-guard, -guard, w + 2 * guard, h + 2 * guard);
    if (!hqs) {
      glProgramUniform1i(points_.id(), points_.uniform("uRound"), s.roundPoints && s.fixedPointSize != 1.0f);
      glDepthFunc(GL_LESS);
      glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
      drawSplats(points_, true);
      glViewport(0, 0, w, h);
    } else {
      // Pass 1: depth pushed back by epsilon. Pass 2: weighted sums of what lies in front of it.
      glProgramUniform1f(hqsDepth_.id(), hqsDepth_.uniform("uDepthEpsilon"), s.hqsDepthEpsilon);
      glDepthFunc(GL_LESS);
      glBindFramebuffer(GL_FRAMEBUFFER, hqsFbo_);
      glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
      drawSplats(hqsDepth_, true);
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      const float zero[4] = {0, 0, 0, 0};
      glClearNamedFramebufferfv(hqsFbo_, GL_COLOR, 0, zero);
      glClearNamedFramebufferfv(hqsFbo_, GL_COLOR, 1, zero);
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
      glBindTextureUnit(0, accColourTex_);
      glBindTextureUnit(1, accNormalTex_);
      glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
      glDepthFunc(GL_ALWAYS);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glDisable(GL_DEPTH_TEST);
  } else if (atomic64_ && s.allowAtomic64) {
    // One pass: min over (depth << 32 | colour); all ones is "empty".
    const size_t pixels = size_t(w) * h;
    const uint32_t empty[2] = {0xffffffffu, 0xffffffffu};
    glClearNamedBufferSubData(packedSsbo_, GL_RG32UI, 0, pixels * 8, GL_RG_INTEGER, GL_UNSIGNED_INT, empty);
    glClearNamedBufferSubData(packedNormalSsbo_, GL_RG32UI, 0, pixels * 8, GL_RG_INTEGER, GL_UNSIGNED_INT, empty);
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 4, packedSsbo_, 0, GLsizeiptr(pixels * 8));
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 6, packedNormalSsbo_, 0, GLsizeiptr(pixels * 8));
    dispatchNodes(*atomic64_, true);
    const GLuint r = resolve64_->id();
    resolve64_->use();
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
    glClearNamedBufferSubData(depthSsbo_, GL_R32UI, 0, pixels * 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &far);
    glClearNamedBufferSubData(accumSsbo_, GL_R32UI, 0, pixels * 16, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glClearNamedBufferSubData(normalSsbo_, GL_R32UI, 0, pixels * 4, GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 1, depthSsbo_, 0, GLsizeiptr(pixels * 4));
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 2, accumSsbo_, 0, GLsizeiptr(pixels * 16));
    glBindBufferRange(GL_SHADER_STORAGE_BUFFER, 3, normalSsbo_, 0, GLsizeiptr(pixels * 4));
    dispatchNodes(depthPass_, true);
    dispatchNodes(colourPass_, false);
    const GLuint r = resolve_.id();
    resolve_.use();
    setMat4(r, "uClipFromView", clipFromView);
    setMat4(r, "uViewFromCamRel", viewFromCamRel);
    glProgramUniform2i(r, resolve_.uniform("uViewport"), w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer_);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_ALWAYS);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_DEPTH_TEST);
  }

  // Eye-dome lighting into the output.
  const GLuint e = edl_.id();
  edl_.use();
  glBindTextureUnit(0, colourTex_);
  glBindTextureUnit(1, depthTex_);
  glProgramUniform1i(e, edl_.uniform("uColour"), 0);
  glProgramUniform1i(e, edl_.uniform("uDepth"), 1);
  glProgramUniform1f(e, edl_.uniform("uNear"), float(camera.nearPlane));
  glProgramUniform1f(e, edl_.uniform("uFar"), float(camera.farPlane));
  glProgramUniform1f(e, edl_.uniform("uStrength"), s.edlStrength);
  glProgramUniform1f(e, edl_.uniform("uRadius"), s.edlRadius);
  glProgramUniform3f(e, edl_.uniform("uBackground"), s.background.x, s.background.y, s.background.z);
  glBindFramebuffer(GL_FRAMEBUFFER, outputFbo_);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

GLuint FrameRenderer::renderToTexture(const std::vector<streaming::DrawNode>& nodes, const frame::GlNodeStore& store,
                                      const Camera& camera, int width, int height, const RenderSettings& s,
                                      DrawTimings* t) {
  const auto t0 = std::chrono::steady_clock::now();
  drawTree_.upload(nodes);
  drawTile(nodes, store, camera, width, height, 0, 0, width, height, s, t);
  if (t) {
    glFinish();
    t->msDraw += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  }
  return outputTex_;
}

Image FrameRenderer::render(const std::vector<streaming::DrawNode>& nodes, const frame::GlNodeStore& store,
                            const Camera& camera, int width, int height, const RenderSettings& s, DrawTimings* t) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw Error("image size " + std::to_string(width) + "x" + std::to_string(height) + " is out of range");
  const auto t0 = std::chrono::steady_clock::now();
  drawTree_.upload(nodes);
  Image img;
  img.width = width, img.height = height;
  img.rgba.assign(size_t(width) * height * 4, 0.f);
  // Tiles overlap by a margin so eye-dome lighting sees its neighbours across tile borders.
  const int margin = int(std::ceil(s.edlRadius)) + 2;
  int tile = std::max(64, s.maxTile);
  while (size_t(tile + 2 * margin) * (tile + 2 * margin) * 16 > kMaxSsboBytes) tile /= 2;
  std::vector<float> px;
  for (int ty = 0; ty < height; ty += tile)
    for (int tx = 0; tx < width; tx += tile) {
      const int w = std::min(tile, width - tx), h = std::min(tile, height - ty);
      const bool single = w == width && h == height;
      const int mx0 = single ? 0 : std::max(0, tx - margin), my0 = single ? 0 : std::max(0, ty - margin);
      const int mx1 = single ? width : std::min(width, tx + w + margin),
                my1 = single ? height : std::min(height, ty + h + margin);
      const int mw = mx1 - mx0, mh = my1 - my0;
      // GL's rows go up; image rows go down: the tile's GL y range is flipped.
      const int glY0 = height - my1;
      drawTile(nodes, store, camera, width, height, mx0, glY0, mw, mh, s, t);
      px.resize(size_t(w_) * h_ * 4);
      glGetTextureImage(outputTex_, 0, GL_RGBA, GL_FLOAT, GLsizei(px.size() * sizeof(float)), px.data());
      for (int y = 0; y < h; ++y) {
        const int imgY = ty + y;
        const int glRow = (height - 1 - imgY) - glY0;
        for (int x = 0; x < w; ++x) {
          const float* src = &px[4 * (size_t(glRow) * w_ + (tx + x - mx0))];
          std::copy(src, src + 4, img.at(tx + x, imgY));
        }
      }
    }
  if (t) t->msDraw += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return img;
}

}  // namespace nestlight::viewer
