// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.2, step 5: the
// gradient-domain in-fill (eq. 3, poisson_infill.h) of the over-exposed points left without a
// value, chunk by chunk so that memory stays bounded (pass D). The paper solves the whole cloud
// at once; the chunks, their overlap margins and the adaptive tiling are ours.
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

namespace {

// The points of one chunk's box, as the in-fill takes them, and where each came from.
struct Chunk {
  struct Origin {
    uint32_t node;
    uint32_t index;
    bool core;  // inside the chunk's cube, not its margin: written back
  };
  std::vector<glm::vec3> pos, ldr, hdr;
  std::vector<InfillRole> role;
  std::vector<Origin> from;
};

// Gather every point in the cube's box (the cube and its margin), from every node whose cube
// meets it.
Chunk gather(Expansion& x, const Box3d& cube, const Box3d& box) {
  const glm::dvec3 origin{(cube.min.x + cube.max.x) / 2, (cube.min.y + cube.max.y) / 2,
                          (cube.min.z + cube.max.z) / 2};
  Chunk c;
  for (size_t ni = 0; ni < x.nodes.size(); ++ni) {
    const auto& [key, entry] = x.nodes[ni];
    if (entry.numPoints == 0) continue;
    const Box3d nb = x.meta.nodeBounds(key.level, key.x, key.y, key.z);
    if (nb.min.x > box.max.x || nb.max.x < box.min.x || nb.min.y > box.max.y ||
        nb.max.y < box.min.y || nb.min.z > box.max.z || nb.max.z < box.min.z)
      continue;
    const ScanNode n = x.scan.read(key, entry);
    std::vector<ScratchRecord> recs;
    x.scratch->read(x.base[ni], n.world.size(), recs);
    for (size_t i = 0; i < n.world.size(); ++i) {
      const glm::dvec3& w = n.world[i];
      if (w.x < box.min.x || w.x > box.max.x || w.y < box.min.y || w.y > box.max.y ||
          w.z < box.min.z || w.z > box.max.z)
        continue;
      const bool core = w.x >= cube.min.x && w.x < cube.max.x && w.y >= cube.min.y &&
                        w.y < cube.max.y && w.z >= cube.min.z && w.z < cube.max.z;
      c.pos.push_back(glm::vec3(w - origin));
      c.ldr.push_back(n.ldr[i]);
      c.hdr.push_back({recs[i].rgb[0], recs[i].rgb[1], recs[i].rgb[2]});
      c.role.push_back(recs[i].state == kTarget ? InfillRole::Target : InfillRole::Fixed);
      c.from.push_back({uint32_t(ni), uint32_t(i), core});
    }
  }
  return c;
}

}  // namespace

// Chunks tile the octree's cube adaptively: a cube is split while its points (its subtree's,
// plus its share of its ancestors') exceed the budget. Only chunks holding points to in-fill are
// solved; they come back in key order.
std::vector<NodeKey> Expansion::infillChunks() {
  std::unordered_map<NodeKey, uint64_t, NodeKeyHash> subtree;
  for (const auto& [key, e] : nodes)
    for (NodeKey k = key;; k = k.parent()) {
      subtree[k] += e.numPoints;
      if (k.level == 0) break;
    }
  auto estimate = [&](const NodeKey& c) {
    double s = 0;
    if (auto it = subtree.find(c); it != subtree.end()) s = double(it->second);
    for (uint32_t l = 0; l < c.level; ++l) {
      auto it = nodeIndex.find(c.ancestor(l));
      if (it != nodeIndex.end())
        s += double(nodes[it->second].second.numPoints) / std::pow(8.0, c.level - l);
    }
    return s;
  };
  std::unordered_set<NodeKey, NodeKeyHash> cells;
  std::vector<NodeKey> stack{NodeKey::root()};
  while (!stack.empty()) {
    const NodeKey c = stack.back();
    stack.pop_back();
    if (estimate(c) > double(o.chunkPoints) && c.level < meta.depth && subtree.count(c)) {
      for (int i = 0; i < 8; ++i) stack.push_back(c.child(i));
    } else {
      cells.insert(c);
    }
  }
  // Which cells hold points to in-fill.
  auto cellOf = [&](const uint32_t* q) {
    for (uint32_t l = 0;; ++l) {
      const uint32_t s = meta.cubeSize >> l;
      const NodeKey k{l, q[0] / s, q[1] / s, q[2] / s};
      if (cells.count(k) || l >= 31) return k;
    }
  };
  std::unordered_map<NodeKey, uint64_t, NodeKeyHash> cellTargets;
  for (size_t ni = 0; ni < nodes.size(); ++ni) {
    if (nodes[ni].second.numPoints == 0) continue;
    std::vector<ScratchRecord> recs;
    scratch->read(base[ni], nodes[ni].second.numPoints, recs);
    bool any = false;
    for (const auto& r : recs) any = any || r.state == kTarget;
    if (!any) continue;
    const PointBuffer pts = reader.readNode(nodes[ni].first);
    for (size_t i = 0; i < recs.size(); ++i)
      if (recs[i].state == kTarget) cellTargets[cellOf(&pts.pos[3 * i])]++;
  }
  std::vector<NodeKey> todo;
  for (const auto& [k, n] : cellTargets) todo.push_back(k);
  std::sort(todo.begin(), todo.end());
  return todo;
}

void Expansion::infillChunk(const NodeKey& cell, const InfillOptions& io) {
  const double finest = meta.levelSpacing(meta.depth);
  const Box3d cube = meta.nodeBounds(cell.level, cell.x, cell.y, cell.z);
  const double margin = std::max(0.1 * (cube.max.x - cube.min.x), 16.0 * finest);
  Box3d box = cube;
  box.min = {cube.min.x - margin, cube.min.y - margin, cube.min.z - margin};
  box.max = {cube.max.x + margin, cube.max.y + margin, cube.max.z + margin};
  Chunk c = gather(*this, cube, box);
  rep.chunks++;
  rep.chunkMaxPoints = std::max<uint64_t>(rep.chunkMaxPoints, c.pos.size());
  std::vector<InfillOutcome> outcome;
  const InfillStats st = poissonInfill(c.pos, c.ldr, c.hdr, c.role, io, &outcome);
  rep.cgIterationsMax = std::max<uint64_t>(rep.cgIterationsMax, st.cgIterations);
  // Write back the core's solved points, node by node.
  std::unordered_map<uint32_t, std::vector<size_t>> byNode;
  for (size_t i = 0; i < c.from.size(); ++i)
    if (c.from[i].core && c.role[i] == InfillRole::Target) byNode[c.from[i].node].push_back(i);
  for (auto& [ni, list] : byNode) {
    std::vector<ScratchRecord> recs;
    scratch->read(base[ni], nodes[ni].second.numPoints, recs);
    for (size_t i : list) {
      ScratchRecord& r = recs[c.from[i].index];
      r.rgb[0] = c.hdr[i].r, r.rgb[1] = c.hdr[i].g, r.rgb[2] = c.hdr[i].b;
      if (outcome[i] == InfillOutcome::Island) {
        r.state = kIsland;
        rep.islandPoints++;
      } else {
        r.state = kInfilled;
        rep.infilled++;
      }
    }
    scratch->write(base[ni], recs);
  }
  rep.islands += st.islands;  // components, counted per chunk (one may span two chunks)
}

void Expansion::infill() {
  const auto t = Clock::now();
  if (targets > 0) {
    const std::vector<NodeKey> todo = infillChunks();
    InfillOptions io;
    io.k = o.neighbours;
    io.mode = o.mode == ExpansionMode::Rgb ? InfillMode::Rgb : InfillMode::Luminance;
    for (size_t ci = 0; ci < todo.size(); ++ci) {
      infillChunk(todo[ci], io);
      progress("in-fill", double(ci + 1) / double(todo.size()));
    }
  }
  rep.seconds["infill"] = seconds(t);
}

}  // namespace nestlight::gi::hdr::expand
