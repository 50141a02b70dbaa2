// The splatting passes (nestlight/frame/point_splatting.h): high-quality splatting after Botsch,
// Hornung, Zwicker, Kobbelt, "High-Quality Surface Splatting on Today's GPUs", 2005, section 3;
// the compute rasteriser after Schütz, Kerbl, Wimmer, "Rendering Point Clouds with Compute
// Shaders and Vertex Order Optimization", 2021.
#include "nestlight/frame/point_splatting.h"

#include <cstdio>
#include <string>
#include <utility>

#include "nestlight/frame/interface.h"
#include "nestlight/octree/error.h"

namespace nestlight::frame {

namespace {

using Defines = std::vector<std::pair<std::string, std::string>>;

gl::ShaderProgram splatProgram(const char* fragment, const Defines& d) {
  return gl::ShaderProgram(
      {{GL_VERTEX_SHADER, "points/points.vert"}, {GL_FRAGMENT_SHADER, fragment}}, d);
}

gl::ShaderProgram fullscreenProgram(const char* fragment, const Defines& d) {
  return gl::ShaderProgram(
      {{GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, fragment}}, d);
}

}  // namespace

PointSplatting::PointSplatting(SplatFrame frame, bool compute) : frame_(frame) {
  // The point view compiles the files as they are (NL_SCENE_FRAME defaults to 0).
  const Defines d = frame == SplatFrame::Scene ? Defines{{"NL_SCENE_FRAME", "1"}} : Defines{};
  basic_ = splatProgram("points/points.frag", d);
  hqsDepth_ = splatProgram("points/hqs_depth.frag", d);
  hqsAccum_ = splatProgram("points/hqs_accum.frag", d);
  hqsResolve_ = fullscreenProgram("points/hqs_resolve.frag", d);
  emptyVao_ = gl::VertexArray::create();
  if (!compute) return;
  computeDepth_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "points/raster_depth.comp"}}, d);
  computeColour_ = gl::ShaderProgram({{GL_COMPUTE_SHADER, "points/raster_colour.comp"}}, d);
  computeResolve_ = fullscreenProgram("points/raster_resolve.frag", d);
  if (frame != SplatFrame::PointView || !epoxy_has_gl_extension("GL_NV_shader_atomic_int64") ||
      !epoxy_has_gl_extension("GL_ARB_gpu_shader_int64"))
    return;
  try {
    atomic64_ = std::make_unique<gl::ShaderProgram>(
        std::vector<gl::ShaderProgram::Stage>{{GL_COMPUTE_SHADER, "points/raster_atomic64.comp"}});
    resolve64_ =
        std::make_unique<gl::ShaderProgram>(fullscreenProgram("points/raster_resolve64.frag", {}));
  } catch (const Error& e) {
    // A driver that offers the extension but rejects the shader: the 32-bit path still works.
    std::fprintf(stderr, "nestlight: 64-bit compute rasteriser unavailable, using two passes: %s\n",
                 e.what());
    atomic64_.reset();
    resolve64_.reset();
  }
}

PointSplatting::~PointSplatting() = default;

void PointSplatting::hqs(const HqsTargets& t, float depthEpsilon, const glm::mat4& clipFromView,
                         const DrawSplats& draw) const {
  // Pass 1: depth pushed back by epsilon splat radii.
  glProgramUniform1f(hqsDepth_.id(), hqsDepth_.uniform("uDepthEpsilon"), depthEpsilon);
  glDepthFunc(GL_LESS);
  glBindFramebuffer(GL_FRAMEBUFFER, t.depthFbo);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  draw(hqsDepth_, true);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  // Pass 2: weighted sums of what lies in front of it.
  const float zero[4] = {0, 0, 0, 0};
  for (int k = 0; k < t.sums; ++k) glClearNamedFramebufferfv(t.sumFbo, GL_COLOR, k, zero);
  glBindFramebuffer(GL_FRAMEBUFFER, t.sumFbo);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  draw(hqsAccum_, false);
  glDisable(GL_BLEND);
  glDepthMask(GL_TRUE);
  // Pass 3: the means into the G-buffer, depth included (pixels no splat covered keep theirs).
  glViewport(0, 0, t.width, t.height);
  const GLuint r = hqsResolve_.id();
  hqsResolve_.use();
  glProgramUniformMatrix4fv(r, hqsResolve_.uniform("uClipFromView"), 1, GL_FALSE,
                            &clipFromView[0][0]);
  for (size_t i = 0; i < t.sumTextures.size(); ++i) glBindTextureUnit(GLuint(i), t.sumTextures[i]);
  glBindFramebuffer(GL_FRAMEBUFFER, t.gbufferFbo);
  glDepthFunc(t.resolveDepthFunc);
  glBindVertexArray(emptyVao_.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void PointSplatting::prepareBuffers(size_t pixels, bool atomic64) {
  NL_CHECK(pixels * 16 <= gl::kMaxSsboRange);
  if (atomic64) {
    // min over (depth << 32 | colour); all ones is "empty".
    packed_.reserve(pixels * 8);
    packedNormal_.reserve(pixels * 8);
    const uint32_t empty[2] = {0xffffffffu, 0xffffffffu};
    for (const gl::Buffer* b : {&packed_, &packedNormal_})
      glClearNamedBufferSubData(b->id(), GL_RG32UI, 0, GLsizeiptr(pixels * 8), GL_RG_INTEGER,
                                GL_UNSIGNED_INT, empty);
    packed_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_PACKED, 0, pixels * 8);
    packedNormal_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_RASTER_PACKED_NORMAL, 0, pixels * 8);
    return;
  }
  const bool scene = frame_ == SplatFrame::Scene;
  depth_.reserve(pixels * 4);
  accum_.reserve(pixels * 16);
  normal_.reserve(pixels * 4);
  if (scene) radius_.reserve(pixels * 4);
  const uint32_t far = 0xffffffffu, zero = 0;
  glClearNamedBufferSubData(depth_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 4), GL_RED_INTEGER,
                            GL_UNSIGNED_INT, &far);
  glClearNamedBufferSubData(accum_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 16), GL_RED_INTEGER,
                            GL_UNSIGNED_INT, &zero);
  glClearNamedBufferSubData(normal_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 4), GL_RED_INTEGER,
                            GL_UNSIGNED_INT, &zero);
  if (scene)
    glClearNamedBufferSubData(radius_.id(), GL_R32UI, 0, GLsizeiptr(pixels * 4), GL_RED_INTEGER,
                              GL_UNSIGNED_INT, &zero);
  // The GI frame's at its method bindings, clear of the lights and shadow views it keeps bound
  // (shaders/points/raster_common.glsl).
  depth_.bindRange(GL_SHADER_STORAGE_BUFFER, scene ? NL_SSBO_SCAN_DEPTH : NL_SSBO_RASTER_DEPTH, 0,
                   pixels * 4);
  accum_.bindRange(GL_SHADER_STORAGE_BUFFER, scene ? NL_SSBO_SCAN_ACCUM : NL_SSBO_RASTER_ACCUM, 0,
                   pixels * 16);
  normal_.bindRange(GL_SHADER_STORAGE_BUFFER, scene ? NL_SSBO_SCAN_NORMAL : NL_SSBO_RASTER_NORMAL,
                    0, pixels * 4);
  if (scene) radius_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_SCAN_RADIUS, 0, pixels * 4);
}

void PointSplatting::resolve(const gl::ShaderProgram& program,
                             const ResolveUniforms& uniforms) const {
  program.use();
  uniforms(program);
  glBindVertexArray(emptyVao_.id());
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

void PointSplatting::compute(int width, int height, bool atomic64, GLuint gbufferFbo,
                             GLenum resolveDepthFunc, const DrawSplats& dispatch,
                             const ResolveUniforms& resolveUniforms) {
  const bool one = atomic64 && atomic64_;
  prepareBuffers(size_t(width) * size_t(height), one);
  if (one) {
    dispatch(*atomic64_, true);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  } else {
    dispatch(computeDepth_, true);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    dispatch(computeColour_, false);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, gbufferFbo);
  glViewport(0, 0, width, height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(resolveDepthFunc);
  resolve(one ? *resolve64_ : computeResolve_, resolveUniforms);
}

}  // namespace nestlight::frame
