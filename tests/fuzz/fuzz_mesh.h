// Shared by the mesh reader fuzz targets. Header-only: each tests/fuzz/fuzz_*.cpp builds on its
// own.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "nestlight/gi/mesh.h"
#include "nestlight/octree/error.h"

namespace nestlight::fuzz {

// Reads `data` as a mesh named `name` (the extension picks the format). Malformed input may
// throw nestlight::Error, which is caught here; anything else escapes and fails the run. Traps
// when a mesh that was read breaks the TriangleMesh contract (an index out of range, per-vertex
// arrays of the wrong size, a report that does not add up), and samples what was read, so that
// whatever the reader lets through is safe to sample too.
inline void readMeshChecked(const std::string& name, const uint8_t* data, size_t size) {
  gi::MeshReadReport report;
  gi::TriangleMesh mesh;
  try {
    mesh = gi::readMeshFromMemory(name, data, size, &report);
  } catch (const nestlight::Error&) {
    return;
  }
  const size_t nv = mesh.positions.size();
  if (mesh.indices.size() % 3 != 0) __builtin_trap();
  for (uint32_t i : mesh.indices)
    if (i >= nv) __builtin_trap();
  if (!mesh.normals.empty() && mesh.normals.size() != nv) __builtin_trap();
  if (!mesh.colors.empty() && mesh.colors.size() != nv) __builtin_trap();
  if (report.trianglesKept != mesh.triangles() || report.facesRead == 0) __builtin_trap();
  for (auto method : {gi::SurfelSampling::AreaUniform, gi::SurfelSampling::PoissonDisk}) {
    gi::SurfelOptions options;
    options.method = method;
    options.count = 16;
    const gi::Surfels s = gi::sampleSurfels(mesh, glm::mat4(1), options);
    if (s.positions.size() != 0 && s.positions.size() != options.count) __builtin_trap();
  }
}

}  // namespace nestlight::fuzz
