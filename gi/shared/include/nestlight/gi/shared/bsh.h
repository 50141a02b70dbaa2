// The bounding-sphere hierarchy (BSH) of point-based GI over one octree node's points
// (Sabbadin et al., "High Dynamic Range Point Clouds for Real-Time Relighting", 2019, section
// 5.1, Algorithm 2): points voxelised on a 64-bit Morton grid over their bounding cube (points
// sharing a cell averaged), radix-sorted, inner nodes by Karras ("Maximizing Parallelism in the
// Construction of BVHs, Octrees, and k-d Trees", 2012), filled bottom-up (mean colour over the
// points below; the smallest sphere containing both children's spheres, exact for two spheres,
// where the paper takes an approximate smallest enclosing ball; the smallest cone containing
// both children's normal cones, normal_cone.h), then pruned: a sub-tree whose points' colour
// variance is below t_c (0.01) and whose mean normal agreement, the mean of n_i . n_mean, is
// above t_n (0.98) becomes one leaf.
//
// The paper builds one BSH over a whole in-core cloud; Nestlight builds one per octree node, on
// the loader thread that loads it, in the node's frame, and a small top tree over the resident
// nodes joins them, so the resident cut is the paper's point cloud at any scan size.
#pragma once

#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <vector>

#include "nestlight/frame/interface.h"

namespace nestlight::gi {

namespace glsl {
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
using ivec4 = glm::ivec4;
#include "gi/shared/bsh_interface.glsl"
}  // namespace glsl

using BshNode = glsl::BshNode;
static_assert(sizeof(BshNode) == 48, "BshNode must keep std430's layout");

// Points to build from (one octree node's, in its frame). Sizes equal; `normal` may be empty
// (the scan has none), and a zero or non-finite normal is "unknown" (its cone bounds nothing).
struct BshPoints {
  std::vector<glm::vec3> position;
  std::vector<glm::vec3> colour;  // linear, any non-negative magnitude
  std::vector<glm::vec3> normal;
  // Each point's disc radius (world units); empty: BshOptions::leafRadius for every point.
  std::vector<float> radius;
};

struct BshOptions {
  // The disc radius each point stands for (world units): leaves are spheres of this radius, so
  // a coarse level's points, which stand for more surface, make wider leaves.
  float leafRadius = 0;
  // BshLayer: each node's points' disc radii (BshPoints::radius) from its points and leafRadius,
  // where leaves must cover the surface for rays not to pass between them (diffrender's exact
  // query: the reference's radii, assignDiscRadii); unset, every leaf has leafRadius.
  std::function<std::vector<float>(const BshPoints&, float leafRadius)> discRadii;
  bool prune = true;
  float colourVariance = 0.01f;  // t_c: largest channel's variance of linear colour, below which...
  float normalAgreement =
      0.98f;                  // t_n: ...and mean n_i . n_mean above which a sub-tree is one leaf
  bool recordLeaves = false;  // fill Bsh::leafOf (tests, tools)
};

struct BshStats {
  uint64_t input = 0;        // points given
  uint64_t rejected = 0;     // non-finite position or colour, or negative colour: not in the tree
  uint64_t sharedCells = 0;  // points averaged into a Morton cell with another point
  uint64_t leaves = 0;       // Morton cells: leaves before pruning
  uint64_t nodesBeforePruning = 0;
  uint64_t nodes = 0;     // after pruning (the paper's "N. Cluster")
  uint64_t clusters = 0;  // leaves that replaced a pruned sub-tree
  int depth = 0;          // levels below the root
  // Accounting: input == rejected + points below the root (the root's links.z).
};

struct Bsh {
  std::vector<BshNode> nodes;  // depth-first, root first; empty when no point was usable
  BshStats stats;
  // With BshOptions::recordLeaves: per input point, the index of the leaf it went into
  // (BSH_LEAF for a rejected point).
  std::vector<uint32_t> leafOf;
};

Bsh buildBsh(const BshPoints& points, const BshOptions& options);

// The top tree over the resident nodes' hierarchies, rebuilt when the cut changes: `roots` are
// their root nodes moved into one frame (the scene's), colours scaled as the gather sees them.
// Its leaves are the roots themselves (sphere, cone, colour, count as given) with links.y the
// index into `roots`; inner nodes as buildBsh's (never pruned). The gather enters a node's own
// hierarchy at a leaf, so the resident cut is traversed as one hierarchy.
Bsh buildTopTree(const std::vector<BshNode>& roots);

// Decoded fields of a node, for tests and tools.
glm::vec3 coneAxis(const BshNode& n);  // (0, 0, 0) when the node's cone bounds nothing
inline bool isLeaf(const BshNode& n) {
  return n.links.x == BSH_LEAF;
}

}  // namespace nestlight::gi
