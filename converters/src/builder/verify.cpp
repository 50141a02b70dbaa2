#include "nestlight/converters/verify.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/staged_directory.h"

namespace nestlight {

namespace fs = std::filesystem;

namespace {

// One colour layer: it opens, covers every node, and holds one finite, non-negative colour per
// point.
template <class Fail>
void verifyLayer(const fs::path& dir, const Metadata& m, const LayerRecord& l,
                 const std::vector<std::pair<NodeKey, HierarchyEntry>>& nodes, uint64_t sum,
                 Fail& fail, VerifyReport& rep) {
  std::unique_ptr<ColourLayerReader> layer;
  try {
    layer = std::make_unique<ColourLayerReader>(dir, m, l.name);
  } catch (const std::exception& ex) {
    fail("layer '" + l.name + "': " + ex.what());
    return;
  }
  rep.layers++;
  if (layer->entries().size() != nodes.size())
    fail("layer '" + l.name + "' has " + std::to_string(layer->entries().size()) +
         " nodes, the octree " + std::to_string(nodes.size()));
  uint64_t layerPoints = 0;
  for (const auto& e : layer->entries()) layerPoints += e.points;
  if (layerPoints != l.points || layerPoints != sum)
    fail("layer '" + l.name + "' holds " + std::to_string(layerPoints) + " colours (metadata: " +
         std::to_string(l.points) + ") for " + std::to_string(sum) + " points");
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t i) {
    const auto& [k, e] = nodes[i];
    try {
      const std::vector<float> rgb = layer->readNode(k, e.numPoints);
      for (size_t v = 0; v < rgb.size(); ++v)
        if (!(rgb[v] >= 0) || !std::isfinite(rgb[v])) {
          fail("layer '" + l.name + "', node " + k.name() + ": point " + std::to_string(v / 3) +
               " has a negative or non-finite colour");
          return;
        }
    } catch (const std::exception& ex) {
      fail("layer '" + l.name + "': " + ex.what());
    }
  });
}

}  // namespace

VerifyReport verifyOctree(const fs::path& dir, unsigned maxFailures) {
  VerifyReport rep;
  std::mutex mutex;
  auto fail = [&](const std::string& s) {
    std::lock_guard<std::mutex> lock(mutex);
    if (rep.failures.size() < maxFailures) rep.failures.push_back(s);
  };
  std::unique_ptr<OctreeReader> reader;
  try {
    reader = std::make_unique<OctreeReader>(dir);
  } catch (const std::exception& e) {
    fail(e.what());
    return rep;
  }
  const Metadata& m = reader->metadata();
  std::error_code ec;
  auto size = fs::file_size(dir / m.payloadFile, ec);
  if (ec || size != m.payloadBytes)
    fail(m.payloadFile + ": size " + std::to_string(ec ? 0 : size) + " differs from metadata's " +
         std::to_string(m.payloadBytes));
  size = fs::file_size(dir / m.hierarchyFile, ec);
  if (ec || size != m.hierarchyBytes)
    fail(m.hierarchyFile + ": size " + std::to_string(ec ? 0 : size) + " differs from metadata's " +
         std::to_string(m.hierarchyBytes));

  std::vector<std::pair<NodeKey, HierarchyEntry>> nodes;
  try {
    nodes = reader->allNodes();
  } catch (const std::exception& e) {
    fail(e.what());
    return rep;
  }
  rep.nodes = nodes.size();
  if (nodes.size() != m.nodes)
    fail("hierarchy holds " + std::to_string(nodes.size()) + " nodes, metadata says " +
         std::to_string(m.nodes));

  // Payload ranges must not overlap and must account for the whole payload file.
  std::vector<std::pair<uint64_t, uint64_t>> ranges;
  uint64_t sum = 0;
  for (auto& [k, e] : nodes) {
    if (e.type == NodeType::Proxy)
      fail("node " + k.name() + " remains a proxy after loading its chunk");
    if (k.level > m.depth) fail("node " + k.name() + " is deeper than metadata's depth");
    if (e.byteSize) ranges.emplace_back(e.byteOffset, e.byteSize);
    sum += e.numPoints;
  }
  std::sort(ranges.begin(), ranges.end());
  uint64_t covered = 0, end = 0;
  for (auto& [o, s] : ranges) {
    if (o < end) fail("payloads overlap at byte " + std::to_string(o));
    end = std::max(end, o + s);
    covered += s;
  }
  if (covered != m.payloadBytes)
    fail("node payloads cover " + std::to_string(covered) + " bytes of " +
         std::to_string(m.payloadBytes));

  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t i) {
    const auto& [k, e] = nodes[i];
    try {
      PointBuffer pts = reader->readNode(k);
      if (pts.size() != e.numPoints) {
        fail("node " + k.name() + " decodes to " + std::to_string(pts.size()) +
             " points, expected " + std::to_string(e.numPoints));
        return;
      }
      const uint64_t s = m.cubeSize >> k.level;
      const uint64_t base[3] = {k.x * s, k.y * s, k.z * s};
      for (size_t p = 0; p < pts.size(); ++p)
        for (int a = 0; a < 3; ++a) {
          uint64_t v = pts.pos[3 * p + a];
          if (v < base[a] || v >= base[a] + s) {
            fail("node " + k.name() + ": point " + std::to_string(p) +
                 " lies outside the node's cube");
            return;
          }
        }
      std::lock_guard<std::mutex> lock(mutex);
      rep.payloadBytes += e.byteSize;
    } catch (const std::exception& ex) {
      fail(ex.what());
    }
  });
  rep.points = sum;

  const Accounting& a = m.accounting;
  if (sum != m.points)
    fail("nodes hold " + std::to_string(sum) + " points, metadata says " +
         std::to_string(m.points));
  if (a.kept != m.points)
    fail("accounting: kept " + std::to_string(a.kept) + " differs from points stored " +
         std::to_string(m.points));
  if (!a.balanced())
    fail("accounting does not balance: input " + std::to_string(a.input) + " != kept " +
         std::to_string(a.kept) + " + merged " + std::to_string(a.duplicatesMerged) +
         " + rejected " + std::to_string(a.rejectedTotal()));
  for (const LayerRecord& l : m.layers) verifyLayer(dir, m, l, nodes, sum, fail, rep);
  for (const auto& n : orphanLayerFiles(dir, m))
    rep.notes.push_back(n +
                        ": a layer file metadata.json does not name (left by an interrupted run; "
                        "the next `expand-hdr` deletes it)");
  for (const auto& p : staleStagingFolders(dir)) {
    std::error_code ec;
    uint64_t bytes = 0;
    for (const auto& e : fs::recursive_directory_iterator(p, ec))
      if (e.is_regular_file(ec)) bytes += e.file_size(ec);
    rep.notes.push_back(
        p.string() + ": " + std::to_string(bytes) +
        " bytes left by a conversion that was killed (the next `convert` to this output "
        "removes it; so may you)");
  }

  // A lenient conversion counts a source's undecodable points as input it rejected.
  uint64_t fromSources = 0;
  for (auto& s : m.sources) fromSources += s.points + s.unreadable;
  if (!m.sources.empty() && fromSources != a.input)
    fail("sources report " + std::to_string(fromSources) +
         " points read or unreadable, accounting says input " + std::to_string(a.input));
  return rep;
}

}  // namespace nestlight
