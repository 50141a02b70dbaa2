// The builder's last passes: node files written, the levels above the chunks merged from their
// provisional samples, the metadata finished.
#include "builder_passes.h"

namespace nestlight::build_passes {

// `drawnSet`: `set` and the ancestors' points inside the node (a superset of `set`, in Morton
// order), on which the node's spacing is measured.
void Builder::writeNode(const NodeKey& key, const PointBuffer& pts,
                        const std::vector<uint32_t>& set, const std::vector<uint32_t>& drawnSet) {
  PointBuffer local(stride_);
  local.reserve(set.size());
  const uint32_t size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * size, key.y * size, key.z * size};
  for (uint32_t i : set) {
    const uint32_t* p = &pts.pos[3 * size_t(i)];
    const uint32_t rel[3] = {p[0] - base[0], p[1] - base[1], p[2] - base[2]};
    NL_CHECK(rel[0] < size && rel[1] < size && rel[2] < size);
    local.push(rel, pts.attrsOf(i));
  }
  // In integer steps; the largest axis step makes it world units (the axes' steps differ by a
  // few per cent at most where they differ at all).
  const double measured =
      medianNeighbourSpacing(pts.pos.data(), drawnSet.data(), drawnSet.size()) * meta_.maxScale();
  writer_->writeNode(key, local, encodeSpacing(measured, meta_.levelSpacing(key.level)));
  stored_ += set.size();
}

void Builder::saveProvisional(const NodeKey& key, const PointBuffer& pts,
                              const std::vector<uint32_t>& set, uint64_t subtreePoints) {
  saveRecords(provisionalFile(key), pts, set);
  std::lock_guard<std::mutex> lock(pendingMutex_);
  pending_.insert(key);
  subtreePoints_[key] = subtreePoints;
}

void Builder::mergeTop() {
  if (distributed()) return mergeTopDistributed();
  // Nodes above the chunks.
  std::set<NodeKey> above;
  for (const NodeKey& k : pending_)
    for (uint32_t l = 0; l < k.level; ++l) above.insert(k.ancestor(l));
  mergeNodes(above);
  writeRoot();
}

void Builder::mergeNodes(const std::set<NodeKey>& above) {
  // Deepest first; each level's nodes in parallel.
  std::map<uint32_t, std::set<NodeKey>> byLevel;
  for (const NodeKey& k : above) byLevel[k.level].insert(k);
  progress_.begin("merge", byLevel.empty() ? 1 : byLevel.rbegin()->first + 1, "levels");
  for (auto it = byLevel.rbegin(); it != byLevel.rend(); ++it) {
    std::vector<NodeKey> nodes(it->second.begin(), it->second.end());
    tbb::parallel_for_each(nodes.begin(), nodes.end(), [&](const NodeKey& key) {
      PointBuffer pts(stride_);
      std::array<std::vector<uint32_t>, 8> sets;
      uint64_t total = 0;
      for (int c = 0; c < 8; ++c) {
        fs::path f = provisionalFile(key.child(c));
        if (!fs::exists(f)) continue;
        {
          std::lock_guard<std::mutex> lock(pendingMutex_);
          total += subtreePoints_.at(key.child(c));
        }
        PointBuffer child = loadRecords(f);
        fs::remove(f);
        for (size_t i = 0; i < child.size(); ++i) {
          sets[c].push_back(static_cast<uint32_t>(pts.size()));
          pts.pushFrom(child, i);
        }
      }
      // Chunks were planned on counts before deduplication (and sampled): a node whose
      // subtree turns out small is a leaf holding all of it, exactly as an in-memory build
      // would make it. Its children then hold their whole subtrees too, unwritten.
      std::vector<uint32_t> selected;
      if (total <= opt_.maxNodePoints) {
        selected.resize(pts.size());
        std::iota(selected.begin(), selected.end(), 0u);
      } else {
        selected = sampleAndWriteChildren(pts, key, sets);
      }
      saveProvisional(key, pts, selected, total);
    });
    progress_.advance(1);
  }
  progress_.end();
}

void Builder::writeRoot() {
  // The root's current sample is final.
  fs::path rootFile = provisionalFile(NodeKey::root());
  PointBuffer root = loadRecords(rootFile);
  std::vector<uint32_t> all(root.size());
  std::iota(all.begin(), all.end(), 0u);
  writeNode(NodeKey::root(), root, all, all);
}

void Builder::finishMetadata() {
  accounting_.kept = stored_.load();
  NL_CHECK_MSG(accounting_.balanced(),
               "point accounting does not balance: input " + std::to_string(accounting_.input) +
                   ", kept " + std::to_string(accounting_.kept) + ", merged " +
                   std::to_string(accounting_.duplicatesMerged) + ", rejected " +
                   std::to_string(accounting_.rejectedTotal()));
  meta_.generator = "nestlight 0.1.0";
  meta_.layout = layout_;
  meta_.points = accounting_.kept;
  meta_.accounting = accounting_;
  meta_.hierarchyStep = kHierarchyStep;
  meta_.normalsEstimated = estimate_;
  if (estimate_)
    meta_.normalEstimation = {
        {"method", "closed-form plane fit (Rohmer et al., section 5)"},
        {"neighbours", opt_.normalNeighbours},
        {"depth_limit", opt_.normalDepthLimit},
        {"orientation", opt_.normalOrientation == NormalOrientation::Up       ? "up"
                        : opt_.normalOrientation == NormalOrientation::Inward ? "inward"
                                                                              : "outward"},
        {"note", "neighbourhoods end at chunk borders; points with no fit have a zero normal"}};
  for (auto& s : sources_) {
    const SourceHeader& h = s.reader->header();
    SourceRecord r;
    r.path = h.path;
    r.format = h.format;
    r.points = s.read;
    r.unreadable = s.unreadable;
    r.declaredPoints = h.declaredPoints;
    // Warnings are the source's own: a reader's "<file>: " in front would print the name twice.
    for (std::string w : s.remoteWarnings ? *s.remoteWarnings : s.reader->warnings()) {
      if (w.rfind(h.path + ": ", 0) == 0) w.erase(0, h.path.size() + 2);
      r.warnings.push_back(std::move(w));
    }
    if (s.outsideDeclared) {
      char w[256];
      std::snprintf(
          w, sizeof w,
          "%llu points lie outside the bounds the header declares, up to %.6g beyond them; kept "
          "(the octree's bounds are the points')",
          (unsigned long long)s.outsideDeclared, s.outsideMax);
      r.warnings.push_back(w);
    }
    r.details = h.details;
    if (meta_.crs.is_null() && !h.crs.is_null()) meta_.crs = h.crs;
    meta_.sources.push_back(std::move(r));
  }
  meta_.build = {
      {"sampling", opt_.sampling == Sampling::Grid ? "grid" : "poisson"},
      {"codec", codecName(opt_.codec)},
      {"max_node_points", opt_.maxNodePoints},
      {"memory_bytes", opt_.memoryBytes},
      {"dedup", opt_.dedup},
      {"chunks", distributed() ? chunksTotal_ : chunks_.size()},
      {"max_chunk_points", maxChunkPoints_ == UINT64_MAX ? json(nullptr) : json(maxChunkPoints_)},
      {"command_line", opt_.commandLine}};
  if (!buildNotes_.empty()) meta_.build["notes"] = buildNotes_;
}

}  // namespace nestlight::build_passes
