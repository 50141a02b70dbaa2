// Directional shadow maps fitted to the camera's receivers (nestlight/gi/frame/shadow_fit.h),
// stabilised as cascaded shadow maps are (Valient 2008, "Stable Rendering of Cascaded Shadow
// Maps"): a fixed light rotation, the origin snapped to texels, the size quantised. The scene's
// objects grouped by single linkage (Sibson 1973, "SLINK: An optimally efficient algorithm for
// the single-link cluster method") for the light views of methods that light beyond the view.
#include "nestlight/gi/frame/shadow_fit.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace nestlight::gi {

namespace {

// Texels of margin on each side: the 3 x 3 PCF and the normal offset of lights.glsl's lookups
// reach up to about three texels beyond a receiver.
constexpr float kPadTexels = 4;

struct Bounds {
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  void add(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y); }
};

glm::vec3 corner(const glm::vec3& lo, const glm::vec3& hi, int c) {
  return {(c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z};
}

Bounds transformed(const glm::mat4& m, const glm::vec3& lo, const glm::vec3& hi) {
  Bounds b;
  for (int c = 0; c < 8; ++c) b.add(glm::vec3(m * glm::vec4(corner(lo, hi, c), 1.0f)));
  return b;
}

// The part of `box` (world) inside the camera's frustum, bounded in the light's view: the box's
// light-space bounds intersected with those of the frustum's slice between the box's nearest
// and farthest depths. Both bound the intersection, so theirs does too; exact clipping would be
// tighter only for boxes that cross the frustum's sides obliquely. Empty when the box is outside.
Bounds visiblePart(const ShadowBox& box, const ShadowFitCamera& cam,
                   const glm::mat4& lightFromWorld) {
  glm::vec3 v[8];
  float dMin = INFINITY, dMax = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    v[c] = glm::vec3(cam.viewFromWorld * glm::vec4(corner(box.lo, box.hi, c), 1.0f));
    dMin = std::min(dMin, -v[c].z);
    dMax = std::max(dMax, -v[c].z);
  }
  const float tx = cam.tanHalfFovY * cam.aspect, ty = cam.tanHalfFovY;
  // Outside when every corner is beyond one of the six planes (conservative: a box across a
  // frustum's edge can pass; the slice below then bounds it).
  auto allBeyond = [&](auto beyond) {
    for (const auto& p : v)
      if (!beyond(p)) return false;
    return true;
  };
  if (allBeyond([&](const glm::vec3& p) { return p.x > -p.z * tx; }) ||
      allBeyond([&](const glm::vec3& p) { return -p.x > -p.z * tx; }) ||
      allBeyond([&](const glm::vec3& p) { return p.y > -p.z * ty; }) ||
      allBeyond([&](const glm::vec3& p) { return -p.y > -p.z * ty; }))
    return {};
  const float d0 = std::max(cam.nearZ, dMin), d1 = std::min(cam.farZ, dMax);
  if (!(d0 <= d1)) return {};
  const glm::mat4 lightFromView = lightFromWorld * glm::inverse(cam.viewFromWorld);
  Bounds slice;
  for (int c = 0; c < 8; ++c) {
    const float d = (c & 4) ? d1 : d0;
    const glm::vec3 p((c & 1) ? d * tx : -d * tx, (c & 2) ? d * ty : -d * ty, -d);
    slice.add(glm::vec3(lightFromView * glm::vec4(p, 1.0f)));
  }
  Bounds b = transformed(lightFromWorld, box.lo, box.hi);
  b.lo = glm::vec3(glm::max(glm::vec2(b.lo), glm::vec2(slice.lo)), b.lo.z);
  b.hi = glm::vec3(glm::min(glm::vec2(b.hi), glm::vec2(slice.hi)), b.hi.z);
  return b.empty() ? Bounds{} : b;
}

}  // namespace

DirectionalShadowFit fitDirectionalShadow(const glm::vec3& direction,
                                          const std::vector<ShadowBox>& objects,
                                          const ShadowFitCamera* camera, int mapSize) {
  const glm::vec3 dir =
      glm::length(direction) > 0 ? glm::normalize(direction) : glm::vec3(0, 0, -1);
  const glm::vec3 up = std::abs(dir.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  DirectionalShadowFit fit;
  // About the origin, so that light-space coordinates (and the texel grid) do not depend on the
  // camera.
  fit.viewFromWorld = glm::lookAt(glm::vec3(0.0f), dir, up);
  const glm::mat4& L = fit.viewFromWorld;
  const float S = float(std::max(mapSize, 16));

  std::vector<Bounds> inLight;
  Bounds all, receivers;
  for (const ShadowBox& b : objects) {
    inLight.push_back(transformed(L, b.lo, b.hi));
    if (!inLight.back().empty()) all.add(inLight.back().lo), all.add(inLight.back().hi);
    if (camera) {
      const Bounds v = visiblePart(b, *camera, L);
      if (!v.empty()) receivers.add(v.lo), receivers.add(v.hi);
    }
  }
  if (all.empty()) all.add(glm::vec3(-1e-3f)), all.add(glm::vec3(1e-3f));

  // Square, with kPadTexels of margin on each side.
  auto paddedSize = [&](const Bounds& b) {
    return std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, 1e-4f}) * S / (S - 2 * kPadTexels);
  };
  const float wholeSize = paddedSize(all);
  double size = wholeSize;
  glm::dvec2 lo = 0.5 * glm::dvec2(all.lo + all.hi) - 0.5 * size;
  if (!receivers.empty()) {
    // Quarter octaves: a size that follows the view continuously would rescale the texel grid
    // every frame.
    const double q = std::exp2(std::ceil(4.0 * std::log2(double(paddedSize(receivers)))) / 4.0);
    if (q < double(wholeSize)) {
      size = q;
      const double texel = q / S;
      const glm::dvec2 centre = 0.5 * glm::dvec2(receivers.lo + receivers.hi);
      lo = glm::floor((centre - 0.5 * q) / texel) * texel;
      fit.fitted = true;
    }
  }
  fit.texel = float(size / S);

  // Depth: every caster whose footprint overlaps the map, in view or not.
  const glm::dvec2 hi = lo + size;
  float zLo = INFINITY, zHi = -INFINITY;
  for (const Bounds& b : inLight)
    if (!b.empty() && b.lo.x <= hi.x && b.hi.x >= lo.x && b.lo.y <= hi.y && b.hi.y >= lo.y)
      zLo = std::min(zLo, b.lo.z), zHi = std::max(zHi, b.hi.z);
  if (!(zLo <= zHi)) zLo = all.lo.z, zHi = all.hi.z;
  // The light looks down -z: depth is -z.
  const float margin = 0.02f * (zHi - zLo) + 2 * fit.texel;
  fit.nearZ = -zHi - margin;
  fit.farZ = -zLo + margin;
  fit.clipFromWorld =
      glm::ortho(float(lo.x), float(hi.x), float(lo.y), float(hi.y), fit.nearZ, fit.farZ) * L;
  return fit;
}

bool meetsFrustum(const ShadowBox& box, const ShadowFitCamera& camera) {
  return !visiblePart(box, camera, glm::mat4(1.0f)).empty();
}

ObjectClusters clusterObjects(const std::vector<ShadowBox>& objects, float reach) {
  // Union-find over every pair: scenes hold scans and meshes by the tens, not thousands.
  std::vector<int> parent(objects.size());
  for (size_t i = 0; i < parent.size(); ++i) parent[i] = int(i);
  auto root = [&](int i) {
    while (parent[size_t(i)] != i) i = parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
    return i;
  };
  for (size_t a = 0; a < objects.size(); ++a)
    for (size_t b = a + 1; b < objects.size(); ++b) {
      const ShadowBox &A = objects[a], &B = objects[b];
      const glm::vec3 gap = glm::max(glm::max(A.lo - B.hi, B.lo - A.hi), glm::vec3(0.0f));
      const float size = std::max(glm::length(A.hi - A.lo), glm::length(B.hi - B.lo));
      if (glm::length(gap) <= reach * size) parent[size_t(root(int(a)))] = root(int(b));
    }
  ObjectClusters c;
  std::vector<int> index(objects.size(), -1);
  for (size_t i = 0; i < objects.size(); ++i) {
    int& k = index[size_t(root(int(i)))];
    if (k < 0) {
      k = int(c.boxes.size());
      c.boxes.push_back({glm::vec3(INFINITY), glm::vec3(-INFINITY)});
    }
    c.of.push_back(k);
    c.boxes[size_t(k)].lo = glm::min(c.boxes[size_t(k)].lo, objects[i].lo);
    c.boxes[size_t(k)].hi = glm::max(c.boxes[size_t(k)].hi, objects[i].hi);
  }
  return c;
}

DirectionalShadowFit fitDirectionalToBox(const glm::vec3& direction, const ShadowBox& lit,
                                         const std::vector<ShadowBox>& objects, int mapSize) {
  // The expressions of the scene-wide view this replaces, term for term: a scene of one cluster
  // keeps its shadow map bit for bit.
  const glm::vec3 centre = 0.5f * (lit.lo + lit.hi);
  const float R = std::max(0.5f * glm::length(lit.hi - lit.lo), 1e-3f);
  const glm::vec3 up = std::abs(direction.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
  DirectionalShadowFit fit;
  fit.viewFromWorld = glm::lookAt(centre - direction * (R * 1.05f), centre, up);
  fit.nearZ = 0.0f;
  fit.farZ = 2.1f * R;
  // Casters beyond `lit` towards the light, over its footprint: the near plane moves back to
  // them. Those beyond the far plane lie behind every receiver and cast nothing on it.
  float nearest = 0.0f;
  for (const ShadowBox& b : objects) {
    const Bounds v = transformed(fit.viewFromWorld, b.lo, b.hi);
    if (v.empty() || v.lo.x > R || v.hi.x < -R || v.lo.y > R || v.hi.y < -R) continue;
    nearest = std::min(nearest, -v.hi.z);  // the view looks down -z
  }
  if (nearest < 0.0f) fit.nearZ = nearest - 0.01f * (fit.farZ - nearest);
  fit.texel = 2 * R / float(std::max(mapSize, 1));
  fit.clipFromWorld = glm::ortho(-R, R, -R, R, fit.nearZ, fit.farZ) * fit.viewFromWorld;
  return fit;
}

}  // namespace nestlight::gi
