// The GI frame's lights and their shadow maps: a record per light, a shadow-map layer per
// light view (spot and directional one, point six cube faces), directional views fitted by
// shadow_fit.h to the camera's view or to the clusters of objects it sees, and the pass that
// draws the maps. Shadow maps are the classic technique (Williams 1978, "Casting Curved
// Shadows on Curved Surfaces").
#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

// One record per light; shadow-map layers: spot and directional one, point six (cube faces in
// the order shadowLayer() in shaders/gi/common/lights.glsl picks them).
void RasterMethod::setUpLights() {
  fitShadowsToCamera_ = !extension_ || extension_->shadowsForTheCameraOnly();
  for (const LocalBox& b : objectBounds_) shadowBoxes_.push_back({b.lo, b.hi});
  // Every cluster until the first frame's camera picks those it sees.
  if (!fitShadowsToCamera_) clusters_ = clusterObjects(shadowBoxes_);
  litClusters_.assign(clusters_.boxes.size(), true);
  litBounds_ = bounds_;
  if (scene_.lights.size() > NL_MAX_LIGHTS)
    throw Error(scene_.file.string(), "lights",
                "the raster method takes at most " + std::to_string(NL_MAX_LIGHTS) +
                    " lights; the scene has " + std::to_string(scene_.lights.size()));
  const glm::vec3 centre = bounds_.centre();
  const float R = std::max(bounds_.radius(), 1e-3f);
  const int S = params_.shadowMapSize;
  for (const Light& l : scene_.lights) {
    frame::LightRecord r{};
    const glm::vec3 pos = scene_.local(l.position);
    const glm::vec3 dir =
        glm::length(l.direction) > 0 ? glm::normalize(l.direction) : glm::vec3(0, 0, -1);
    const int type = l.type == LightType::Point  ? NL_LIGHT_POINT
                     : l.type == LightType::Spot ? NL_LIGHT_SPOT
                                                 : NL_LIGHT_DIRECTIONAL;
    r.position = glm::vec4(pos, float(type));
    r.direction = glm::vec4(dir, 0.0f);
    r.intensity = glm::vec4(l.intensity.r, l.intensity.g, l.intensity.b, 0.0f);
    r.cone = glm::vec4(std::cos(glm::radians(l.outerAngleDegrees)),
                       std::cos(glm::radians(l.innerAngleDegrees)), 0, 0);
    auto upFor = [](const glm::vec3& d) {
      return std::abs(d.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
    };
    const float farL = glm::length(pos - centre) + R * 1.01f;
    const float nearL = std::max(farL * 1e-4f, 1e-4f);
    r.shadow = glm::vec4(float(shadowViews_.size()), 0.0f, nearL, farL);
    if (type == NL_LIGHT_DIRECTIONAL && fitShadowsToCamera_) {
      // The whole scene until the first frame's camera refits it.
      const DirectionalShadowFit fit = fitDirectionalShadow(dir, shadowBoxes_, nullptr, S);
      shadowViews_.push_back(fit.clipFromWorld);
      shadowViewFromWorld_.push_back(fit.viewFromWorld);
      r.shadow.y = fit.texel;
      r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
    } else if (type == NL_LIGHT_DIRECTIONAL) {
      const DirectionalShadowFit fit =
          fitDirectionalToBox(dir, {bounds_.lo, bounds_.hi}, shadowBoxes_, S);
      shadowViews_.push_back(fit.clipFromWorld);
      shadowViewFromWorld_.push_back(fit.viewFromWorld);
      r.shadow.y = fit.texel;
      r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
    } else if (type == NL_LIGHT_SPOT) {
      // The outer cone plus a texel of margin, at most 170 degrees (beyond that a point light's
      // six views would serve better; the falloff still cuts the light at the cone).
      const float half = std::min(glm::radians(l.outerAngleDegrees) * 1.02f, glm::radians(85.0f));
      const glm::mat4 view = glm::lookAt(pos, pos + dir, upFor(dir));
      shadowViews_.push_back(glm::perspective(2 * half, 1.0f, nearL, farL) * view);
      shadowViewFromWorld_.push_back(view);
      r.shadow.y = 2 * std::tan(half) / float(S);
    } else {
      const glm::vec3 axes[6] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                 {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};
      for (const auto& a : axes) {
        const glm::mat4 view = glm::lookAt(pos, pos + a, upFor(a));
        shadowViews_.push_back(glm::perspective(glm::radians(90.0f), 1.0f, nearL, farL) * view);
        shadowViewFromWorld_.push_back(view);
      }
      r.shadow.y = 2.0f / float(S);
    }
    lightRecords_.push_back(r);
  }
  lightsBuffer_ = gl::Buffer(std::max<size_t>(lightRecords_.size(), 1) * sizeof(frame::LightRecord),
                             lightRecords_.empty() ? nullptr : lightRecords_.data());
  std::vector<glm::mat4> views = shadowViews_;
  if (views.empty()) views.emplace_back(1.0f);
  shadowViewsBuffer_ = gl::Buffer(views.size() * sizeof(glm::mat4), views.data());
}

// Directional lights' maps cover what this camera sees (shadow_fit.h); the shadow pass of the
// frame that follows draws them, and lookups read the texel size and views from the buffers.
void RasterMethod::fitShadowsToCamera(const ShadowFitCamera& camera) {
  bool changed = false;
  for (frame::LightRecord& r : lightRecords_) {
    if (int(r.position.w) != NL_LIGHT_DIRECTIONAL) continue;
    const size_t layer = size_t(r.shadow.x);
    const DirectionalShadowFit fit =
        fitDirectionalShadow(glm::vec3(r.direction), shadowBoxes_, &camera, params_.shadowMapSize);
    if (fit.clipFromWorld == shadowViews_[layer] && fit.texel == r.shadow.y) continue;
    shadowViews_[layer] = fit.clipFromWorld;
    shadowViewFromWorld_[layer] = fit.viewFromWorld;
    r.shadow.y = fit.texel;
    r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
    changed = true;
  }
  if (!changed) return;
  lightsBuffer_.upload(lightRecords_.data(), lightRecords_.size() * sizeof(frame::LightRecord));
  shadowViewsBuffer_.upload(shadowViews_.data(), shadowViews_.size() * sizeof(glm::mat4));
  ++lightViewsGeneration_;
}

// Extensions light beyond the camera's view, so their directional views span whole clusters:
// those the camera sees (a cluster it does not see lights them negligibly, shadow_fit.h's
// clusterObjects). Refitted only when that set changes, so the views (and what extensions
// derive from them) stay put while the camera moves within a cluster; a camera that sees none
// keeps the last set.
void RasterMethod::fitLightViewsToClusters(const ShadowFitCamera& camera) {
  std::vector<bool> seen(clusters_.boxes.size(), false);
  for (size_t i = 0; i < shadowBoxes_.size(); ++i)
    if (!seen[size_t(clusters_.of[i])] && meetsFrustum(shadowBoxes_[i], camera))
      seen[size_t(clusters_.of[i])] = true;
  if (seen == litClusters_ || std::find(seen.begin(), seen.end(), true) == seen.end()) return;
  litClusters_ = seen;
  litBounds_ = LocalBox{};
  for (size_t k = 0; k < seen.size(); ++k)
    if (seen[k]) litBounds_.add(clusters_.boxes[k].lo), litBounds_.add(clusters_.boxes[k].hi);
  for (frame::LightRecord& r : lightRecords_) {
    if (int(r.position.w) != NL_LIGHT_DIRECTIONAL) continue;
    const size_t layer = size_t(r.shadow.x);
    const DirectionalShadowFit fit =
        fitDirectionalToBox(glm::vec3(r.direction), {litBounds_.lo, litBounds_.hi}, shadowBoxes_,
                            params_.shadowMapSize);
    shadowViews_[layer] = fit.clipFromWorld;
    shadowViewFromWorld_[layer] = fit.viewFromWorld;
    r.shadow.y = fit.texel;
    r.shadow.z = fit.nearZ, r.shadow.w = fit.farZ;
  }
  lightsBuffer_.upload(lightRecords_.data(), lightRecords_.size() * sizeof(frame::LightRecord));
  shadowViewsBuffer_.upload(shadowViews_.data(), shadowViews_.size() * sizeof(glm::mat4));
  ++lightViewsGeneration_;
}

// The shadow maps, one layer per light view (spot and directional one, point six), meshes and
// the lights' cut of every scan.
void RasterMethod::addShadowMapPass() {
  const int S = params_.shadowMapSize;
  graph_.addPass(
      "shadow_maps", frame::Scope::Frame, [](frame::PassBuilder& b) { b.write("shadow_maps"); },
      [this, S](const frame::PassContext& ctx) {
        const gl::Texture& maps = ctx.target("shadow_maps");
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glDisable(GL_BLEND);
        glDisable(GL_CULL_FACE);
        glViewport(0, 0, S, S);
        // Slope-scaled offset for triangles (points take theirs in the lookup).
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(1.5f, 2.0f);
        for (size_t layer = 0; layer < shadowViews_.size(); ++layer) {
          shadowFbo_.attachLayer(GL_DEPTH_ATTACHMENT, maps, int(layer));
          if (layer == 0) shadowFbo_.finish(0, "shadow map");
          glBindFramebuffer(GL_FRAMEBUFFER, shadowFbo_.id());
          const float one = 1.0f;
          glClearBufferfv(GL_DEPTH, 0, &one);
          const glm::mat4& clip = shadowViews_[layer];
          drawMeshes(meshShadow_, clip, false);
          // Which light owns the layer: its projection sizes the splats.
          const frame::LightRecord* owner = nullptr;
          for (const auto& r : lightRecords_)
            if (size_t(r.shadow.x) <= layer) owner = &r;
          NL_CHECK(owner != nullptr);
          const bool ortho = int(owner->position.w) == NL_LIGHT_DIRECTIONAL;
          // Texels per world unit (orthographic) or per unit at distance 1 (perspective).
          drawScans(scanShadow_, clip, shadowViewFromWorld_[layer], 1.0f / owner->shadow.y, ortho,
                    true);
        }
        glDisable(GL_POLYGON_OFFSET_FILL);
      });
}

}  // namespace nestlight::gi::frame_detail
