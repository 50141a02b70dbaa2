// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4, step 6: the
// scratch file's colours, bounded, written as the octree's HDR colour layer (pass E) with the
// report as its build notes, atomically beside the scan's LDR colour, which is never changed.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cstring>

#include "expand/expansion.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/process_memory.h"

namespace nestlight::gi::hdr::expand {

void Expansion::writeLayer() {
  const auto t = Clock::now();
  if (!o.writeLayer) return;
  std::atomic<uint64_t> maxBits{0};
  // Nothing written exceeds what the photograph recorded (times the exposure): the in-fill's
  // gradients can carry a few matched values far beyond it.
  const float bound = float(checks.bound);
  std::atomic<uint64_t> bounded{0};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    std::vector<ScratchRecord> recs;
    scratch->read(base[ni], nodes[ni].second.numPoints, recs);
    float m = 0;
    uint64_t nb = 0;
    for (const auto& r : recs)
      for (int c = 0; c < 3; ++c) {
        nb += r.rgb[c] > bound;
        m = std::max(m, std::min(r.rgb[c], bound));
      }
    bounded += nb;
    uint32_t bits;
    std::memcpy(&bits, &m, 4);
    uint64_t cur = maxBits.load();
    while (bits > cur && !maxBits.compare_exchange_weak(cur, bits)) {
    }
  });
  const uint32_t bits = uint32_t(maxBits.load());
  float maxValue;
  std::memcpy(&maxValue, &bits, 4);
  rep.maxValue = maxValue;
  rep.boundedValues = bounded;
  // Half floats end at 65504: a scale keeps larger values (dynamic ranges beyond 1e5 of 1).
  const double scale = std::max(1.0, double(maxValue) / 60000.0);
  ColourLayerWriter writer(dir, o.layerName, scale);
  std::atomic<uint64_t> nodesDone{0};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    std::vector<ScratchRecord> recs;
    scratch->read(base[ni], nodes[ni].second.numPoints, recs);
    std::vector<float> rgb(recs.size() * 3);
    for (size_t i = 0; i < recs.size(); ++i)
      for (int c = 0; c < 3; ++c) rgb[3 * i + size_t(c)] = std::min(recs[i].rgb[c], bound);
    writer.writeNode(nodes[ni].first, rgb.data(), recs.size());
    progress("write layer", double(++nodesDone) / double(nodes.size()));
  });
  rep.seconds["write_layer"] = seconds(t);
  rep.seconds["total"] = seconds(t0);
  rep.peakRssBytes = peakRssBytes();
  rep.clampedValues = writer.clampedValues();
  json build = rep.toJson();
  build["mode"] = expansionModeName(o.mode);
  build["overexposed_threshold"] = o.overexposed;
  build["max_ssd"] = o.maxSsd;
  build["neighbours"] = o.neighbours;
  build["exposure_log2"] = rep.log2Exposure;
  if (!o.commandLine.is_null()) build["command"] = o.commandLine;
  writer.finish(build);
}

}  // namespace nestlight::gi::hdr::expand
