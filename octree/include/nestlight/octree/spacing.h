// The measured point spacing of a node, stored in its hierarchy entry (encodeSpacing).
//
// A viewer sizes each splat by the spacing of the points drawn around it. The nominal spacing of
// a level (the root's spacing / 2^level) says how far apart the level's Poisson-disk samples are
// at least, but not how dense the scan really is: a leaf holds every remaining point of the scan
// at its raw density, and an inner node's sample radius may have been widened to fit the node's
// point limit. So the builder measures it, on the set that is drawn where the node is the finest
// drawn node: the node's own points together with its ancestors' points inside its cube.
#pragma once

#include <cstddef>
#include <cstdint>

#include "nestlight/octree/hierarchy.h"
#include "nestlight/octree/metadata.h"

namespace nestlight {

// The spacing of a point set on a surface: the side of the square of surface each point stands
// for, sqrt(area / points), estimated locally from the distance r to the k-th nearest distinct
// neighbour (k points within r: spacing = r sqrt(pi / k)) and taken as the median over the set.
// It is 1.02 times the step of a regular grid, and does not shrink for irregular sets as the
// nearest-neighbour distance does (a jittered grid's nearest neighbours are closer than its step).
// Positions are integers (x, y, z per point) in `xyz`; `indices` selects `n` of them (nullptr: the
// first n), which must be in Morton order: the neighbour search looks at the `window` points on
// either side of a query in that order, where a point's spatial neighbours nearly always are (a
// Z-order jump can hide a neighbour, which the median absorbs). At most `maxQueries` evenly
// strided points are queried, so the cost is bounded per node: about 8k distance tests (2-3% of a
// conversion).
// Returns 0 when fewer than 8 queries find k distinct neighbours (too few points, or coincident
// ones): the caller then keeps the nominal spacing.
//
// Bunched returns: where a query's estimate exceeds kClusterRatio times the one its 2nd-nearest
// neighbour gives (r_2 sqrt(pi / 2)), the query is in a bunch, and takes the largest estimate
// r_j sqrt(pi / j) (j = 2 .. k - 1) within that bound: its bunch's. A few returns bunched together
// far from the rest (stray points of dust or birds, often several returns within a centimetre)
// would otherwise measure the distance to the next bunch, and a node holding little else would
// draw them as discs that wide (issue 30: 65-pixel discs above the lion). On a surface the rule
// almost never applies: it needs 2 of the 5 neighbours inside r_6 within 0.19 r_6, 1.2% of
// queries for points scattered at random (a 2D Poisson process), none on a grid or a Poisson-disk
// sample (the octree's levels), so the median moves by less than one percentile. A lone pair is
// no bunch here (a scan's near-duplicate returns would shrink splats into holes); single stray
// points are sized by the nodes around them (the finest drawn node at their position).
inline constexpr int kSpacingNeighbours = 6;
inline constexpr double kClusterRatio = 3.0;

// The measured spacing of the node at `level` with hierarchy entry `e`, in world units; 0 when
// it was not measured (format version 1, whose byte 3 was reserved, or too few points).
double measuredSpacing(const Metadata& meta, uint32_t level, const HierarchyEntry& e);

double medianNeighbourSpacing(const uint32_t* xyz, const uint32_t* indices, size_t n,
                              size_t maxQueries = 128, size_t window = 32);

}  // namespace nestlight
