// The resident cut's per-node hierarchies joined into the buffers a GPU traversal reads
// (shaders/gi/pbgi/pbgi_nodes.glsl: PBGI_SSBO_TOP, _NODES, _TABLE): every lights'-cut node's BSH
// layer copied one after another, inserted meshes' hierarchies after them, and the top tree over
// all their roots. Rebuilt when the cut changes; used by the pbgi gather and by the ibl method's
// visibility rays.
#pragma once

#include <cstdint>
#include <vector>

#include "nestlight/gi/frame/scene_frame.h"
#include "nestlight/gi/shared/bsh.h"
#include "nestlight/gi/shared/mesh_trees.h"
#include "nestlight/gl/resources.h"

namespace nestlight::gi {

using PbgiNode = glsl::PbgiNode;

class CutHierarchies {
 public:
  // Inserted meshes' hierarchies, joined after the scan's at every assemble() (uploaded once).
  void setMeshTrees(const std::vector<MeshTree>& trees);
  // Gathers the lights' cut's hierarchies (node layer `layer`). The finest nodes are left out
  // (and counted) when the whole would exceed one 128 MiB buffer range.
  void assemble(SceneFrame& frame, size_t layer);

  const gl::Buffer& top() const { return top_; }
  const gl::Buffer& nodes() const { return nodes_; }
  const gl::Buffer& table() const { return table_; }
  // The table as uploaded: the cut's nodes first (scanTrees() of them), then the meshes'.
  const std::vector<PbgiNode>& entries() const { return entries_; }
  // The top tree's leaves in the scene frame, colours scaled, in the table's order.
  const std::vector<BshNode>& roots() const { return roots_; }
  const BshNode& topRoot() const { return topRoot_; }
  size_t topCount() const { return topCount_; }
  size_t scanTrees() const { return scanTrees_; }
  uint64_t nodeCount() const { return nodeCount_; }
  uint64_t cutNodes() const { return cutNodes_; }
  uint64_t leftOut() const { return leftOut_; }
  double milliseconds() const { return ms_; }

 private:
  std::vector<MeshTree> meshTrees_;
  std::vector<size_t> meshOffsets_;  // each one's first node in meshNodes_
  gl::Buffer meshNodes_, top_, nodes_, table_, rootsStaging_;
  std::vector<PbgiNode> entries_;
  std::vector<BshNode> roots_;
  BshNode topRoot_{};
  size_t topCount_ = 0, scanTrees_ = 0;
  uint64_t nodeCount_ = 0, cutNodes_ = 0, leftOut_ = 0;
  double ms_ = 0;
};

}  // namespace nestlight::gi
