// Inserted meshes in point-based GI: each mesh's surfels (nestlight/gi/mesh.h) become a
// bounding-sphere hierarchy of their own beside the scan's, joined under the same top tree, so
// the meshes occlude the scan's light, reflect the scene's lights and emit their own onto every
// receiver. Sabbadin et al., "High Dynamic Range Point Clouds for Real-Time Relighting" (2019),
// section 5, lights inserted objects as receivers only; a polygon model taking part in point-based
// GI through points sampled on its surface is Preiner, "Real-Time Global Illumination in Point
// Clouds" (section 6), whose sampler (mesh_sampling.cpp) this reuses.
//
// A surfel reflects as a Lambertian surface whose albedo is the material's directional albedo at
// normal incidence (its whole reflectance, glossy lobes included, spread over the hemisphere):
// what a micro-buffer pixel can store, one colour per node. Its emission is the material's.
//
// Never pruned: a pruned cluster is one flat disc as wide as its sub-tree, and on a curved mesh
// (whose surfels receive too) such a disc's rim rises above the tangent planes of the surface's
// own receivers: a sphere mesh in a uniform furnace came out 20% dark with the paper's pruning,
// exact without. A mesh's surfels are few (its `surfels.count`), so pruning saves little.
#pragma once

#include <cstdint>
#include <glm/glm.hpp>
#include <vector>

#include "nestlight/gi/mesh.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/shared/bsh.h"

namespace nestlight::gi {

struct MeshTree {
  std::vector<BshNode> nodes;  // positions relative to `origin`; colour: the surfels' albedo
  glm::vec3 origin{0.0f};      // scene (local) frame: the surfels' bounding-box minimum
  uint32_t material = 0;       // index into the scene's materials (emission, at light time)
  uint64_t surfels = 0;
  float discRadius = 0;          // the leaves' disc radius: the surfels' mean spacing
  glm::vec3 lo{0.0f}, hi{0.0f};  // scene (local) frame: the bounding box of the mesh's triangles
};

// One hierarchy per mesh with at least one surfel, in scene order (a mesh whose triangles are
// all degenerate has none and is left out). `meshes`: the scene's meshes as read, one per
// scene.meshes entry.
std::vector<MeshTree> buildMeshTrees(const Scene& scene, const std::vector<TriangleMesh>& meshes);

}  // namespace nestlight::gi
