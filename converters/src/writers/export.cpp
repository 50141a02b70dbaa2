#include "nestlight/converters/export.h"

#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>

#include <cstring>
#include <memory>
#include <thread>
#include <unordered_map>

#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/progress.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight {
namespace {

struct Selected {
  NodeKey key;
  HierarchyEntry entry;
  Overlap overlap;  // Partial: test each point; All: keep every point
};

// The nodes to read, breadth first, each with how the clipping volumes meet its cube. A node
// under one kept whole is kept whole without a test; one outside them is never read.
std::vector<Selected> selectNodes(OctreeReader& reader, const ExportOptions& o,
                                  ExportReport& report) {
  const Metadata& m = reader.metadata();
  std::unordered_map<NodeKey, Overlap, NodeKeyHash> overlaps;
  std::vector<Selected> out;
  for (const auto& [key, entry] : reader.allNodes()) {
    Overlap ov = Overlap::All;
    if (o.clip && !o.clip->empty()) {
      Overlap parent = Overlap::Partial;
      if (key.level > 0) {
        auto it = overlaps.find(key.parent());
        // A parent outside never got its children listed as kept; breadth first, it is known.
        if (it != overlaps.end()) parent = it->second;
      }
      ov = parent == Overlap::Partial ? o.clip->keeps(m.nodeBounds(key.level, key.x, key.y, key.z))
                                      : parent;
      overlaps[key] = ov;
    }
    if (o.level && key.level != *o.level) continue;
    if (entry.numPoints == 0) continue;
    if (ov == Overlap::None) {
      ++report.nodesSkipped;
      continue;
    }
    out.push_back({key, entry, ov});
  }
  return out;
}

}  // namespace

ExportReport walkClipped(const std::filesystem::path& dir, const ExportOptions& o,
                         const std::function<void(ClippedNode&)>& parallel,
                         const std::function<void(ClippedNode&)>& serial) {
  OctreeReader reader(dir);
  const Metadata& m = reader.metadata();
  ExportReport report;
  const std::vector<Selected> nodes = selectNodes(reader, o, report);
  uint64_t total = 0;
  for (const Selected& s : nodes) total += s.entry.numPoints;
  if (o.progress) o.progress->begin("read", total, "points");

  // Colour layers travel as float x3 attributes after the stored ones (see exportHeader).
  std::vector<std::unique_ptr<ColourLayerReader>> layers;
  for (const auto& l : m.layers)
    layers.push_back(std::make_unique<ColourLayerReader>(dir, m, l.name));
  const size_t in = m.layout.stride(), out = in + 12 * layers.size();

  const unsigned threads =
      o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  size_t next = 0;
  std::atomic<uint64_t> tested{0};
  tbb::parallel_pipeline(
      threads * 2, tbb::make_filter<void, std::shared_ptr<ClippedNode>>(
                       tbb::filter_mode::serial_in_order,
                       [&](tbb::flow_control& fc) -> std::shared_ptr<ClippedNode> {
                         if (next == nodes.size()) {
                           fc.stop();
                           return nullptr;
                         }
                         auto n = std::make_shared<ClippedNode>();
                         n->key = nodes[next].key;
                         n->entry = nodes[next].entry;
                         n->whole = nodes[next].overlap == Overlap::All;
                         ++next;
                         return n;
                       }) &
                       tbb::make_filter<std::shared_ptr<ClippedNode>, std::shared_ptr<ClippedNode>>(
                           tbb::filter_mode::parallel,
                           [&](std::shared_ptr<ClippedNode> n) {
                             const bool whole = n->whole;
                             PointBuffer pts = reader.readNode(n->key);
                             std::vector<std::vector<float>> rgb;
                             for (auto& l : layers)
                               rgb.push_back(l->readNode(n->key, n->entry.numPoints));
                             PointBatch& b = n->batch;
                             b.xyz.resize(pts.size() * 3);
                             b.attrs.resize(pts.size() * out);
                             uint64_t t = 0;
                             size_t k = 0;  // points kept so far
                             for (size_t i = 0; i < pts.size(); ++i) {
                               const Vec3d w = m.worldPoint(&pts.pos[3 * i]);
                               if (!whole) {
                                 ++t;
                                 if (!o.clip->keeps(w)) continue;
                               }
                               b.xyz[3 * k] = w.x, b.xyz[3 * k + 1] = w.y, b.xyz[3 * k + 2] = w.z;
                               uint8_t* a = b.attrs.data() + k * out;
                               std::memcpy(a, pts.attrsOf(i), in);
                               for (size_t li = 0; li < rgb.size(); ++li)
                                 std::memcpy(a + in + 12 * li, &rgb[li][3 * i], 12);
                               ++k;
                             }
                             b.xyz.resize(3 * k);
                             b.attrs.resize(k * out);
                             tested += t;
                             if (parallel) parallel(*n);
                             return n;
                           }) &
                       tbb::make_filter<std::shared_ptr<ClippedNode>, void>(
                           tbb::filter_mode::serial_in_order, [&](std::shared_ptr<ClippedNode> n) {
                             ++report.nodes;
                             report.pointsRead += n->entry.numPoints;
                             report.payloadBytes += n->entry.byteSize;
                             report.points += n->batch.size();
                             serial(*n);
                             if (o.progress)
                               o.progress->advance(n->entry.numPoints, n->entry.numPoints);
                           }));
  report.pointsTested = tested;
  for (const Selected& s : nodes) report.nodesWhole += s.overlap == Overlap::All;
  if (o.progress) o.progress->end();
  return report;
}

ExportReport exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                          const ExportOptions& o) {
  Metadata m;
  {
    OctreeReader reader(dir);
    m = reader.metadata();
  }
  SourceHeader h;
  h.path = file.string();
  h.format = "octree";
  // Colour layers travel as float x3 attributes named after them ("hdr": PLY hdr_0..2, a LAS
  // extra-bytes array): exporting must not lose the HDR colour.
  h.layout = m.layout;
  for (const auto& l : m.layers)
    h.layout.add({l.name, ScalarType::F32, 3, "colour layer '" + l.name + "': linear RGB"});
  h.rgbBits = m.rgbSourceBits;
  // The inputs' own scale and offset: a LAS file's integer coordinates come back unchanged.
  h.scale = m.scale;
  h.offset = m.sourceOffset.value_or(m.offset);
  h.crs = m.crs;
  auto writer = createWriter(file.string(), h);
  ExportReport r = walkClipped(dir, o, nullptr, [&](ClippedNode& n) {
    if (n.batch.size()) writer->write(n.batch);
  });
  writer->close();
  return r;
}

uint64_t exportOctree(const std::filesystem::path& dir, const std::filesystem::path& file,
                      std::optional<uint32_t> level) {
  ExportOptions o;
  o.level = level;
  return exportOctree(dir, file, o).points;
}

ExportReport selectOctree(const std::filesystem::path& dir, const ExportOptions& o) {
  OctreeReader reader(dir);
  ExportReport report;
  for (const Selected& s : selectNodes(reader, o, report)) {
    ++report.nodes;
    report.nodesWhole += s.overlap == Overlap::All;
    report.pointsRead += s.entry.numPoints;
    report.payloadBytes += s.entry.byteSize;
  }
  return report;
}

ExportReport countOctree(const std::filesystem::path& dir, const ExportOptions& o) {
  OctreeReader reader(dir);
  const Metadata& m = reader.metadata();
  ExportReport report;
  const std::vector<Selected> nodes = selectNodes(reader, o, report);
  uint64_t total = 0;
  for (const Selected& s : nodes)
    if (s.overlap == Overlap::Partial) total += s.entry.numPoints;
  if (o.progress) o.progress->begin("count", total, "points");
  std::vector<const Selected*> partial;
  for (const Selected& s : nodes) {
    ++report.nodes;
    if (s.overlap == Overlap::All) {
      ++report.nodesWhole;
      report.points += s.entry.numPoints;
    } else {
      partial.push_back(&s);
    }
  }
  const unsigned threads =
      o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency());
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  std::atomic<uint64_t> kept{0}, read{0}, bytes{0};
  std::atomic<size_t> next{0};
  std::vector<std::thread> pool;
  std::exception_ptr failure;
  std::mutex failureMutex;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      try {
        for (size_t i; (i = next++) < partial.size();) {
          const Selected& s = *partial[i];
          PointBuffer pts = reader.readNode(s.key);
          uint64_t k = 0;
          for (size_t p = 0; p < pts.size(); ++p) k += o.clip->keeps(m.worldPoint(&pts.pos[3 * p]));
          kept += k;
          read += pts.size();
          bytes += s.entry.byteSize;
          if (o.progress) o.progress->advance(pts.size(), pts.size());
        }
      } catch (...) {
        std::lock_guard<std::mutex> lock(failureMutex);
        if (!failure) failure = std::current_exception();
        next = partial.size();
      }
    });
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  if (o.progress) o.progress->end();
  report.points += kept;
  report.pointsRead = report.pointsTested = read;
  report.payloadBytes = bytes;
  return report;
}

}  // namespace nestlight
