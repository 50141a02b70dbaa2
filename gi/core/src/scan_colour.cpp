#include "nestlight/gi/scan_colour.h"

#include <cstring>

#include "nestlight/gi/srgb.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

ScanColours::ScanColours(const std::filesystem::path& octree, const Metadata& meta,
                         const std::string& source)
    : source_(source) {
  if (source == kRecorded) {
    rgb_ = meta.layout.find(attr::kRgb);
    if (rgb_ >= 0 && (meta.layout[size_t(rgb_)].type != ScalarType::U16 ||
                      meta.layout[size_t(rgb_)].components != 3))
      throw Error(octree.empty() ? "the scan" : octree.string(), "",
                  "its rgb attribute is not uint16 x3");
    if (rgb_ >= 0) rgbOffset_ = meta.layout.offset(rgb_);
  } else {
    layer_ = std::make_shared<const ColourLayerReader>(octree, meta, source);
    if (layer_->record().kind != "colour")
      throw Error(
          octree.string(), "",
          "layer '" + source + "' is a '" + layer_->record().kind + "' layer, not a colour");
  }
}

void ScanColours::linear(const NodeKey& key, const PointBuffer& points,
                         std::vector<float>& rgb) const {
  const size_t n = points.size();
  if (layer_) {
    rgb = layer_->readNode(key, uint32_t(n));
    return;
  }
  rgb.assign(3 * n, kNoColour);
  if (rgb_ < 0) return;
  for (size_t i = 0; i < n; ++i) {
    uint16_t v[3];
    std::memcpy(v, points.attrsOf(i) + rgbOffset_, 6);
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = srgbDecode(v[c] / 65535.0f);
  }
}

}  // namespace nestlight::gi
