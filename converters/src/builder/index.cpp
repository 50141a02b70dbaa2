// The builder's indexing of one chunk: its points sorted in Morton order, duplicates merged, the
// nested octree of its subtree built bottom-up (Schütz, Ohrhallinger, Wimmer, "Fast Out-of-Core
// Octree Generation for Massive Point Clouds", 2020; the nested octree of Wimmer and
// Scheiblauer, "Instant Points", 2006).
#include <algorithm>

#include "builder_passes.h"

namespace nestlight::build_passes {

void Builder::indexChunks() {
  uint64_t total = 0;
  for (auto& c : chunks_) total += c.points;
  progress_.begin("index", total, "points");
  std::vector<size_t> order(chunks_.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return chunks_[a].points > chunks_[b].points; });
  std::atomic<uint64_t> merged{0};
  tbb::parallel_for_each(order.begin(), order.end(), [&](size_t ci) {
    // Isolated: while a chunk's nested parallel sort waits, this thread must not start another
    // chunk, or more chunks than threads would be in memory at once.
    tbb::this_task_arena::isolate([&] { indexChunk(ci, merged); });
  });
  accounting_.duplicatesMerged += merged.load();
  progress_.end();
}

void Builder::indexChunk(size_t ci, std::atomic<uint64_t>& merged) {
  {
    Chunk& c = chunks_[ci];
    if (c.points == 0) return;
    PointBuffer pts = loadRecords(c.file);
    fs::remove(c.file);
    NL_CHECK(pts.size() == c.points);
    sortPoints(pts, c.key);
    if (opt_.dedup) merged += dedup(pts);
    if (estimate_) estimateMissingNormals(pts);
    std::vector<uint32_t> set = buildSubtree(pts, c.key, 0, pts.size());
    saveProvisional(c.key, pts, set, pts.size());
    progress_.advance(c.points);
  }
}

PointBuffer Builder::loadRecords(const fs::path& file) const {
  const size_t rec = 12 + stride_;
  PointBuffer pts(stride_);
  if (!fs::exists(file)) return pts;
  const size_t n = fs::file_size(file) / rec;
  pts.pos.resize(n * 3);
  pts.attrs.resize(n * stride_);
  FILE* f = std::fopen(file.c_str(), "rb");
  if (!f) throw Error(file.string(), "", "cannot read temporary file");
  std::vector<uint8_t> buf(rec * 65536);
  size_t at = 0, got;
  while (at < n && (got = std::fread(buf.data(), rec, std::min<size_t>(65536, n - at), f)) > 0) {
    for (size_t k = 0; k < got; ++k, ++at) {
      std::memcpy(&pts.pos[3 * at], &buf[k * rec], 12);
      if (stride_) std::memcpy(&pts.attrs[at * stride_], &buf[k * rec + 12], stride_);
    }
  }
  std::fclose(f);
  NL_CHECK(at == n);
  return pts;
}

void Builder::saveRecords(const fs::path& file, const PointBuffer& pts,
                          const std::vector<uint32_t>& set) const {
  const size_t rec = 12 + stride_;
  std::vector<uint8_t> buf(set.size() * rec);
  for (size_t k = 0; k < set.size(); ++k) {
    std::memcpy(&buf[k * rec], &pts.pos[3 * size_t(set[k])], 12);
    if (stride_) std::memcpy(&buf[k * rec + 12], pts.attrsOf(set[k]), stride_);
  }
  FILE* f = std::fopen(file.c_str(), "wb");
  if (!f || std::fwrite(buf.data(), 1, buf.size(), f) != buf.size())
    throw Error(file.string(), "", "cannot write temporary file (disk full?)");
  std::fclose(f);
}

void Builder::sortPoints(PointBuffer& pts, const NodeKey& key) const {
  const size_t n = pts.size();
  // Coarse Morton keys of the top 21 bits inside the node order almost everything (LSD radix
  // sort); exact comparison settles runs of equal keys.
  const uint32_t bits = cubeBits() - key.level;
  const uint32_t shift = bits > 21 ? bits - 21 : 0;
  const uint32_t m = mask(bits);
  // Uninitialised on purpose: every slot is written before it is read.
  struct KeyIdx {
    uint64_t first;
    uint32_t second;
  };
  std::unique_ptr<KeyIdx[]> keys(new KeyIdx[n]), tmp(new KeyIdx[n]);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const uint32_t* p = &pts.pos[3 * i];
    keys[i] = {mortonEncode21((p[0] & m) >> shift, (p[1] & m) >> shift, (p[2] & m) >> shift),
               static_cast<uint32_t>(i)};
  });
  const uint32_t keyBits = 3 * std::min<uint32_t>(bits, 21);
  constexpr uint32_t kDigit = 11;
  std::vector<uint32_t> hist(size_t(1) << kDigit);
  for (uint32_t s0 = 0; s0 < keyBits; s0 += kDigit) {
    std::fill(hist.begin(), hist.end(), 0);
    for (size_t i = 0; i < n; ++i) hist[(keys[i].first >> s0) & ((1u << kDigit) - 1)]++;
    uint32_t sum = 0;
    for (auto& h : hist) {
      uint32_t c = h;
      h = sum;
      sum += c;
    }
    for (size_t i = 0; i < n; ++i)
      tmp[hist[(keys[i].first >> s0) & ((1u << kDigit) - 1)]++] = keys[i];
    keys.swap(tmp);
  }
  tmp.reset();
  auto exactLess = [&](const KeyIdx& a, const KeyIdx& b) {
    const uint32_t* p = &pts.pos[3 * size_t(a.second)];
    const uint32_t* q = &pts.pos[3 * size_t(b.second)];
    if (p[0] != q[0] || p[1] != q[1] || p[2] != q[2]) return mortonLess(p, q);
    return stride_ && std::memcmp(pts.attrsOf(a.second), pts.attrsOf(b.second), stride_) < 0;
  };
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && keys[j].first == keys[i].first) ++j;
    if (j - i > 1) std::sort(keys.get() + i, keys.get() + j, exactLess);
    i = j;
  }
  PointBuffer sorted(stride_);
  sorted.pos.resize(n * 3);
  sorted.attrs.resize(n * stride_);
  // A random gather: prefetch a few points ahead, or every read is a cache miss.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      constexpr size_t kAhead = 16;
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        if (i + kAhead < n) {
                          const size_t f = keys[i + kAhead].second;
                          __builtin_prefetch(&pts.pos[3 * f]);
                          if (stride_) __builtin_prefetch(pts.attrsOf(f));
                        }
                        const size_t j = keys[i].second;
                        std::memcpy(&sorted.pos[3 * i], &pts.pos[3 * j], 12);
                        if (stride_)
                          std::memcpy(&sorted.attrs[i * stride_], pts.attrsOf(j), stride_);
                      }
                    });
  pts = std::move(sorted);
}

// Merges exact duplicates (same position and attributes), adjacent after sorting.
uint64_t Builder::dedup(PointBuffer& pts) const {
  const size_t n = pts.size();
  if (n == 0) return 0;
  size_t w = 1;
  for (size_t i = 1; i < n; ++i) {
    const uint32_t* p = &pts.pos[3 * i];
    const uint32_t* q = &pts.pos[3 * (w - 1)];
    if (p[0] == q[0] && p[1] == q[1] && p[2] == q[2] &&
        (stride_ == 0 || std::memcmp(pts.attrsOf(i), pts.attrsOf(w - 1), stride_) == 0))
      continue;
    if (w != i) {
      std::memcpy(&pts.pos[3 * w], p, 12);
      if (stride_) std::memmove(&pts.attrs[w * stride_], pts.attrsOf(i), stride_);
    }
    ++w;
  }
  pts.pos.resize(3 * w);
  pts.attrs.resize(w * stride_);
  return n - w;
}

void Builder::estimateMissingNormals(PointBuffer& pts) const {
  const size_t n = pts.size();
  std::vector<float> normals(3 * n, 0.f);
  // The orientation centre: the middle of the scan's tight bounds, in integer units.
  double c[3];
  for (int a = 0; a < 3; ++a)
    c[a] = ((meta_.bounds.min[a] + meta_.bounds.max[a]) * 0.5 - meta_.offset[a]) / meta_.scale[a];
  int orient = opt_.normalOrientation == NormalOrientation::Up       ? 2
               : opt_.normalOrientation == NormalOrientation::Inward ? 1
                                                                     : 0;
  // The fit works in integer units. Axes of different scales (inputs of different LAS scales)
  // make that frame anisotropic; the finest scale gives the widest limit, erring towards keeping
  // neighbours as the fit without the rule does.
  const double finest = std::min({meta_.scale.x, meta_.scale.y, meta_.scale.z});
  const double depthLimit = opt_.normalDepthLimit > 0 ? opt_.normalDepthLimit / finest : 0;
  estimateNormals(pts.pos.data(), n, opt_.normalNeighbours, orient, c, normals.data(), depthLimit);
  const size_t off = layout_.offset(normalIndex_);
  for (size_t i = 0; i < n; ++i) {
    float cur[3];
    std::memcpy(cur, pts.attrs.data() + i * stride_ + off, 12);
    if (std::isnan(cur[0])) std::memcpy(pts.attrs.data() + i * stride_ + off, &normals[3 * i], 12);
  }
}

// Returns the node's current sample (indices into pts); writes every node below it.
std::vector<uint32_t> Builder::buildSubtree(const PointBuffer& pts, const NodeKey& key, size_t b,
                                            size_t e) {
  const uint32_t size = meta_.cubeSize >> key.level;
  if (e - b <= opt_.maxNodePoints || size <= 1) {
    std::vector<uint32_t> all(e - b);
    std::iota(all.begin(), all.end(), static_cast<uint32_t>(b));
    return all;
  }
  const uint32_t half = size >> 1;
  auto childOf = [&](size_t i) {
    const uint32_t* p = &pts.pos[3 * i];
    return ((p[0] & half) ? 4 : 0) | ((p[1] & half) ? 2 : 0) | ((p[2] & half) ? 1 : 0);
  };
  // Morton order makes each child's points one contiguous run.
  std::array<std::vector<uint32_t>, 8> sets;
  size_t start = b;
  while (start < e) {
    int c = childOf(start);
    size_t end = start + 1;
    while (end < e && childOf(end) == c) ++end;
    NL_CHECK_MSG(sets[c].empty(), "points not in Morton order");
    sets[c] = buildSubtree(pts, key.child(c), start, end);
    start = end;
  }
  return sampleAndWriteChildren(pts, key, sets);
}

// Selects `key`'s sample from its children's current samples and writes the children.
std::vector<uint32_t> Builder::sampleAndWriteChildren(const PointBuffer& pts, const NodeKey& key,
                                                      std::array<std::vector<uint32_t>, 8>& sets) {
  std::vector<uint32_t> candidates;
  for (auto& s : sets) candidates.insert(candidates.end(), s.begin(), s.end());
  std::vector<char> chosen = sample(pts, key, candidates);
  std::vector<uint32_t> selected;
  std::vector<char> isSelected;  // by candidate position
  size_t at = 0;
  for (int c = 0; c < 8; ++c) {
    if (sets[c].empty()) continue;
    std::vector<uint32_t> rest;
    for (uint32_t idx : sets[c]) {
      if (chosen[at++])
        selected.push_back(idx);
      else
        rest.push_back(idx);
    }
    // sets[c] is the child's sample before this node took its share: the points drawn where
    // the child is the finest drawn node.
    writeNode(key.child(c), pts, rest, sets[c]);
  }
  return selected;
}

}  // namespace nestlight::build_passes
