// The drawn nodes as a tree on the GPU (NL_SSBO_DRAW_TREE): for each node of the draw list, the
// index of its drawn child in each octant (-1: none) and its measured point spacing. Vertex
// shaders walk it to size each point by the finest drawn node at its position
// (shaders/points/splat_size.glsl). Uploaded once per frame, read by every pass that draws points.
#pragma once

#include <vector>

#include "nestlight/gl/resources.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::frame {

class DrawTree {
 public:
  // Entry k is nodes[k]; the draw list puts parents first.
  void upload(const std::vector<streaming::DrawNode>& nodes);
  void bind() const;
  size_t bytes() const { return bytes_; }

 private:
  gl::Buffer buffer_;
  size_t bytes_ = 0;
};

}  // namespace nestlight::frame
