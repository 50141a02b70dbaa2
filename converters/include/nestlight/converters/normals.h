// Normal estimation by a closed-form local plane fit (Rohmer, Jendersie, Grosch, "Natural
// Environment Illumination", section 5): after centring the k nearest neighbours on their mean,
// fix one normal component to 1 and solve the 2x2 normal equations for the other two by
// Cramer's rule; of the three choices of fixed component, use the one with the largest
// determinant (the best-conditioned). Fewer than 3 neighbours or a vanishing determinant leave
// the normal undefined (zero vector).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace nestlight {

// Fits a normal to `count` points (xyz triples, any frame); returns false when undefined.
bool fitPlaneNormal(const double* xyz, size_t count, float normal[3]);

// Estimates normals for `n` points (integer positions, 3 per point) using each point's `k`
// nearest neighbours (nanoflann k-d tree). `normals` receives 3 floats per point.
// Orientation: flipped to face away from `centre` (outward) or towards it (inward), or upwards.
//
// `depthLimit` (in the positions' integer units; 0: off) is the paper's guard against fitting
// across a depth discontinuity: neighbours whose depth differs from the nearest sample's (the
// point itself) by more than it are dropped and the plane is fitted again to the rest. The paper
// measures depth along the camera's view ray; a converted scan has no scanner position, so depth
// here is the distance along the normal of a first fit to all k neighbours. Where fewer than 3
// neighbours remain the first fit stands.
void estimateNormals(const uint32_t* pos, size_t n, unsigned k, int orientation,
                     const double centre[3], float* normals, double depthLimit = 0);

}  // namespace nestlight
