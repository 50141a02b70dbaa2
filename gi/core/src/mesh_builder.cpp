// Polygon soup to clean triangles for the mesh readers. Fan triangulation is exact for the convex
// polygons that PLY and OBJ writers emit (the Wavefront OBJ spec, appendix B1, asks for convex
// faces); the sRGB decoding is IEC 61966-2-1.
#include "mesh_builder.h"

#include <cmath>
#include <glm/geometric.hpp>
#include <string>

#include "nestlight/octree/error.h"

namespace nestlight::gi::meshio {

void MeshBuilder::addPolygon(const uint32_t* corners, size_t n) {
  ++report.facesRead;
  if (n < 3) {
    // A point or an edge: there is no surface to keep, but the face was in the file.
    ++report.degenerateDropped;
    return;
  }
  if (n > 3) ++report.polygonsTriangulated;
  for (size_t i = 1; i + 1 < n; ++i) {
    mesh.indices.push_back(corners[0]);
    mesh.indices.push_back(corners[i]);
    mesh.indices.push_back(corners[i + 1]);
  }
}

namespace {
bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Twice the area vector, in double: float edges of a large but valid triangle can overflow a
// float cross product, and collinear float corners give exactly zero here.
glm::dvec3 areaVector(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::dvec3 da(a);
  return glm::cross(glm::dvec3(b) - da, glm::dvec3(c) - da);
}
}  // namespace

void MeshBuilder::finish() {
  const size_t nv = mesh.positions.size();
  report.nonFiniteVertices = 0;
  for (const auto& p : mesh.positions)
    if (!finite(p)) ++report.nonFiniteVertices;

  auto& idx = mesh.indices;
  size_t kept = 0;
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const uint32_t a = idx[t], b = idx[t + 1], c = idx[t + 2];
    NL_CHECK(a < nv && b < nv && c < nv);  // the readers check indices as they read them
    const glm::vec3 &pa = mesh.positions[a], &pb = mesh.positions[b], &pc = mesh.positions[c];
    bool keep = a != b && b != c && a != c && finite(pa) && finite(pb) && finite(pc);
    if (keep) {
      const glm::dvec3 n = areaVector(pa, pb, pc);
      keep = glm::dot(n, n) > 0;
    }
    if (!keep) {
      ++report.degenerateDropped;
      continue;
    }
    idx[kept] = a, idx[kept + 1] = b, idx[kept + 2] = c;
    kept += 3;
  }
  idx.resize(kept);
  idx.shrink_to_fit();
  report.trianglesKept = kept / 3;

  if (!needsNormal.empty() && !mesh.normals.empty()) {
    NL_CHECK(needsNormal.size() == nv && mesh.normals.size() == nv);
    std::vector<glm::dvec3> sum(nv, glm::dvec3(0));
    for (size_t t = 0; t < idx.size(); t += 3) {
      const glm::dvec3 n = areaVector(mesh.positions[idx[t]], mesh.positions[idx[t + 1]],
                                      mesh.positions[idx[t + 2]]);
      for (int k = 0; k < 3; ++k)
        if (needsNormal[idx[t + k]]) sum[idx[t + k]] += n;
    }
    for (size_t v = 0; v < nv; ++v)
      if (needsNormal[v]) mesh.normals[v] = glm::vec3(sum[v]);
  }

  if (mesh.normals.empty()) return;
  // Only normals that a triangle uses are worth a warning.
  std::vector<uint8_t> used(nv, 0);
  for (uint32_t i : idx) used[i] = 1;
  uint64_t unusable = 0;
  for (size_t v = 0; v < nv; ++v) {
    glm::vec3& n = mesh.normals[v];
    const double len = glm::length(glm::dvec3(n));
    if (std::isfinite(len) && len > 0) {
      n = glm::vec3(glm::dvec3(n) / len);
    } else {
      n = glm::vec3(0);
      unusable += used[v];
    }
  }
  if (unusable > 0)
    report.warnings.push_back(std::to_string(unusable) +
                              " vertex normals are zero or not finite; they are left zero, and "
                              "shading there uses the geometric normal");
}

}  // namespace nestlight::gi::meshio
