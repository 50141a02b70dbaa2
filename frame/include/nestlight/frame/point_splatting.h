// The splatting passes every renderer of points draws with (shaders/points/): basic splats (the
// nearest wins), high-quality splatting (Botsch, Hornung, Zwicker, Kobbelt, "High-Quality
// Surface Splatting on Today's GPUs", 2005, section 3), and the compute rasteriser (Schütz,
// Kerbl, Wimmer, "Rendering Point Clouds with Compute Shaders and Vertex Order Optimization",
// 2021) with its two-pass 32-bit and one-pass 64-bit variants. The point view and the GI frame's
// scan G-buffer both run them; each brings its own nodes and vertex uniforms (a draw callback)
// and its own G-buffer, the passes' order and GL state are here once.
#pragma once

#include <epoxy/gl.h>

#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "nestlight/gl/program.h"
#include "nestlight/gl/resources.h"

namespace nestlight::frame {

// The frame the splats are drawn in (shaders/points/splat_frame.glsl's NL_SCENE_FRAME).
enum class SplatFrame {
  // Positions relative to the eye; a G-buffer of linear colour and view-space normal.
  PointView,
  // Positions in the scene's local frame, splats as discs in their tangent planes; the GI
  // frame's G-buffer (shaders/gi/common/gbuffer_out.glsl) over the meshes already in it.
  Scene,
};

class PointSplatting {
 public:
  // `compute`: the compute rasteriser's programs too; for the point view also its 64-bit variant
  // where the driver offers 64-bit atomics (and compiles them).
  PointSplatting(SplatFrame frame, bool compute);
  ~PointSplatting();
  PointSplatting(const PointSplatting&) = delete;
  PointSplatting& operator=(const PointSplatting&) = delete;

  // The programs whose vertex stage is shaders/points/points.vert: a draw sets their uniforms.
  const gl::ShaderProgram& basic() const { return basic_; }
  const gl::ShaderProgram& hqsDepth() const { return hqsDepth_; }
  const gl::ShaderProgram& hqsAccum() const { return hqsAccum_; }
  bool hasAtomic64() const { return atomic64_ != nullptr; }

  // Draws (or dispatches) every splat with `program`; `first`: the frame's first pass over the
  // points (where a caller counts them).
  using DrawSplats = std::function<void(const gl::ShaderProgram& program, bool first)>;
  // Sets a resolve program's uniforms (uViewport, uClipFromView and the frame's own).
  using ResolveUniforms = std::function<void(const gl::ShaderProgram& program)>;

  // High-quality splatting's three passes. The caller has enabled the depth test and program
  // point sizes and set the (guard-banded) viewport of the splats; pass 3 draws at width x height.
  struct HqsTargets {
    GLuint depthFbo = 0;  // pass 1: depth only (colour writes masked)
    GLuint sumFbo = 0;    // pass 2: the sums at its first `sums` colour attachments, same depth
    int sums = 2;
    std::vector<GLuint> sumTextures;  // pass 3 reads them at texture units 0, 1, ...
    GLuint gbufferFbo = 0;            // pass 3 writes the means here
    // Pass 3's depth test: GL_ALWAYS where the G-buffer holds splats alone, GL_LESS to keep
    // nearer meshes.
    GLenum resolveDepthFunc = GL_ALWAYS;
    int width = 0, height = 0;
  };
  void hqs(const HqsTargets& targets, float depthEpsilon, const glm::mat4& clipFromView,
           const DrawSplats& draw) const;

  // The compute rasteriser into `gbufferFbo` (bound, with the depth test and `resolveDepthFunc`,
  // for the resolve) at width x height: the 64-bit variant when `atomic64` and available, else
  // the 32-bit one. Its per-pixel buffers are cleared and bound here.
  void compute(int width, int height, bool atomic64, GLuint gbufferFbo, GLenum resolveDepthFunc,
               const DrawSplats& dispatch, const ResolveUniforms& resolveUniforms);

 private:
  void prepareBuffers(size_t pixels, bool atomic64);
  void resolve(const gl::ShaderProgram& program, const ResolveUniforms& uniforms) const;

  SplatFrame frame_;
  gl::ShaderProgram basic_, hqsDepth_, hqsAccum_, hqsResolve_;
  gl::ShaderProgram computeDepth_, computeColour_, computeResolve_;
  std::unique_ptr<gl::ShaderProgram> atomic64_, resolve64_;  // only with 64-bit atomics
  gl::VertexArray emptyVao_;
  // The compute rasteriser's per-pixel buffers: 32-bit depth, colour sums (16 bytes), normal,
  // and for the scene its radius; 64-bit min(depth << 32 | colour) and min(depth << 32 | normal).
  gl::Buffer depth_, accum_, normal_, radius_, packed_, packedNormal_;
};

}  // namespace nestlight::frame
