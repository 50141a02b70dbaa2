// The inserted meshes as a solid voxel grid (the "object volume" of differential rendering):
// which voxels the objects fill, and on their surface the normal and material. Built on the CPU by
// parity along +z, as Eisemann and Décoret's single-pass GPU solid voxelisation does on the GPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <glm/glm.hpp>
#include <string>
#include <vector>

#include "nestlight/gi/mesh.h"

namespace nestlight::gi {

// One inserted mesh as the voxeliser takes it.
struct VolumeMesh {
  const TriangleMesh* mesh = nullptr;
  glm::mat4 localFromObject{1.0f};  // into the scene's local frame
  uint32_t material = 0;            // index of the scene's material (< 255: alpha is material + 1)
  std::string name;                 // for warnings, e.g. "meshes[1].path (bunny.ply)"
};

struct ObjectVolume {
  glm::ivec3 size{0};  // voxels per axis
  // The grid's box, scene-local: the meshes' bounds padded by one voxel on each side (an axis of
  // fewer than 3 voxels is centred on the bounds instead; an axis along which the meshes are flat
  // gets the largest voxel size of the other axes). Voxel (x, y, z) spans
  // lo + (x, y, z) * (hi - lo) / size to one voxel further.
  glm::vec3 lo{0.0f}, hi{0.0f};
  // Per voxel, x fastest then y then z: 255 where the voxel is solid (its centre inside a closed
  // mesh, or a triangle crosses it away from any interior: thin sheets, open meshes), kShell where
  // a triangle crosses it but its centre lies outside next to the interior (the conservative
  // shell's excess, which rays pass), else 0.
  std::vector<uint8_t> occupancy;
  // Per voxel, RGBA8 packed in a uint32 (R in the low byte): boundary voxels (crossed by a
  // triangle) hold the mean of the crossing triangles' area-weighted outward normals, normalised,
  // as rgb = n * 0.5 + 0.5, and alpha = material + 1 (the material of the mesh whose triangles
  // there have the most area; the first such mesh on a tie); every other voxel 0.
  std::vector<uint32_t> surface;
  static constexpr uint8_t kShell = 128;
  uint64_t solidVoxels = 0;     // occupancy not 0 (255 or kShell)
  uint64_t boundaryVoxels = 0;  // surface != 0 (all of them are solid)
  // Voxels whose centre is inside a mesh by parity alone (the interior without the surface
  // shell): the grid's estimate of the enclosed volume, parityVoxels * voxel volume.
  uint64_t parityVoxels = 0;
  // Triangles left out: an index out of range, a non-finite corner (after the transform), or
  // zero area.
  uint64_t skippedTriangles = 0;
  // Meshes that are not closed (a column met an odd number of crossings: only its shell is solid
  // there), one warning each naming VolumeMesh::name and how many columns.
  std::vector<std::string> warnings;

  glm::vec3 voxelSize() const { return (hi - lo) / glm::vec3(size); }
  size_t bytes() const;  // occupancy + surface bytes
};

// Solid voxelisation of the meshes into one grid of `size` voxels over their joint bounds. Each
// mesh is filled on its own (its interior OR-ed into the grid), so an open mesh is found and named
// even where another mesh covers it. A voxel centre is inside a mesh when the line along +z
// through it crosses the mesh an odd number of times at or below the centre; a column whose line
// crosses the mesh an odd number of times in all is open and gets nothing from parity. A column
// through a shared edge or vertex crosses it once (ties go as for a column moved by an
// infinitesimal). Then every voxel a triangle overlaps becomes solid and gets the normal and
// material; a face lying exactly on a voxel boundary marks the voxel behind it (inside), so the
// padding stays empty. Outward is the side from which a triangle's corners run counter-clockwise
// in the object's frame (a mirroring localFromObject keeps it outward). No triangles at all
// (empty meshes, all skipped) give an empty grid of `size` over the box [-0.5, 0.5]^3.
// Throws nestlight::Error for a size component below 1, more than 2^31 voxels, a material of 255
// or more, a null mesh, or bounds too large for floats.
ObjectVolume voxelizeSolid(const std::vector<VolumeMesh>& meshes, glm::ivec3 size);

}  // namespace nestlight::gi
