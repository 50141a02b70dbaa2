#include "nestlight/gi/shared/cut_hierarchies.h"

#include <algorithm>
#include <bit>
#include <chrono>

namespace nestlight::gi {

void CutHierarchies::setMeshTrees(const std::vector<MeshTree>& trees) {
  meshTrees_ = trees;
  meshOffsets_.clear();
  std::vector<BshNode> all;
  for (const auto& t : meshTrees_) {
    meshOffsets_.push_back(all.size());
    all.insert(all.end(), t.nodes.begin(), t.nodes.end());
  }
  if (!all.empty()) meshNodes_ = gl::Buffer(all.size() * sizeof(BshNode), all.data(), 0);
}

void CutHierarchies::assemble(SceneFrame& f, size_t layer) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto& cut = f.lightsCut();
  std::vector<PbgiNode> table;
  std::vector<size_t> included;
  uint64_t total = 0;
  leftOut_ = 0;
  // Parents come before children in the cut: when the hierarchies outgrow one buffer range,
  // the finest nodes are the ones left out (and counted).
  for (size_t i = 0; i < cut.size(); ++i) {
    const size_t bytes = f.layerBytes(cut[i], layer);
    const uint64_t count = bytes / sizeof(BshNode);
    if (count == 0) continue;
    if ((total + count) * sizeof(BshNode) > gl::kMaxSsboRange) {
      leftOut_++;
      continue;
    }
    PbgiNode e{};
    e.origin = glm::vec4(cut[i].origin, cut[i].colourScale);
    e.range =
        glm::uvec4(uint32_t(total), uint32_t(count), 0, std::bit_cast<uint32_t>(cut[i].spacing));
    table.push_back(e);
    included.push_back(i);
    total += count;
  }
  cutNodes_ = cut.size();
  scanTrees_ = table.size();
  // The meshes' hierarchies after the cut's (range.z: material + 1, which marks them).
  std::vector<size_t> meshIncluded;
  for (size_t k = 0; k < meshTrees_.size(); ++k) {
    const uint64_t count = meshTrees_[k].nodes.size();
    if ((total + count) * sizeof(BshNode) > gl::kMaxSsboRange) {
      leftOut_++;
      continue;
    }
    PbgiNode e{};
    e.origin = glm::vec4(meshTrees_[k].origin, 1.0f);
    e.range = glm::uvec4(uint32_t(total), uint32_t(count), meshTrees_[k].material + 1,
                         std::bit_cast<uint32_t>(meshTrees_[k].discRadius));
    table.push_back(e);
    meshIncluded.push_back(k);
    total += count;
  }
  nodeCount_ = total;
  nodes_.reserve(std::max<size_t>(total, 1) * sizeof(BshNode));
  // The roots come back in one read (one read per node would stall the pipeline each time).
  std::vector<BshNode> roots(included.size());
  rootsStaging_.reserve(std::max<size_t>(included.size(), 1) * sizeof(BshNode));
  for (size_t k = 0; k < included.size(); ++k) {
    const GLuint src = f.layerBuffer(cut[included[k]], layer);
    const size_t bytes = size_t(table[k].range.y) * sizeof(BshNode);
    glCopyNamedBufferSubData(src, nodes_.id(), 0,
                             GLintptr(size_t(table[k].range.x) * sizeof(BshNode)),
                             GLsizeiptr(bytes));
    glCopyNamedBufferSubData(src, rootsStaging_.id(), 0, GLintptr(k * sizeof(BshNode)),
                             sizeof(BshNode));
  }
  if (!included.empty()) {
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    glGetNamedBufferSubData(rootsStaging_.id(), 0, GLsizeiptr(roots.size() * sizeof(BshNode)),
                            roots.data());
  }
  for (size_t k = 0; k < included.size(); ++k) {
    const CutNode& n = cut[included[k]];
    roots[k].sphere = glm::vec4(glm::vec3(roots[k].sphere) + n.origin, roots[k].sphere.w);
    roots[k].colour = glm::vec4(glm::vec3(roots[k].colour) * n.colourScale, roots[k].colour.w);
  }
  for (size_t j = 0; j < meshIncluded.size(); ++j) {
    const MeshTree& t = meshTrees_[meshIncluded[j]];
    const PbgiNode& e = table[scanTrees_ + j];
    glCopyNamedBufferSubData(meshNodes_.id(), nodes_.id(),
                             GLintptr(meshOffsets_[meshIncluded[j]] * sizeof(BshNode)),
                             GLintptr(size_t(e.range.x) * sizeof(BshNode)),
                             GLsizeiptr(t.nodes.size() * sizeof(BshNode)));
    BshNode root = t.nodes[0];
    root.sphere = glm::vec4(glm::vec3(root.sphere) + t.origin, root.sphere.w);
    roots.push_back(root);
  }
  const Bsh topTree = buildTopTree(roots);
  topCount_ = topTree.nodes.size();
  topRoot_ = topCount_ ? topTree.nodes[0] : BshNode{};
  top_.reserve(std::max<size_t>(topCount_, 1) * sizeof(BshNode));
  if (topCount_) top_.upload(topTree.nodes.data(), topCount_ * sizeof(BshNode));
  table_.reserve(std::max<size_t>(table.size(), 1) * sizeof(PbgiNode));
  if (!table.empty()) table_.upload(table.data(), table.size() * sizeof(PbgiNode));
  entries_ = std::move(table);
  roots_ = std::move(roots);
  ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace nestlight::gi
