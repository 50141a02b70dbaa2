#include "nestlight/converters/export.h"

#include "nestlight/converters/point_writer.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight {

uint64_t exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                      std::optional<uint32_t> level) {
  OctreeReader reader(dir);
  const Metadata& m = reader.metadata();
  SourceHeader h;
  h.path = file.string();
  h.format = "octree";
  h.layout = m.layout;
  h.rgbBits = m.rgbSourceBits;
  h.scale = Vec3d{m.scale, m.scale, m.scale};
  h.offset = m.offset;
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
      for (int a = 0; a < 3; ++a) batch.xyz[3 * i + a] = m.offset[a] + pts.pos[3 * i + a] * m.scale;
    batch.attrs = std::move(pts.attrs);
    writer->write(batch);
    written += batch.size();
  }
  writer->close();
  return written;
}

}  // namespace nestlight
