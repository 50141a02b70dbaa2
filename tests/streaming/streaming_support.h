// Helpers of the streaming tests: small octrees built with the library, cameras, an independent
// computation of the ideal cut, and the invariants every frame must keep.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <ostream>
#include <queue>
#include <set>
#include <thread>
#include <vector>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/memory_store.h"
#include "nestlight/streaming/streamer.h"
#include "nestlight/streaming/view.h"

namespace nestlight {
// Readable node keys in gtest messages.
inline void PrintTo(const NodeKey& k, std::ostream* os) {
  *os << k.name();
}
}  // namespace nestlight

namespace nestlight::test {

// Converts a synthetic scan into `dir`; small nodes give deep trees (several hierarchy chunks)
// from few points.
inline Metadata buildSyntheticOctree(const std::filesystem::path& dir, const SyntheticSpec& spec,
                                     uint32_t maxNodePoints = 1000) {
  BuildOptions o;
  o.output = dir;
  o.progress = ProgressMode::Quiet;
  o.threads = 2;
  o.maxNodePoints = maxNodePoints;
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openSynthetic(spec));
  return buildOctree(std::move(r), o).metadata;
}

inline glm::dvec3 boundsCenter(const Metadata& m) {
  return {0.5 * (m.bounds.min.x + m.bounds.max.x), 0.5 * (m.bounds.min.y + m.bounds.max.y),
          0.5 * (m.bounds.min.z + m.bounds.max.z)};
}

inline streaming::View camera(const glm::dvec3& eye, const glm::dvec3& target, int w = 1280,
                              int h = 720) {
  return streaming::perspectiveView(eye, target, {0, 0, 1}, glm::radians(60.0), w, h, 0.01, 1e5);
}

// The cut the scheduler should reach, computed from every node of the octree (read through the
// reader's blocking API) with the rule streamer.h states, written independently of the library:
// from the root in decreasing projected radius of the node's bounding sphere (node cube clipped
// to the scan's bounds; distance from the eye to the sphere), ties in NodeKey order; visible
// nodes enter while the point and byte budgets hold (the first that does not fit ends the cut);
// a node's children are candidates when its spacing projects to more than spacingPixels.
inline std::vector<NodeKey> idealCut(OctreeReader& reader, const streaming::View& view,
                                     const streaming::Budgets& b, double bytesPerPoint) {
  const Metadata& m = reader.metadata();
  std::map<NodeKey, HierarchyEntry> entries;
  for (auto& [k, e] : reader.allNodes()) entries[k] = e;
  const streaming::Frustum frustum(view.clipFromWorld);
  struct Cand {
    double weight, distance;
    NodeKey key;
  };
  auto lower = [](const Cand& a, const Cand& c) {
    return a.weight != c.weight ? a.weight < c.weight : c.key < a.key;
  };
  std::priority_queue<Cand, std::vector<Cand>, decltype(lower)> heap(lower);
  auto consider = [&](const NodeKey& k) {
    Box3d box;
    double c[3], r2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double size = double(m.cubeSize >> k.level) * m.scale[a];
      const double lo = m.offset[a] + (a == 0 ? k.x : a == 1 ? k.y : k.z) * size;
      const double clo = std::max(lo, m.bounds.min[a]), chi = std::min(lo + size, m.bounds.max[a]);
      box.min[a] = clo;
      box.max[a] = chi;
      c[a] = 0.5 * (clo + chi);
      r2 += (0.5 * (chi - clo)) * (0.5 * (chi - clo));
    }
    if (!frustum.intersects(box)) return;
    const double r = std::sqrt(r2);
    const double dx = c[0] - view.eye.x, dy = c[1] - view.eye.y, dz = c[2] - view.eye.z;
    const double d = std::max(std::sqrt(dx * dx + dy * dy + dz * dz) - r, 0.0);
    heap.push({view.projectedPixels(r, d), d, k});
  };
  std::vector<NodeKey> cut;
  uint64_t points = 0, bytes = 0;
  consider(NodeKey::root());
  while (!heap.empty()) {
    Cand c = heap.top();
    heap.pop();
    const HierarchyEntry& e = entries.at(c.key);
    const uint64_t nb = static_cast<uint64_t>(std::ceil(e.numPoints * bytesPerPoint));
    if (points + e.numPoints > b.points || bytes + nb > b.gpuBytes) break;
    points += e.numPoints;
    bytes += nb;
    cut.push_back(c.key);
    const double spacing = m.spacing / std::pow(2.0, c.key.level);
    if (!e.childMask || !(view.projectedPixels(spacing, c.distance) > b.spacingPixels)) continue;
    for (int i = 0; i < 8; ++i)
      if (e.childMask & (1u << i)) consider(c.key.child(i));
  }
  return cut;
}

// The drawn nodes, sorted (the draw list's own order is parents first, not more; the order is
// checked by expectFrameInvariants).
inline std::vector<NodeKey> drawKeys(const streaming::Streamer& s) {
  std::vector<NodeKey> out;
  for (const auto& d : s.drawList()) out.push_back(d.key);
  std::sort(out.begin(), out.end());
  return out;
}

inline std::vector<NodeKey> sorted(std::vector<NodeKey> v) {
  std::sort(v.begin(), v.end());
  return v;
}

// What every frame must keep: the byte budget (also as the store saw it), stats that agree with
// the store, no node drawn before its parent, handles that hold the node they claim.
inline void expectFrameInvariants(const streaming::Streamer& s, const streaming::MemoryStore& store,
                                  const streaming::Budgets& b) {
  const streaming::FrameStats& st = s.stats();
  EXPECT_LE(st.residentBytes, b.gpuBytes) << "frame " << st.frame;
  EXPECT_EQ(st.residentBytes, store.liveBytes()) << "frame " << st.frame;
  EXPECT_EQ(st.residentNodes, store.liveHandles()) << "frame " << st.frame;
  EXPECT_LE(st.drawPoints, b.points);
  EXPECT_LE(st.cutPoints, b.points);
  EXPECT_LE(st.drawNodes, st.cutNodes);
  std::set<NodeKey> seen;
  for (const auto& d : s.drawList()) {
    if (d.key.level > 0) {
      EXPECT_TRUE(seen.count(d.key.parent())) << d.key.name() << " before its parent";
    }
    EXPECT_EQ(store.keyOf(d.handle), d.key);
    seen.insert(d.key);
  }
}

// Updates with `view` until the cut is complete; returns the frames it took, or -1 after
// `maxFrames`. Frames are paced (1 ms) so that the bound means time for the loaders.
inline int runUntilComplete(streaming::Streamer& s, const streaming::View& view, int maxFrames,
                            const std::function<void()>& everyFrame = {}) {
  for (int f = 1; f <= maxFrames; ++f) {
    const bool complete = s.update(view).complete;
    if (everyFrame) everyFrame();
    if (complete) return f;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return -1;
}

// Updates until no request is queued or in flight.
inline bool drain(streaming::Streamer& s, const streaming::View& view, int maxFrames = 5000) {
  for (int f = 0; f < maxFrames; ++f) {
    const auto& st = s.update(view);
    if (st.queueLength == 0 && st.inFlight == 0) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

}  // namespace nestlight::test
