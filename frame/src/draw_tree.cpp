#include "nestlight/frame/draw_tree.h"

#include <cstring>
#include <unordered_map>

#include "nestlight/frame/interface.h"

namespace nestlight::frame {

void DrawTree::upload(const std::vector<streaming::DrawNode>& nodes) {
  // 12 words per node (std430 struct of 8 ints and 4 floats): the drawn child in each octant, the
  // spacing, padding.
  std::vector<int32_t> words(std::max<size_t>(nodes.size(), 1) * 12, -1);
  std::unordered_map<NodeKey, int32_t, NodeKeyHash> index;
  index.reserve(nodes.size());
  for (size_t k = 0; k < nodes.size(); ++k) {
    const auto& n = nodes[k];
    index.emplace(n.key, int32_t(k));
    // The streamer fills pointSpacing (the nominal spacing where none was measured); a draw list
    // made by hand may leave it 0.
    const float spacing = float(n.pointSpacing > 0 ? n.pointSpacing : n.spacing);
    std::memcpy(&words[12 * k + 8], &spacing, 4);
    if (n.key.level == 0) continue;
    auto parent = index.find(n.key.parent());
    if (parent != index.end()) words[12 * size_t(parent->second) + n.key.childIndex()] = int32_t(k);
  }
  bytes_ = words.size() * 4;
  buffer_.reserve(std::max(bytes_, size_t(4096)));
  buffer_.upload(words.data(), bytes_);
}

void DrawTree::bind() const {
  buffer_.bindRange(GL_SHADER_STORAGE_BUFFER, NL_SSBO_DRAW_TREE, 0, bytes_);
}

}  // namespace nestlight::frame
