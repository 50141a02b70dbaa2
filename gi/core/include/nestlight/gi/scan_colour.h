// Where a scan's light comes from: its recorded colour (16-bit sRGB, decoded to linear) or one
// of the octree's colour layers (linear already: the HDR colour `nestlight expand-hdr` writes).
// A scene's `octrees[].colour` names it; the GI frame's methods, the reference path tracer and
// the point view all read a scan's colour through this, so they light with the same values.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/metadata.h"
#include "nestlight/octree/point_buffer.h"

namespace nestlight::gi {

class ScanColours {
 public:
  // The source name of the recorded colour.
  static constexpr const char* kRecorded = "rgb";
  // Grey for a scan with neither (as the reference lights it; the point view draws such a scan by
  // elevation instead).
  static constexpr float kNoColour = 0.8f;

  // `source`: "rgb" or the name of a colour layer of the octree at `octree`. Opening a layer
  // reads its index; throws nestlight::Error naming the file when the layer is absent or
  // damaged.
  ScanColours(const std::filesystem::path& octree, const Metadata& meta, const std::string& source);

  const std::string& source() const { return source_; }
  // The layer when the source is one (the GL node store packs it into the point format).
  const std::shared_ptr<const ColourLayerReader>& layer() const { return layer_; }
  // False for "rgb" on a scan that recorded none.
  bool hasColour() const { return layer_ != nullptr || rgb_ >= 0; }

  // Linear colour of each of the node's points (3 floats each, in the order of `points`, which
  // must be the node's points as the octree decodes them). Thread-safe. Throws nestlight::Error
  // when a layer's node is missing or damaged.
  void linear(const NodeKey& key, const PointBuffer& points, std::vector<float>& rgb) const;

 private:
  std::string source_;
  int rgb_ = -1;
  size_t rgbOffset_ = 0;  // in a point's attribute bytes
  std::shared_ptr<const ColourLayerReader> layer_;
};

}  // namespace nestlight::gi
