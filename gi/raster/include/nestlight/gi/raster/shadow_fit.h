// A directional light's shadow map fitted to what the camera sees. Spanning the whole scene, one
// mesh 1000 km from the scan makes every texel kilometres wide and the scan's shadows vanish; so
// the map covers the receivers (the objects' boxes that meet the camera's frustum, clipped to
// it), its depth range every caster whose footprint in the light's view overlaps them (casters
// out of view still cast into it). The rectangle moves in whole texels and its size in steps of
// a quarter octave, so the texel grid stays put in the world while the camera moves and edges
// do not shimmer.
#pragma once

#include <glm/glm.hpp>
#include <vector>

namespace nestlight::gi {

struct ShadowBox {
  glm::vec3 lo{0.0f}, hi{0.0f};
};

// The camera's frustum: its view (looking down -z) and a symmetric perspective.
struct ShadowFitCamera {
  glm::mat4 viewFromWorld{1.0f};
  float tanHalfFovY = 1, aspect = 1;  // aspect: width / height
  float nearZ = 0.1f, farZ = 1000.0f;
};

struct DirectionalShadowFit {
  glm::mat4 viewFromWorld{1.0f};  // the light's rotation alone: the same for every camera
  glm::mat4 clipFromWorld{1.0f};  // orthographic
  float texel = 0;                // world units per texel
  float nearZ = 0, farZ = 0;      // the orthographic depth range along the light
  bool fitted = false;            // false: the whole scene (no camera, or it sees nothing)
};

// `direction`: where the light travels; `objects`: every scan's and mesh's box; `camera`: null
// fits the whole scene. `mapSize`: texels per side.
DirectionalShadowFit fitDirectionalShadow(const glm::vec3& direction,
                                          const std::vector<ShadowBox>& objects,
                                          const ShadowFitCamera* camera, int mapSize);

}  // namespace nestlight::gi
