#pragma once

#include <vector>

namespace nestlight::gi::projection {

// The solid angle of each texel of a size x size hemi-octahedral micro-buffer (Maletz, Wang and
// Bowers 2011, eq. 2; shaders/gi/projection/projection_map.glsl), row by row (texel (x, y) at
// y * size + x; t = ((x, y) + 0.5) / size at its centre). Exact: the map is linear on each face
// of the octahedron, so a texel's part on a face is a planar polygon, whose solid angle is a sum
// of triangles' (Van Oosterom and Strackee's formula). They sum to 2 pi.
std::vector<double> hemiOctTexelSolidAngles(int size);

}  // namespace nestlight::gi::projection
