// The frame loop of the scheduler, after Potree 2's viewer (Schütz, Ohrhallinger, Wimmer 2020)
// and Potree's point budget (Schütz 2016, chapter 3): select the cut by screen-space priority,
// queue what it misses for the loader threads in the same order, upload a bounded amount of what
// they finished, evict least recently wanted nodes to make room, and draw only nodes whose
// ancestors are all resident, so that detail arrives as refinement and never as holes. The render
// thread reads no file: loaders read payloads and hierarchy chunks, and the hierarchy the cut
// walks is the scheduler's own copy (node_table.h).
#include "nestlight/streaming/streamer.h"

#include <algorithm>
#include <chrono>

#include "cut_selection.h"
#include "loaders.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/spacing.h"
#include "node_table.h"
#include "residency.h"

namespace nestlight::streaming {

using namespace detail;

namespace {
// Frames a loaded node waits outside the cut before it is dropped: a camera that turns back
// soon finds it without reading it again; a camera that flies on does not pile up loads.
constexpr uint64_t kReadyGraceFrames = 30;

double msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

struct Streamer::Impl {
  Impl(OctreeReader& r, NodeStore& s, const Budgets& b)
      : reader(r), table(r.metadata()), budgets(b), resident(s), loaders(r, s, badLog) {}

  void integrate(LoadResult& r, FrameStats& s);
  void markBad(uint32_t idx);
  void scanCut(FrameStats& s);
  void upload(FrameStats& s);
  void buildDrawList(FrameStats& s);

  OctreeReader& reader;
  NodeTable table;
  Budgets budgets;
  CutSelector selector;
  CutResult cut;
  std::vector<uint32_t> previousCut;
  BadNodeLog badLog;
  ResidentSet resident;
  Loaders loaders;

  uint64_t frame = 0;
  uint64_t preparedBytes = 0, preparedPoints = 0;  // for the bytes-per-point estimate
  uint32_t badCount = 0;
  Totals totals;
  FrameStats stats;
  std::vector<DrawNode> drawList;
  std::vector<uint64_t> drawFrame;  // per node: last frame drawn (apart: a small, hot array)
  std::vector<LoadRequest> queue;
  std::vector<LoadResult> results;
  std::vector<uint32_t> ready, readyNext, uploadOrder;
  EntryList walk;
};

void Streamer::Impl::markBad(uint32_t idx) {
  Node& n = table[idx];
  if (n.residency == Residency::Bad) return;
  if (n.residency == Residency::Resident) resident.evict(table, idx);
  n.prepared.reset();
  n.residency = Residency::Bad;
  ++badCount;
}

void Streamer::Impl::integrate(LoadResult& r, FrameStats& s) {
  table[r.node].load->store(LoadState::Idle);
  s.bytesRead += r.bytesRead;
  totals.bytesRead += r.bytesRead;
  if (r.failed) {
    ++totals.failed;
    markBad(r.node);
    return;
  }
  ++totals.completed;
  if (r.hasHierarchy && !table.integrate(r.node, r.hierarchy)) {
    // The loader checked each chunk's checksum and structure; a walk that still disagrees with
    // the table is a hierarchy that contradicts itself across chunks.
    badLog.report(table[r.node].key, "node " + table[r.node].key.name() + ": " +
                                         (reader.dir() / reader.metadata().hierarchyFile).string() +
                                         ": hierarchy chunk contradicts its parent chunk");
    markBad(r.node);
    return;
  }
  if (!r.prepared) return;
  Node& n = table[r.node];  // after integrate(): the table may have grown
  n.bytes = r.prepared->residentBytes();
  n.bytesKnown = true;
  preparedBytes += n.bytes;
  preparedPoints += r.prepared->numPoints;
  if (n.residency == Residency::Absent) {
    n.residency = Residency::Ready;
    n.prepared = std::move(r.prepared);
    ready.push_back(r.node);
  } else {
    ++totals.discarded;
  }
}

// One pass over the cut: its nodes leave the eviction list, and those it misses are queued.
void Streamer::Impl::scanCut(FrameStats& s) {
  queue.clear();
  for (uint32_t idx : cut.nodes) {
    Node& n = table[idx];
    resident.keep(table, idx);
    const bool payload = n.residency == Residency::Absent;
    const bool hierarchy = NodeTable::needsHierarchy(n) && (payload || n.refine);
    if (!payload && !hierarchy) continue;
    const LoadState st = n.load->load();
    if (st == LoadState::Loading) continue;
    if (st == LoadState::Idle) {
      n.load->store(LoadState::Queued);
      ++totals.requested;
    }
    n.queuedFrame = frame;
    queue.push_back({idx, n.load, n.key, n.entry, hierarchy, payload});
  }
  // The priority traversal lists the cut in priority order already; the depth-first one does not.
  if (!cut.budgetBound)
    std::sort(queue.begin(), queue.end(), [this](const LoadRequest& a, const LoadRequest& b) {
      return higherPriority(table[a.node], table[b.node]);
    });
  s.queueLength = static_cast<uint32_t>(queue.size());
  // `queue` comes back holding the previous queue: what no loader took and this frame no longer
  // wants is cancelled (a loader that races us to it wins, and the load completes).
  const size_t untaken = loaders.replaceQueue(queue);
  for (size_t i = untaken; i < queue.size(); ++i) {
    const LoadRequest& q = queue[i];
    if (table[q.node].queuedFrame == frame) continue;
    LoadState expected = LoadState::Queued;
    if (q.state->compare_exchange_strong(expected, LoadState::Idle)) {
      ++s.cancelled;
      ++totals.cancelled;
    }
  }
}

void Streamer::Impl::upload(FrameStats& s) {
  uploadOrder.clear();
  readyNext.clear();
  for (uint32_t idx : ready) {
    Node& n = table[idx];
    if (n.residency != Residency::Ready) continue;
    if (n.cutFrame == frame) {
      uploadOrder.push_back(idx);
    } else if (frame - n.cutFrame > kReadyGraceFrames) {
      n.prepared.reset();
      n.residency = Residency::Absent;
      ++totals.discarded;
    } else {
      readyNext.push_back(idx);
    }
  }
  std::sort(uploadOrder.begin(), uploadOrder.end(),
            [this](uint32_t a, uint32_t b) { return higherPriority(table[a], table[b]); });
  bool blocked = false;
  for (uint32_t idx : uploadOrder) {
    if (!blocked) {
      Node& n = table[idx];
      const uint64_t size = n.prepared->residentBytes();
      // At least one node per frame, however big, so that no node starves behind the cap.
      if (s.uploads > 0 && s.uploadBytes + size > budgets.uploadBytesPerFrame) {
        blocked = true;
      } else if (!resident.makeRoom(table, cut.nodes, size, budgets.gpuBytes, idx)) {
        blocked = true;  // strict priority: nothing of lower priority jumps ahead
      } else {
        resident.upload(table, idx);
        ++s.uploads;
        s.uploadBytes += size;
        continue;
      }
    }
    readyNext.push_back(idx);
  }
  std::swap(ready, readyNext);
  s.readyWaiting = static_cast<uint32_t>(ready.size());
}

void Streamer::Impl::buildDrawList(FrameStats& s) {
  drawList.clear();
  drawFrame.resize(table.size(), 0);
  for (uint32_t idx : cut.nodes) {
    const Node& n = table[idx];
    if (n.residency != Residency::Resident) continue;
    // The parent precedes its children in the cut: its drawFrame is already this frame's.
    if (n.parent != kNone && drawFrame[n.parent] != frame) continue;
    drawFrame[idx] = frame;
    const double measured = measuredSpacing(reader.metadata(), n.key.level, n.entry);
    drawList.push_back({n.key, n.handle, n.numPoints, table.cube(n.key), n.spacing,
                        measured > 0 ? measured : n.spacing});
    s.drawPoints += n.numPoints;
  }
  s.drawNodes = static_cast<uint32_t>(drawList.size());
}

Streamer::Streamer(OctreeReader& reader, NodeStore& store, const Budgets& budgets)
    : impl_(std::make_unique<Impl>(reader, store, budgets)) {
  // The root chunk was read when the reader opened: peek() reads nothing.
  auto root = reader.peek(NodeKey::root());
  NL_CHECK_MSG(root && root->type != NodeType::Proxy, "the reader has no root entry");
  impl_->table.addRoot(*root);
  if (collectWalk(reader, NodeKey::root(), *root, impl_->table.hierarchyStep(), impl_->walk))
    impl_->table.integrate(0, impl_->walk);
  impl_->loaders.setThreads(budgets.loaderThreads);
}

Streamer::~Streamer() {
  Impl& m = *impl_;
  m.loaders.stop();
  for (size_t i = m.loaders.queueHead(); i < m.loaders.queue().size(); ++i) {
    LoadState expected = LoadState::Queued;
    if (m.loaders.queue()[i].state->compare_exchange_strong(expected, LoadState::Idle))
      ++m.totals.cancelled;
  }
  m.loaders.takeResults(m.results);  // finished loads nobody will upload: freed with the vector
  m.results.clear();
  for (uint32_t idx : m.ready) m.table[idx].prepared.reset();
  m.resident.releaseAll(m.table);
}

const FrameStats& Streamer::update(const View& view) {
  Impl& m = *impl_;
  const auto start = std::chrono::steady_clock::now();
  FrameStats s;
  s.frame = ++m.frame;

  m.loaders.takeResults(m.results);
  for (LoadResult& r : m.results) m.integrate(r, s);
  m.results.clear();

  const auto cutStart = std::chrono::steady_clock::now();
  std::swap(m.previousCut, m.cut.nodes);
  const double bytesPerPoint =
      m.preparedPoints ? double(m.preparedBytes) / double(m.preparedPoints) : 0.0;
  m.selector.select(m.table, view, m.budgets, bytesPerPoint, m.frame, m.cut);
  s.msCutSelection = msSince(cutStart);
  s.cutNodes = static_cast<uint32_t>(m.cut.nodes.size());
  s.cutPoints = m.cut.points;

  const uint64_t evictedBefore = m.resident.evictions();
  m.scanCut(s);
  m.resident.addLeavers(m.table, m.previousCut, m.frame);
  m.resident.beginFrame();
  // A budget lowered by setBudgets(): evict at once, before anything is uploaded.
  if (m.resident.bytes() > m.budgets.gpuBytes)
    m.resident.makeRoom(m.table, m.cut.nodes, 0, m.budgets.gpuBytes, kNone);

  const auto uploadStart = std::chrono::steady_clock::now();
  m.upload(s);
  s.msUpload = msSince(uploadStart);

  m.buildDrawList(s);

  s.residentNodes = m.resident.count();
  s.residentBytes = m.resident.bytes();
  s.evictions = static_cast<uint32_t>(m.resident.evictions() - evictedBefore);
  s.inFlight = m.loaders.inFlight();
  s.badNodes = m.badCount;
  s.complete = s.drawNodes == s.cutNodes && m.cut.pendingHierarchy == 0;
  m.totals.uploaded = m.resident.uploads();
  m.totals.evicted = m.resident.evictions();
  m.totals.maxResidentBytes = m.resident.maxBytes();
  s.msUpdate = msSince(start);
  m.stats = s;
  return m.stats;
}

const std::vector<DrawNode>& Streamer::drawList() const {
  return impl_->drawList;
}
const FrameStats& Streamer::stats() const {
  return impl_->stats;
}

void Streamer::setBudgets(const Budgets& b) {
  impl_->budgets = b;
  impl_->loaders.setThreads(b.loaderThreads);
}

const Budgets& Streamer::budgets() const {
  return impl_->budgets;
}
std::vector<BadNode> Streamer::badNodes() const {
  return impl_->badLog.list();
}

void Streamer::onBadNode(std::function<void(const BadNode&)> log) {
  impl_->badLog.setCallback(std::move(log));
}

Streamer::Totals Streamer::totals() const {
  return impl_->totals;
}

}  // namespace nestlight::streaming
