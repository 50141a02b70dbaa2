#include "nestlight/converters/export.h"

#include <cstring>
#include <memory>

#include "nestlight/converters/point_writer.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight {

uint64_t exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                      std::optional<uint32_t> level) {
  OctreeReader reader(dir);
  const Metadata& m = reader.metadata();
  SourceHeader h;
  h.path = file.string();
  h.format = "octree";
  // Colour layers travel as float x3 attributes named after them ("hdr": PLY hdr_0..2, a LAS
  // extra-bytes array): exporting must not lose the HDR colour.
  h.layout = m.layout;
  std::vector<std::unique_ptr<ColourLayerReader>> layers;
  for (const auto& l : m.layers) {
    layers.push_back(std::make_unique<ColourLayerReader>(dir, m, l.name));
    h.layout.add({l.name, ScalarType::F32, 3, "colour layer '" + l.name + "': linear RGB"});
  }
  h.rgbBits = m.rgbSourceBits;
  // The inputs' own scale and offset: a LAS file's integer coordinates come back unchanged.
  h.scale = m.scale;
  h.offset = m.sourceOffset.value_or(m.offset);
  h.crs = m.crs;
  auto writer = createWriter(file.string(), h);
  uint64_t written = 0;
  PointBatch batch;
  for (const auto& [key, entry] : reader.allNodes()) {
    if (level && key.level != *level) continue;
    if (entry.numPoints == 0) continue;
    PointBuffer pts = reader.readNode(key);
    batch.clear();
    batch.xyz.resize(pts.size() * 3);
    for (size_t i = 0; i < pts.size(); ++i)
      for (int a = 0; a < 3; ++a) batch.xyz[3 * i + a] = m.world(a, pts.pos[3 * i + a]);
    if (layers.empty()) {
      batch.attrs = std::move(pts.attrs);
    } else {
      const size_t in = m.layout.stride(), out = h.layout.stride();
      batch.attrs.assign(pts.size() * out, 0);
      for (size_t i = 0; i < pts.size(); ++i)
        std::memcpy(&batch.attrs[i * out], pts.attrsOf(i), in);
      for (size_t li = 0; li < layers.size(); ++li) {
        const std::vector<float> rgb = layers[li]->readNode(key, entry.numPoints);
        for (size_t i = 0; i < pts.size(); ++i)
          std::memcpy(&batch.attrs[i * out + in + 12 * li], &rgb[3 * i], 12);
      }
    }
    writer->write(batch);
    written += batch.size();
  }
  writer->close();
  return written;
}

}  // namespace nestlight
