// The GI frame's environment: the scene's map or a video light probe's frame, uploaded as a
// mipmapped texture, its irradiance on diffuse lobes as order-2 spherical harmonics
// (Ramamoorthi and Hanrahan 2001, "An Efficient Representation for Irradiance Environment
// Maps"), and for glossy lobes prefiltered by roughness with the split sum's table (Karis 2013,
// "Real Shading in Unreal Engine 4"; nestlight/gi/frame/split_sum.h).
#include <algorithm>
#include <cstdio>

#include "nestlight/gi/frame/irradiance_sh.h"
#include "nestlight/gi/frame/split_sum.h"
#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

void RasterMethod::bindEnvironment(const gl::ShaderProgram& program) const {
  glBindTextureUnit(5, environment_ ? environment_.id() : 0);
  glUniform1i(program.uniform("uHasEnvironment"), hasEnvironment_ ? 1 : 0);
  glUniform1f(program.uniform("uEnvRotation"), envRotation_);
  glUniform1f(program.uniform("uEnvScale"), envScale_);
  glUniform3fv(program.uniform("uEnvSh"), 9, &sh_[0].x);
}

void RasterMethod::setUpEnvironment() {
  if (!scene_.environment) return;
  envSource_ = std::make_unique<EnvironmentSource>(scene_.environment);
  // A sequence lights every frame, even if its first is black: extensions plan for a sky.
  uploadEnvironment(envSource_->at(0), envSource_->isSequence());
  envFrame_ = 0;
}

// The frame of a video light probe that `camera.time` plays, uploaded when it changes.
void RasterMethod::selectEnvironment(const SceneCamera& camera) {
  if (!envSource_ || !envSource_->isSequence()) return;
  const size_t frame = envSource_->frameAt(camera.time);
  if (frame == envFrame_) return;
  uploadEnvironment(envSource_->at(camera.time), true);
  envFrame_ = frame;
}

void RasterMethod::uploadEnvironment(std::shared_ptr<const EnvironmentMap> map, bool sequence) {
  envMap_ = std::move(map);
  const EnvironmentMap& env = *envMap_;
  // What the path tracer says of a map, every GL method (they all light through this frame)
  // says too: texels it cannot use are black, not silently.
  if ((env.invalidTexels() || (env.black() && env.image().pixels() > 0)) && scene_.environment) {
    const auto& e = *scene_.environment;
    std::string what = (e.sequence.empty() ? e.path : e.sequence).string() + ": environment";
    if (env.invalidTexels())
      what +=
          ": " + std::to_string(env.invalidTexels()) + " NaN, infinite or negative texels set to 0";
    if (env.black())
      what += std::string(env.invalidTexels() ? ";" : ":") + " all black, it adds no light";
    if (what != lastEnvWarning_) std::fprintf(stderr, "nestlight: warning: %s\n", what.c_str());
    lastEnvWarning_ = what;
  }
  envGeneration_++;
  hasEnvironment_ = sequence || !env.black();
  envRotation_ = glm::radians(env.rotationDegrees());
  envScale_ = env.scale();
  sh_ = irradianceSh(env);
  const HdrImage& img = env.image();
  const std::vector<float> rgba = img.rgba();
  // Mip levels for lookups averaged over a solid angle (environment.glsl's environmentOver: a
  // GI method's micro-buffer m-pixel, which point samples would alias on a small bright sun).
  int levels = 1;
  while ((std::max(img.width, img.height) >> levels) > 0) ++levels;
  if (!environment_ || environment_.width() != img.width || environment_.height() != img.height) {
    environment_ = gl::Texture(GL_RGBA32F, img.width, img.height, levels);
    environment_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
  }
  glTextureSubImage2D(environment_.id(), 0, 0, 0, img.width, img.height, GL_RGBA, GL_FLOAT,
                      rgba.data());
  glGenerateTextureMipmap(environment_.id());
  if (hasEnvironment_) prefilterEnvironment();
}

namespace {
// Roughness 0.2, 0.4, ... 1: linear steps in roughness, as Karis 2013 spaces its mip levels.
constexpr int kPrefilteredLevels = 5;
// The first level's width: 1.4 degrees a texel, a third of roughness 0.2's lobe (alpha 0.04) at
// half maximum. Each later level halves it, as its lobe widens.
constexpr int kPrefilteredWidth = 256;
// Half vectors a texel: with filtered importance sampling each reads the mip level of its share
// of the lobe, so 64 leave no visible noise (Krivanek and Colbert 2008 use 24 to 40).
constexpr int kPrefilterSamples = 64;
constexpr int kSplitSumSize = 32;
}  // namespace

void RasterMethod::prefilterEnvironment() {
  if (envPrefilter_.id() == 0)
    envPrefilter_ =
        gl::ShaderProgram({{GL_COMPUTE_SHADER, "gi/common/environment_prefilter.comp"}});
  if (!splitSumTable_) {
    const SplitSumTable t = splitSumTable(kSplitSumSize);
    splitSumTable_ = gl::Texture(GL_RG32F, t.size, t.size);
    glTextureSubImage2D(splitSumTable_.id(), 0, 0, 0, t.size, t.size, GL_RG, GL_FLOAT, t.ab.data());
    splitSumTable_.setFilter(GL_LINEAR, GL_LINEAR);
    glTextureParameteri(splitSumTable_.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(splitSumTable_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  if (!envPrefiltered_) {
    // RGBA32F: a sun beyond half-float range stays finite through the filter.
    envPrefiltered_ =
        gl::Texture(GL_RGBA32F, kPrefilteredWidth, kPrefilteredWidth / 2, kPrefilteredLevels);
    envPrefiltered_.setFilter(GL_LINEAR_MIPMAP_LINEAR, GL_LINEAR);
    glTextureParameteri(envPrefiltered_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  envPrefilter_.use();
  bindEnvironment(envPrefilter_);
  glUniform1i(envPrefilter_.uniform("uSamples"), kPrefilterSamples);
  for (int level = 0; level < kPrefilteredLevels; ++level) {
    const int w = std::max(kPrefilteredWidth >> level, 2), h = std::max(w / 2, 1);
    glUniform1f(envPrefilter_.uniform("uRoughness"), float(level + 1) / kPrefilteredLevels);
    glBindImageTexture(0, envPrefiltered_.id(), level, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glDispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
  }
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
}

void RasterMethod::bindEnvironmentSpecular(const gl::ShaderProgram& program) const {
  glBindTextureUnit(6, envPrefiltered_ ? envPrefiltered_.id() : 0);
  glBindTextureUnit(7, splitSumTable_ ? splitSumTable_.id() : 0);
  glUniform1i(program.uniform("uEnvPrefilteredLevels"), kPrefilteredLevels);
}

}  // namespace nestlight::gi::frame_detail
