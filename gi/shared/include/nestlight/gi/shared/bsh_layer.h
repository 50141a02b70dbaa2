// The BSH of each streamed node, built by the loader thread that loads it (never on the render
// thread) and uploaded with the node as a layer of its own: counted in the node's resident bytes
// and freed with it, so a gather can only ever read the hierarchy of a node that is resident.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "nestlight/frame/gl_node_store.h"
#include "nestlight/gi/scan_colour.h"
#include "nestlight/gi/shared/bsh.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/metadata.h"

namespace nestlight::gi {

// Leaves: the node's points, linear colour from the scan's colour source
// (nestlight/gi/scan_colour.h: the recorded 16-bit sRGB colour decoded, 0.8 grey without colour as
// the reference, or a colour layer such as the HDR colour), the scan's normals, disc radius the
// node level's nominal spacing (the distance a level's sample keeps between its points, so discs of
// that radius leave no surface uncovered where this node is the finest drawn). Points the scan's
// clipping volumes remove are left out (the node's drawn points are clipped on the GPU; its
// hierarchy is built without them).
class BshLayer : public frame::NodeLayer {
 public:
  // `colours`: where leaves take their colour; none: the recorded colour.
  // `clip`: the scan's clipping volumes; none: every point.
  explicit BshLayer(const Metadata& meta, BshOptions options = {},
                    std::shared_ptr<const ScanColours> colours = nullptr,
                    std::shared_ptr<const ClipSet> clip = nullptr);
  std::string name() const override { return "pbgi_bsh"; }
  void prepare(const NodeKey& key, const PointBuffer& points, const std::vector<uint8_t>& gpuPoints,
               std::vector<uint8_t>& out) const override;
  // The same build, returned whole (tests, tools).
  Bsh build(const NodeKey& key, const PointBuffer& points,
            const std::vector<uint8_t>& gpuPoints) const;

  // What the loader threads built so far: nodes, points, hierarchy nodes, and the thread time it
  // took (the paper's Table 1 times one build over a whole cloud; here builds run per node).
  struct Totals {
    uint64_t builds = 0, points = 0, nodes = 0, nanoseconds = 0;
  };
  Totals totals() const;

 private:
  Metadata meta_;
  BshOptions options_;
  std::shared_ptr<const ScanColours> colours_;
  std::shared_ptr<const ClipSet> clip_;
  int normal_ = -1;
  mutable std::atomic<uint64_t> builds_{0}, points_{0}, nodes_{0}, nanoseconds_{0};
};

}  // namespace nestlight::gi
