// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4: opening the scan
// (its node table, numbered in key order so every pass agrees on a point's index) and running
// the stages in the algorithm's order.
#include "expand/expansion.h"

#include <algorithm>
#include <cmath>

#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/process_memory.h"

namespace nestlight::gi::hdr::expand {

double seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

Expansion::Expansion(const fs::path& dir, const HdrImage& photo, const ExpandOptions& o,
                     Clock::time_point t0)
    : t0(t0), dir(dir), photo(photo), o(o), reader(dir), meta(reader.metadata()), scan(reader) {
  if (o.writeLayer) removeOrphanLayerFiles(dir, meta);
  nodes = reader.allNodes();
  std::sort(nodes.begin(), nodes.end(), [](auto& a, auto& b) { return a.first < b.first; });
  base.assign(nodes.size() + 1, 0);
  for (size_t i = 0; i < nodes.size(); ++i) {
    base[i + 1] = base[i] + nodes[i].second.numPoints;
    nodeIndex[nodes[i].first] = i;
  }
  rep.points = base.back();
  rep.nodes = nodes.size();
  if (rep.points == 0) throw Error(dir.string(), "", "the scan holds no points");
  if (photo.pixels() == 0) throw Error("", "", "the photograph has no pixels");
  if (!o.photoMask.empty() && o.photoMask.size() != photo.pixels())
    throw Error("", "photo mask",
                "has " + std::to_string(o.photoMask.size()) + " pixels, the photograph " +
                    std::to_string(photo.width) + " x " + std::to_string(photo.height) +
                    ": a mask is drawn on the photograph itself, at its size");
}

ExpandReport Expansion::run() {
  statistics();
  photographExposure();
  chooseViews();
  render();
  photoViewExposure();

  // PatchMatch of each rendering against the exposed photograph (display values, as the scan's
  // camera recorded them), then the HDR mapping: the photograph's values at the matches.
  auto t = Clock::now();
  expanded.resize(renderings.size());
  exposedDisplay = HdrImage(small.width, small.height);
  preparePhotoCoverage();
  match(float(std::exp2(rep.log2Exposure)));
  settleExposure();
  exposure = float(std::exp2(rep.log2Exposure));
  rejectStrays();
  bound();
  if (!o.debugDir.empty()) {
    writeExr((o.debugDir / "photo-exposed.exr").string(), exposedDisplay);
    writeViews(o.debugDir / "views.json", rep.views);
  }
  rep.seconds["patchmatch"] = seconds(t);

  backProject();
  infill();
  writeLayer();
  rep.seconds["total"] = seconds(t0);
  rep.peakRssBytes = peakRssBytes();
  return rep;
}

}  // namespace nestlight::gi::hdr::expand
