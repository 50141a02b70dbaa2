// Importance-warped VPLs: Preiner, "Real-Time Global Illumination in Point Clouds" (the light
// G-buffer, Halton VPLs with hierarchical warping). Warping: Clarberg, Jarosz, Akenine-Moeller and
// Jensen 2005, "Wavelet Importance Sampling".
#include <algorithm>

#include "nestlight/frame/passes.h"
#include "nestlight/octree/error.h"
#include "vpl_extension.h"

namespace nestlight::gi::vpl {

ImportanceWarp::ImportanceWarp()
    : pyramid_({{GL_COMPUTE_SHADER, "gi/vpl/vpl_pyramid.comp"}}),
      warp_({{GL_COMPUTE_SHADER, "gi/vpl/vpl_warp.comp"}}) {}

// `levels` holds level 0 of every layer (pyramidLayerFloats(size) floats per layer): fills the
// levels above, then warps `count` Halton points into `samples`.
void ImportanceWarp::run(const gl::Buffer& levels, int size, int layers, int count,
                         gl::Buffer& samples) const {
  levels.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, levels.bytes());
  pyramid_.use();
  glUniform1i(pyramid_.uniform("uSize"), size);
  for (int level = 1; (size >> level) >= 1; ++level) {
    glUniform1i(pyramid_.uniform("uLevel"), level);
    const GLuint g = GLuint(((size >> level) + 7) / 8);
    glDispatchCompute(g, g, GLuint(layers));
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  samples.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_SAMPLES, 0,
                    size_t(count) * sizeof(WarpSample));
  warp_.use();
  glUniform1i(warp_.uniform("uSize"), size);
  glUniform1i(warp_.uniform("uLayers"), layers);
  glUniform1i(warp_.uniform("uCount"), count);
  glUniform1i(warp_.uniform("uFirstIndex"), 1);
  glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

// The light G-buffer and the warped samples on it.
void VplExtension::addLightPasses(SceneFrame& f, const char* const (&lightTargets)[4]) {
  frame::FrameGraph& g = f.graph();
  const int G = params_.lightResolution, layers = std::max(layers_, 1);
  g.addTarget("light_depth", {GL_DEPTH_COMPONENT32F, true, G, G, layers});
  g.addTarget("light_base", {GL_RGBA32F, true, G, G, layers});
  g.addTarget("light_normal", {GL_RGBA16F, true, G, G, layers});
  g.addTarget("light_material", {GL_RGBA16UI, true, G, G, layers});
  g.addBuffer("vpl_samples");

  // The light G-buffer: every light's views (the shadow maps' projections) of the meshes and
  // the lights' cut, with the camera G-buffer's shaders and encoding.
  g.addPass(
      "light_gbuffer", frame::Scope::Frame,
      [&](frame::PassBuilder& b) {
        for (const char* t : lightTargets) b.write(t);
      },
      [this, &f, G](const frame::PassContext& ctx) {
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glDisable(GL_BLEND);
        glDisable(GL_CULL_FACE);
        glViewport(0, 0, G, G);
        const int S = f.frameParameters().shadowMapSize;
        for (int layer = 0; layer < layers_; ++layer) {
          lightFbo_.attachLayer(GL_COLOR_ATTACHMENT0, ctx.target("light_base"), layer);
          lightFbo_.attachLayer(GL_COLOR_ATTACHMENT1, ctx.target("light_normal"), layer);
          lightFbo_.attachLayer(GL_COLOR_ATTACHMENT2, ctx.target("light_material"), layer);
          lightFbo_.attachLayer(GL_DEPTH_ATTACHMENT, ctx.target("light_depth"), layer);
          lightFbo_.finish(3, "light G-buffer");
          glBindFramebuffer(GL_FRAMEBUFFER, lightFbo_.id());
          frame::clearGBuffer();
          const glm::mat4& clip = f.lightClipFromWorld()[size_t(layer)];
          f.drawMeshes(meshGBuffer_, clip, true);
          const frame::LightRecord& l = f.lights()[size_t(layerOwner_[size_t(layer)])];
          const bool ortho = int(l.position.w) == NL_LIGHT_DIRECTIONAL;
          // Texels per unit at distance 1 (or per world unit): the shadow map's, rescaled.
          const float pixelsPerUnit = float(G) / (l.shadow.y * float(S));
          f.drawScans(scanGBuffer_, clip, f.lightViewFromWorld()[size_t(layer)], pixelsPerUnit,
                      ortho, true);
        }
      });

  // Importance, its pyramid and the warped Halton samples.
  g.addPass(
      "vpl_warp", frame::Scope::Frame,
      [&](frame::PassBuilder& b) {
        for (const char* t : lightTargets) b.read(t);
        b.write("vpl_samples");
      },
      [this, &f, G, layers](const frame::PassContext& ctx) {
        bindCommon(f);
        bindLightTextures(ctx);
        pyramid_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, pyramid_.bytes());
        importance_.use();
        glUniform1i(importance_.uniform("uLayerStride"), int(pyramidLayerFloats(G)));
        if (layers_ > 0) {
          glDispatchCompute(GLuint((G + 7) / 8), GLuint((G + 7) / 8), GLuint(layers_));
        } else {
          const float zero = 0;
          glClearNamedBufferData(pyramid_.id(), GL_R32F, GL_RED, GL_FLOAT, &zero);
        }
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        warp_->run(pyramid_, G, layers, params_.count, samples_);
      });
}

void VplExtension::bindLightTextures(const frame::PassContext& ctx) const {
  ctx.bindTexture("light_depth", 0);
  ctx.bindTexture("light_base", 1);
  ctx.bindTexture("light_normal", 2);
  ctx.bindTexture("light_material", 3);
}

// Radiance-cache mode: the first generation drawn on the scans' emitting points, by luminance x
// area (hierarchical warping over the pool laid out as a square). Without inserted objects
// there is nothing for them to light (scan pixels take no indirect light in this mode).
void VplExtension::emitFromScans() {
  const bool any = scanPoints_ > 0 && surfelPoints_.size() > 0;
  if (!any) {
    std::vector<VplRecord> dark(size_t(params_.count));
    records_.upload(dark.data(), dark.size() * sizeof(VplRecord), 0);
    return;
  }
  const float zero = 0;
  glClearNamedBufferData(emitPyramid_.id(), GL_R32F, GL_RED, GL_FLOAT, &zero);
  pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
  emitPyramid_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_PYRAMID, 0, emitPyramid_.bytes());
  emitImportance_.use();
  glUniform1i(emitImportance_.uniform("uScanPoints"), int(scanPoints_));
  glDispatchCompute(GLuint((scanPoints_ + 127) / 128), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  warp_->run(emitPyramid_, emitSide_, 1, params_.count, samples_);
  samples_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_SAMPLES, 0, samples_.bytes());
  records_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_RECORDS, 0, records_.bytes());
  pool_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_POOL, 0, pool_.bytes());
  emit_.use();
  glUniform1i(emit_.uniform("uCount"), params_.count);
  glUniform1i(emit_.uniform("uSide"), emitSide_);
  const glm::vec3 c = 0.5f * (objectsLo_ + objectsHi_);
  glUniform3f(emit_.uniform("uObjectsCentre"), c.x, c.y, c.z);
  glDispatchCompute(GLuint((params_.count + 63) / 64), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
}

}  // namespace nestlight::gi::vpl

namespace nestlight::gi {

std::vector<WarpedSample> warpImportanceOnGpu(const std::vector<float>& importance, int size,
                                              int layers, int count) {
  NL_CHECK(size > 0 && (size & (size - 1)) == 0 && layers > 0 && count > 0);
  NL_CHECK(importance.size() == size_t(size) * size_t(size) * size_t(layers));
  const size_t stride = vpl::pyramidLayerFloats(size);
  std::vector<float> levels(stride * size_t(layers), 0.0f);
  for (int l = 0; l < layers; ++l)
    std::copy(importance.begin() + ptrdiff_t(size_t(l) * size * size),
              importance.begin() + ptrdiff_t(size_t(l + 1) * size * size),
              levels.begin() + ptrdiff_t(size_t(l) * stride));
  gl::Buffer pyramid(levels.size() * 4, levels.data());
  gl::Buffer samples(size_t(count) * sizeof(vpl::WarpSample));
  vpl::ImportanceWarp warp;
  warp.run(pyramid, size, layers, count, samples);
  std::vector<vpl::WarpSample> raw(static_cast<size_t>(count));
  glGetNamedBufferSubData(samples.id(), 0, GLsizeiptr(raw.size() * sizeof(vpl::WarpSample)),
                          raw.data());
  std::vector<WarpedSample> out;
  for (const auto& r : raw) {
    WarpedSample s;
    s.x = r.texel.x, s.y = r.texel.y, s.layer = r.texel.z, s.valid = r.texel.w == 1,
    s.probability = r.where.z;
    out.push_back(s);
  }
  return out;
}

}  // namespace nestlight::gi
