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

// Whether any of `box` may lie in the camera's frustum (conservative: a box across a frustum's
// edge may pass).
bool meetsFrustum(const ShadowBox& box, const ShadowFitCamera& camera);

// The scene's objects in clusters that light one another: two objects join when the gap between
// their boxes is at most `reach` times the larger box's diagonal, and clusters are the connected
// groups (single linkage). Across a gap of 10 diagonals a box subtends under pi / 400 sr, so it
// adds under 1/400 of the irradiance a surrounding surface of its radiance would: a cluster that
// far lights another negligibly (and less with distance, by the inverse square law).
struct ObjectClusters {
  std::vector<int> of;           // each object's cluster
  std::vector<ShadowBox> boxes;  // each cluster's bounds
};
constexpr float kClusterReach = 10;
ObjectClusters clusterObjects(const std::vector<ShadowBox>& objects, float reach = kClusterReach);

// A directional light's fixed view over `lit` (the clusters a method lights, which may lie
// beyond the camera's view): an orthographic view of `lit`'s bounding sphere, its depth range
// taken towards the light to every box of `objects` whose footprint in the light's view overlaps
// the sphere's (a cluster between the light and `lit` still casts into it). `direction`: where
// the light travels, normalised. With `lit` the scene's bounds and nothing beyond them it is the
// view a scene-wide map always had.
DirectionalShadowFit fitDirectionalToBox(const glm::vec3& direction, const ShadowBox& lit,
                                         const std::vector<ShadowBox>& objects, int mapSize);

}  // namespace nestlight::gi
