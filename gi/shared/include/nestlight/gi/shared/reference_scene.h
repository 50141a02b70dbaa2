// The reference's view of a scene: scan points as oriented discs and inserted meshes as
// triangles in one Embree 3 BVH, plus the materials, lights and environment that shade them.
// Everything is in the scene's local float frame (Scene::local), so national-grid scans keep
// their precision.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/environment_map.h"
#include "nestlight/gi/material.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

// Points of one scan, ready for Embree: (x, y, z, radius) and a unit normal per point.
struct DiscCloud {
  std::vector<glm::vec4> discs;
  std::vector<glm::vec3> normals;  // empty: discs face the ray (the scan has no normals)
  std::vector<Rgb> colour;         // linear; emitted radiance (radiance cache) or albedo
  // Oriented discs: how far the same surface's neighbouring discs reach off this disc's plane
  // (the scan's noise and the discs' tilt; see assignDiscThickness). Filled by ReferenceScene when
  // empty.
  std::vector<float> thickness;
};

struct DiscCloudStats {
  uint64_t nodes = 0, points = 0, bytes = 0;
  int deepestLevel = -1;         // deepest level loaded
  int octreeDepth = 0;           // deepest level the octree has
  bool limitedByBudget = false;  // stopped above maxLevel (or the octree's depth) for memory
  uint64_t zeroRadius = 0;       // discs with no extent (coincident points): never hit
};

// Loads whole levels of an octree, from the root down to `octree.maxLevel` or the deepest level
// whose points fit in `octree.memoryBudget` (40 bytes per point here), and sizes the discs by
// assignDiscRadii with `octree.radiusScale`.
DiscCloud loadDiscCloud(const SceneOctree& octree, const glm::dvec3& origin,
                        DiscCloudStats* stats = nullptr);
// Radii that close the sampled surface for rays whatever its sampling (random, striped, even):
// each disc covers its cell, the part of its tangent plane nearer to it than to any neighbour
// on the same surface (normals and directions within 30 degrees of its plane), cut where its
// surface meets another (a crease) by that surface's planes; radius 1.2 x the cell's plus 3 x
// the RMS height of the neighbours over its plane (scan noise). Where the cell stays open (a
// surface's boundary), the disc is at least 1.5 x half the distance to the 8th nearest point
// (the rule of earlier versions); no disc exceeds 3 x the median 8th-neighbour distance of its
// neighbours (outliers). Writes .w of `discs` (positions in .xyz), times `radiusScale`;
// `normals` empty: planes fitted to the 16 nearest points. docs/SCENE.md gives the reasons and
// the measurements.
void assignDiscRadii(std::vector<glm::vec4>& discs, const std::vector<glm::vec3>& normals,
                     float radiusScale);
void assignDiscRadii(DiscCloud& cloud, float radiusScale);
// The thickness of a scanned surface at each oriented disc (radii assigned): over its 8 nearest
// neighbours that lie on the same surface (normals within 30 degrees), the height each one's
// disc reaches above (and below) this disc's plane, h = |n . (p_j - p_i)| + r_j sin(angle), as
// mean + 3 standard deviations, capped at the disc's radius. Scan noise offsets overlapping
// discs of one flat surface by millimetres; a ray leaving a disc from less than that height hits
// its neighbours, and the surface shadows itself: 12% dark under light 25 degrees off the
// normal on a 1 mm-noise scan, a cellular pattern of shadows at grazing light. Rays leave from
// this height instead (no-op without normals: `thickness` is cleared).
void assignDiscThickness(DiscCloud& cloud);

// Changes whenever the same scene would render differently (the disc model, the integrator), so
// that images cached under an older model (`bench gi`'s reference) are not taken for current.
// 2: disc radius 1.5 x half the 8th-neighbour distance (evenly sampled surfaces closed).
// 3: rays leave a disc from its surface's thickness (no self-shadowing by scan noise).
// 4: discs cover their tangent-plane Voronoi cells (unevenly sampled surfaces closed).
// 5: the outlier cap reads bunches of a few returns by their own spacing.
inline constexpr int kReferenceModelVersion = 5;

struct SurfaceHit {
  enum class Kind { None, Disc, Triangle } kind = Kind::None;
  float t = 0;
  glm::vec3 position{0.0f};
  glm::vec3 geometricNormal{0.0f};  // unit; not flipped towards the ray
  glm::vec3 shadingNormal{0.0f};    // unit; interpolated for meshes with normals
  Rgb colour{1.0f};                 // disc colour, or the mesh's vertex colour (1 without)
  uint32_t material = 0;            // meshes: index into materials()
  float radius = 0;                 // discs: their radius (sets the ray offset)
  float thickness = 0;              // oriented discs: the surface's thickness there (ray offset)
  bool orientedDisc = true;         // false: a ray-facing disc (no normal known)
};

class ReferenceScene {
 public:
  // Loads octrees, meshes and the environment map named by `scene`. `log` gets one line per
  // loaded part (may be null).
  static std::unique_ptr<ReferenceScene> load(const Scene& scene,
                                              void (*log)(const std::string&) = nullptr);
  // From data already in the local frame (tests build analytic scenes this way). `meshes` are
  // already transformed; meshMaterial[i] indexes `materials`.
  ReferenceScene(std::vector<DiscCloud> clouds, std::vector<TriangleMesh> meshes,
                 std::vector<uint32_t> meshMaterial, std::vector<Material> materials,
                 std::vector<Light> lights, EnvironmentMap environment,
                 glm::dvec3 origin = glm::dvec3(0.0));
  ~ReferenceScene();
  ReferenceScene(const ReferenceScene&) = delete;
  ReferenceScene& operator=(const ReferenceScene&) = delete;

  bool intersect(const glm::vec3& origin, const glm::vec3& direction, float tMax,
                 SurfaceHit* hit) const;
  bool occluded(const glm::vec3& origin, const glm::vec3& direction, float tMax) const;
  // What intersect() reports for a ray that meets disc `disc` of cloud `cloud` at its centre (the
  // scan point itself): where the radiance of given scan points is estimated.
  SurfaceHit discHit(size_t cloud, size_t disc) const;
  // The scans' discs, in the order loadDiscCloud read them (radii and thicknesses assigned).
  const std::vector<DiscCloud>& clouds() const { return clouds_; }

  const std::vector<Material>& materials() const { return materials_; }
  const std::vector<Light>& lights() const { return lights_; }
  const EnvironmentMap& environment() const { return *environment_; }
  bool hasEnvironment() const { return !environment_->black(); }
  // Another frame of a video light probe (the geometry stays).
  void setEnvironment(std::shared_ptr<const EnvironmentMap> environment) {
    if (environment) environment_ = std::move(environment);
  }
  const glm::dvec3& origin() const { return origin_; }
  // Light positions in the local frame.
  glm::vec3 lightPosition(size_t i) const { return glm::vec3(lights_[i].position - origin_); }
  // Scale of the scene's coordinates: ray offsets are relative to it.
  float extent() const { return extent_; }

  uint64_t discs() const;
  uint64_t triangles() const;
  const std::vector<DiscCloudStats>& cloudStats() const { return cloudStats_; }
  const std::vector<MeshReadReport>& meshReports() const { return meshReports_; }

 private:
  void build();

  std::vector<DiscCloud> clouds_;
  std::vector<TriangleMesh> meshes_;
  std::vector<uint32_t> meshMaterial_;
  std::vector<Material> materials_;
  std::vector<Light> lights_;
  std::shared_ptr<const EnvironmentMap> environment_;
  glm::dvec3 origin_{0.0};
  float extent_ = 1;
  std::vector<DiscCloudStats> cloudStats_;
  std::vector<MeshReadReport> meshReports_;
  struct Embree;
  std::unique_ptr<Embree> rtc_;
  // geomID -> (is a cloud, index)
  std::vector<std::pair<bool, uint32_t>> geometry_;
};

}  // namespace nestlight::gi
