// Inserted objects: triangle meshes read from PLY or OBJ, and their sampling into points so that
// they take part in point-based GI beside the scan (Preiner, paper 004, section 6).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/sampling.h"

namespace nestlight::gi {

// What the readers return. `positions` holds every vertex of the file in file order, also those
// no triangle uses (a NaN vertex stays there, referenced by none); an OBJ vertex whose corners
// name different normals (`vn`) is split, and its copies follow the file's vertices. `normals`
// are unit length, or zero where the file gives none usable (a zero or NaN normal, or an OBJ
// vertex used by no corner): there, shade with the geometric normal. `indices` hold only
// triangles of non-zero area with finite corners.
struct TriangleMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // per vertex, empty when the file has none
  std::vector<Rgb> colors;         // per vertex, linear [0,1], empty when the file has none
  std::vector<uint32_t> indices;   // 3 per triangle

  size_t triangles() const { return indices.size() / 3; }
};

struct MeshReadReport {
  uint64_t facesRead = 0;      // polygons in the file
  uint64_t trianglesKept = 0;  // after fan triangulation and cleaning
  // Zero-area triangles (a repeated index, collinear corners), triangles with a non-finite
  // corner, and faces of fewer than three vertices (one each): not rendered, counted.
  uint64_t degenerateDropped = 0;
  uint64_t polygonsTriangulated = 0;  // faces with more than three vertices
  uint64_t nonFiniteVertices = 0;     // vertices with NaN/Inf coordinates
  // What was read differently from what the file says, without losing a triangle: colours of a
  // type that is not a colour, normals that cannot be normalised, OBJ corners without a normal
  // beside corners with one, bytes after the last element.
  std::vector<std::string> warnings;
};

// By extension: .ply (ASCII, binary little- or big-endian) or .obj. Throws nestlight::Error with
// the file and the line or byte of the fault; never asserts on malformed input. A file with no
// faces at all (a point cloud) is an error; faces that are all degenerate give an empty mesh.
TriangleMesh readMesh(const std::string& path, MeshReadReport* report = nullptr);
// The same on bytes in memory (for fuzzing); `name` is used in messages, its extension picks
// the format.
TriangleMesh readMeshFromMemory(const std::string& name, const void* data, size_t size,
                                MeshReadReport* report = nullptr);

enum class SurfelSampling { AreaUniform, PoissonDisk };

// Points on a mesh: each stands for `area` of surface (the sum equals the mesh's area).
struct Surfels {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // shading normal (interpolated vertex normal, else face)
  std::vector<float> area;
  std::vector<Rgb> albedo;         // vertex colour times the material's base colour
  std::vector<uint32_t> material;  // index into the scene's materials
};

struct SurfelOptions {
  SurfelSampling method = SurfelSampling::AreaUniform;
  size_t count = 10000;  // points wanted (Poisson-disk may return slightly fewer)
  uint64_t seed = 1;
  uint32_t material = 0;
  Rgb baseColor{1.0f};
};

// Samples `mesh` transformed by worldFromObject. Degenerate triangles get no points.
Surfels sampleSurfels(const TriangleMesh& mesh, const glm::mat4& worldFromObject,
                      const SurfelOptions& options);

double meshArea(const TriangleMesh& mesh, const glm::mat4& worldFromObject);

}  // namespace nestlight::gi
