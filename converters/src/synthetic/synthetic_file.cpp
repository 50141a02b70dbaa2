// A synthetic scan written as a scan file (writeSynthetic, synthetic.h).
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/synthetic.h"

namespace nestlight {

uint64_t writeSynthetic(const SyntheticSpec& spec, const std::string& path) {
  auto src = openSynthetic(spec);
  SourceHeader h = src->header();
  h.path = path;
  if (!h.scale) h.scale = Vec3d{spec.precision, spec.precision, spec.precision};
  if (!h.offset) h.offset = spec.origin;
  auto w = createWriter(path, h);
  PointBatch batch;
  uint64_t n = 0;
  while (src->read(batch, 1 << 20)) {
    w->write(batch);
    n += batch.size();
  }
  w->close();
  return n;
}

}  // namespace nestlight
