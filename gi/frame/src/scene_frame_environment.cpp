// The GI frame's environment: the scene's map or a video light probe's frame, uploaded as a
// mipmapped texture, and its irradiance on diffuse lobes as order-2 spherical harmonics
// (Ramamoorthi and Hanrahan 2001, "An Efficient Representation for Irradiance Environment
// Maps").
#include <algorithm>
#include <cstdio>

#include "nestlight/gi/frame/irradiance_sh.h"
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
}

}  // namespace nestlight::gi::frame_detail
