#include "nestlight/gi/shared/mesh_trees.h"

#include <cmath>

#include "nestlight/gi/material.h"
#include "nestlight/gi/mesh.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

std::vector<MeshTree> buildMeshTrees(const Scene& scene, const std::vector<TriangleMesh>& meshes) {
  NL_CHECK(meshes.size() == scene.meshes.size());
  std::vector<MeshTree> trees;
  for (size_t i = 0; i < scene.meshes.size(); ++i) {
    const SceneMesh& m = scene.meshes[i];
    const TriangleMesh& mesh = meshes[i];
    SurfelOptions o;
    o.method = m.surfelMethod;
    o.count = m.surfelCount;
    o.material = m.material;
    o.baseColor = Rgb(1.0f);  // vertex colour only: the material's reflectance multiplies it below
    const Surfels s = sampleSurfels(mesh, scene.localFromObject(m), o);
    if (s.positions.empty()) continue;
    const Material& mat = scene.materials.at(m.material);
    // 4096 BSDF samples: the albedo to about 1% (a Lambert material's is exact).
    const Rgb rho =
        glm::clamp(directionalAlbedo(mat, glm::vec3(0, 0, 1), 4096), Rgb(0.0f), Rgb(1.0f));
    MeshTree t;
    t.material = m.material;
    t.surfels = s.positions.size();
    double area = 0;
    glm::vec3 lo(INFINITY);
    for (size_t i = 0; i < s.positions.size(); ++i)
      area += s.area[i], lo = glm::min(lo, s.positions[i]);
    t.origin = lo;
    const glm::mat4 localFromObject = scene.localFromObject(m);
    t.lo = glm::vec3(INFINITY), t.hi = glm::vec3(-INFINITY);
    for (uint32_t v : mesh.indices) {
      const glm::vec3 p(localFromObject * glm::vec4(mesh.positions[v], 1.0f));
      t.lo = glm::min(t.lo, p), t.hi = glm::max(t.hi, p);
    }
    BshPoints in;
    in.position.reserve(s.positions.size());
    in.colour.reserve(s.positions.size());
    in.normal = s.normals;
    for (size_t i = 0; i < s.positions.size(); ++i) {
      in.position.push_back(s.positions[i] - lo);
      in.colour.push_back(glm::vec3(s.albedo[i]) * glm::vec3(rho));
    }
    // The scan's leaves take their level's spacing as disc radius (bsh_layer.h); surfels the same:
    // discs that overlap rather than leave holes between randomly placed samples.
    t.discRadius = float(std::sqrt(area / double(s.positions.size())));
    BshOptions opt;
    opt.leafRadius = t.discRadius;
    opt.prune = false;  // see mesh_trees.h
    t.nodes = buildBsh(in, opt).nodes;
    if (!t.nodes.empty()) trees.push_back(std::move(t));
  }
  return trees;
}

}  // namespace nestlight::gi
