// Out-of-core nested-octree builder.
//
// Structure after Potree 2 (Schütz, Ohrhallinger, Wimmer, "Fast Out-of-Core Octree Generation for
// Massive Point Clouds", 2020): counting on a coarse grid, distribution into chunk files, indexing
// of each chunk, merging of the levels above. The nested octree itself is the one of Instant
// Points (Wimmer and Scheiblauer 2006), as used by Preiner (seed 004, section 3): each node holds a
// spatially even subsample of its subtree and passes the rest on to its children.
//
// Sampling is bottom-up: a leaf holds all its points; an inner node selects its sample from the
// union of its children's current samples, which then lose the selected points. A node's content
// is therefore a function of its subtree's points alone, so that chunking (and the memory budget
// that decides it) never changes the result, and points are processed in a total order (Morton
// order of position, then attribute bytes) so that input order never does either.
#include "nestlight/converters/builder.h"

#include <sys/resource.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <numeric>
#include <set>
#include <thread>
#include <unordered_set>

#include "nestlight/converters/normals.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/node_key.h"
#include "nestlight/octree/octree_writer.h"
#include "nestlight/octree/spacing.h"
#include "nestlight/octree/staged_directory.h"

namespace nestlight {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// VmHWM, the high-water mark of this address space: getrusage's ru_maxrss would do for a process
// that was never exec'd, but Linux carries the pre-exec mark across execve, so a child that
// `bench hdr` or `bench convert` spawns would report its parent's memory as its own.
uint64_t peakRssBytes() {
  if (FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    uint64_t kb = 0;
    bool found = false;
    while (std::fgets(line, sizeof line, f))
      if (std::strncmp(line, "VmHWM:", 6) == 0)
        kb = std::strtoull(line + 6, nullptr, 10), found = true;
    std::fclose(f);
    if (found) return kb * 1024;
  }
  struct rusage ru {};
  ::getrusage(RUSAGE_SELF, &ru);
  return static_cast<uint64_t>(ru.ru_maxrss) * 1024;
}

namespace {

// The shortest text that reads back as `v` (a scale such as 1.1645e-06).
std::string shortNumber(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

constexpr size_t kBatchPoints = 1 << 18;
constexpr uint32_t kGridLevel = 7;  // counting grid: 128^3 cells
constexpr size_t kCountSampleStep = 8;

double seconds(Clock::time_point a) {
  return std::chrono::duration<double>(Clock::now() - a).count();
}

// Exact Morton order of two integer positions without computing 93-bit codes: compare on the
// axis whose coordinates differ in the highest bit (x before y before z at equal bits).
inline bool lessMsb(uint32_t a, uint32_t b) {
  return a < b && a < (a ^ b);
}
inline bool mortonLess(const uint32_t* p, const uint32_t* q) {
  int axis = 0;
  uint32_t best = p[0] ^ q[0];
  for (int a = 1; a < 3; ++a) {
    uint32_t d = p[a] ^ q[a];
    if (lessMsb(best, d)) best = d, axis = a;
  }
  return p[axis] < q[axis];
}

struct Chunk {
  NodeKey key;
  uint64_t points = 0;
  fs::path file;
};

// Per-source mapping of attributes into the octree's layout.
struct AttributeMap {
  struct Entry {
    int src = -1;  // index in the source layout, or -1 when the source lacks the attribute
    bool copy = false;
  };
  std::vector<Entry> entries;
};

struct SourceState {
  std::unique_ptr<PointReader> reader;
  AttributeMap map;
  bool identity = false;  // the source's layout is the octree's: attributes copy as one block
  std::optional<Box3d> declared;  // valid declared bounds, if any
  double tolerance = 0;
  uint64_t read = 0;
  uint64_t unreadable = 0;       // declared points it could not decode (lenient), in the input
  uint64_t outsideDeclared = 0;  // points beyond the declared bounds (and tolerance), kept
  double outsideMax = 0;         // the farthest of them, in units of the input
};

// A point beyond the cube planned from declared bounds: the conversion starts again with the
// bounds measured from the points (buildOctree).
struct OutsideCube {};

bool validBox(const Box3d& b) {
  return !b.empty() && std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
         std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z);
}

class Builder {
  using json = nlohmann::json;

 public:
  Builder(std::vector<std::unique_ptr<PointReader>> sources, const BuildOptions& o,
          bool measureBounds)
      : opt_(o), progress_(o.progress), measureBounds_(measureBounds) {
    for (auto& r : sources) {
      SourceState s;
      s.reader = std::move(r);
      sources_.push_back(std::move(s));
    }
  }
  std::vector<std::unique_ptr<PointReader>> takeSources() {
    std::vector<std::unique_ptr<PointReader>> out;
    for (auto& s : sources_) out.push_back(std::move(s.reader));
    return out;
  }

  BuildReport run() {
    auto t0 = Clock::now();
    BuildReport report;
    unsigned threads =
        opt_.threads ? opt_.threads : std::max(1u, std::thread::hardware_concurrency());
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    threads_ = threads;

    planLayout();
    planQuantisation(report);
    // Built beside the output and swapped in at the end: a failed, full-disk or killed run leaves
    // an existing octree (and its layers) as it was.
    if (fs::exists(opt_.output / "metadata.json") && !opt_.overwrite)
      throw Error(opt_.output.string(), "",
                  "already holds an octree; pass --overwrite to replace it");
    StagedDirectory staged(opt_.output, isOctreeFileName);
    for (const fs::path& p : staged.staleRemoved())
      report.warnings.push_back("removed " + p.string() + ", left by a conversion that was killed");
    writer_ = std::make_unique<OctreeWriter>(staged.path(), layout_, opt_.codec, true);
    tmp_ = staged.path() / "chunks.tmp";
    fs::create_directories(tmp_);
    struct Cleanup {
      fs::path p;
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(p, ec);
      }
    } cleanup{tmp_};

    auto t = Clock::now();
    countPass();
    if (outsideCube_) throw OutsideCube{};
    report.phases["count"] = seconds(t);
    t = Clock::now();
    distributePass();
    if (outsideCube_) throw OutsideCube{};
    report.phases["distribute"] = seconds(t);
    t = Clock::now();
    splitOversizedChunks();
    indexChunks();
    report.phases["index"] = seconds(t);
    t = Clock::now();
    mergeTop();
    report.phases["merge"] = seconds(t);

    finishMetadata();
    t = Clock::now();
    writer_->finish(meta_);
    writer_.reset();
    fs::remove_all(tmp_);
    staged.commit();
    report.phases["write"] = seconds(t);
    report.seconds = seconds(t0);
    report.chunks = chunks_.size();
    // Points read, not declared: a lenient conversion's unreadable points took no time.
    uint64_t read = 0;
    for (const auto& src : sources_) read += src.read;
    report.pointsPerSecond = report.seconds > 0 ? double(read) / report.seconds : 0;
    report.peakRssBytes = peakRssBytes();
    report.metadata = meta_;
    return report;
  }

 private:
  // ---- planning -------------------------------------------------------------------------------

  // Planning visits sources sorted by path, so that the layout and the grid's offset do not
  // depend on the order the inputs were given in.
  std::vector<SourceState*> planningOrder() {
    std::vector<SourceState*> order;
    for (auto& s : sources_) order.push_back(&s);
    std::stable_sort(order.begin(), order.end(), [](const SourceState* a, const SourceState* b) {
      return a->reader->header().path < b->reader->header().path;
    });
    return order;
  }

  void planLayout() {
    int rgbBits = 0;
    bool rgb16 = false;
    for (SourceState* sp : planningOrder()) {
      SourceState& s = *sp;
      const SourceHeader& h = s.reader->header();
      for (const Attribute& a : h.layout.attributes()) {
        int i = layout_.find(a.name);
        if (i < 0) {
          layout_.add(a);
        } else if (!(layout_[i] == a)) {
          if (layout_[i].components != a.components)
            throw Error(h.path, "",
                        "attribute '" + a.name + "' has " + std::to_string(a.components) +
                            " components here but " + std::to_string(layout_[i].components) +
                            " in another input");
          // Mixed types: widen to double, which holds every integer type up to 32 bits exactly.
          widened_.insert(a.name);
        }
      }
      if (h.layout.has(attr::kRgb)) {
        rgbBits = 8;
        rgb16 = rgb16 || h.rgbBits != 8;
      }
    }
    if (!widened_.empty()) {
      PointLayout l;
      for (Attribute a : layout_.attributes()) {
        if (widened_.count(a.name)) a.type = ScalarType::F64;
        l.add(a);
      }
      layout_ = l;
    }
    meta_.rgbSourceBits = rgbBits ? (rgb16 ? 16 : 8) : 0;
    if (opt_.estimateNormals) {
      bool allHave = !sources_.empty();
      for (auto& s : sources_) allHave = allHave && s.reader->header().layout.has(attr::kNormal);
      if (allHave) {
        progress_.message("every input has normals; --estimate-normals keeps them");
      } else {
        if (!layout_.has(attr::kNormal))
          layout_.add({std::string(attr::kNormal), ScalarType::F32, 3, "estimated"});
        estimate_ = true;
      }
    }
    stride_ = layout_.stride();
    normalIndex_ = layout_.find(attr::kNormal);
    for (auto& s : sources_) {
      const PointLayout& sl = s.reader->header().layout;
      for (size_t i = 0; i < layout_.size(); ++i) {
        AttributeMap::Entry e;
        e.src = sl.find(layout_[i].name);
        e.copy = e.src >= 0 && sl[e.src] == layout_[i];
        s.map.entries.push_back(e);
      }
      s.identity = sl == layout_ && !estimate_;
    }
  }

  void planQuantisation(BuildReport& report) {
    // Precision per axis: the inputs' own scales (the finest of each axis where they differ),
    // so that LAS integer coordinates come back out exactly; one --precision for all axes when
    // given.
    Vec3d scales{opt_.precision, opt_.precision, opt_.precision};
    std::optional<Vec3d> base;
    std::set<std::array<double, 3>> seen;
    for (SourceState* sp : planningOrder()) {
      const SourceHeader& h = sp->reader->header();
      if (h.offset && !base) base = h.offset;
      if (opt_.precision <= 0 && h.scale) {
        seen.insert({h.scale->x, h.scale->y, h.scale->z});
        for (int a = 0; a < 3; ++a)
          if ((*h.scale)[a] > 0)
            scales[a] = scales[a] > 0 ? std::min(scales[a], (*h.scale)[a]) : (*h.scale)[a];
      }
    }
    // Axes no input scales: the finest scale any axis has, else a millimetre.
    double finest = 0;
    for (int a = 0; a < 3; ++a)
      if (scales[a] > 0) finest = finest > 0 ? std::min(finest, scales[a]) : scales[a];
    for (int a = 0; a < 3; ++a)
      if (!(scales[a] > 0)) scales[a] = finest > 0 ? finest : 0.001;
    if (seen.size() > 1)
      buildNotes_.push_back(
          "the inputs have " + std::to_string(seen.size()) +
          " different scales; the octree keeps the finest of each axis (" + shortNumber(scales.x) +
          ", " + shortNumber(scales.y) + ", " + shortNumber(scales.z) +
          "): coordinates of the other inputs that are not on that grid are rounded to it");
    report.warnings.insert(report.warnings.end(), buildNotes_.begin(), buildNotes_.end());
    meta_.scale = scales;
    meta_.sourceOffset = base;
    for (int a = 0; a < 3; ++a) invScale_[a] = 1.0 / scales[a];
    const double scale = meta_.maxScale();

    // Bounds: declared ones where a header gives valid bounds, a reading pass for the rest.
    Box3d bounds;
    std::vector<size_t> scan;
    for (size_t i = 0; i < sources_.size(); ++i) {
      auto& s = sources_[i];
      const SourceHeader& h = s.reader->header();
      if (h.declaredBounds && validBox(*h.declaredBounds)) {
        s.declared = *h.declaredBounds;
        double ss = h.scale ? std::max({h.scale->x, h.scale->y, h.scale->z}) : scale;
        s.tolerance = 0.5 * ss;
      }
      // Header bounds are advisory: they spare a reading pass. The grid's first step lies at or
      // below their minimum and the cube holds a step beyond their maximum, so points rounded
      // half a step past them (bounds computed before quantisation) still fit; a point beyond
      // the cube restarts the conversion with the bounds measured (OutsideCube).
      if (s.declared && !measureBounds_) {
        bounds.extend(*s.declared);
      } else {
        scan.push_back(i);
      }
    }
    if (!scan.empty()) {
      auto t = Clock::now();
      uint64_t total = 0;
      for (size_t i : scan) total += sources_[i].reader->bytesTotal();
      progress_.begin("bounds", total, "bytes");
      PointBatch batch;
      for (size_t i : scan) {
        auto& r = *sources_[i].reader;
        r.rewind();
        uint64_t before = 0;
        while (r.read(batch, kBatchPoints)) {
          const double* p = batch.xyz.data();
          for (size_t k = 0, n = batch.size(); k < n; ++k, p += 3)
            if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))
              bounds.extend(p[0], p[1], p[2]);
          progress_.advance(r.bytesConsumed() - before, batch.size());
          before = r.bytesConsumed();
        }
      }
      progress_.end();
      report.phases["bounds"] = seconds(t);
    }
    if (bounds.empty()) {
      meta_.offset = {0, 0, 0};
      meta_.cubeSize = 1;
      meta_.spacing = meta_.cubeWorldSize() / 128.0;
      return;
    }
    // The integer grid keeps the input's: offsets step from the first LAS offset in whole scales,
    // so that LAS integer coordinates map to ours without rounding.
    Vec3d b = base.value_or(Vec3d{0, 0, 0});
    double extent = 0;
    for (int a = 0; a < 3; ++a) {
      const double sa = scales[a];
      meta_.offset[a] = b[a] + std::floor((bounds.min[a] - b[a]) / sa) * sa;
      const double steps = std::ceil((bounds.max[a] - meta_.offset[a]) / sa) + 1;
      if (!(steps < double(uint64_t(1) << 31)))
        throw Error("", "",
                    "the scan spans " + std::to_string(steps * sa) + " units along " +
                        std::string(1, "xyz"[a]) + ", more than 2^31 steps of " +
                        std::to_string(sa) + "; use a coarser --precision");
      extent = std::max(extent, steps);
    }
    uint64_t cube = 1;
    while (cube < extent) cube <<= 1;
    meta_.cubeSize = static_cast<uint32_t>(cube);
    meta_.spacing = meta_.cubeWorldSize() / 128.0;  // the root's; nodes measure theirs against it
  }

  // ---- the reading pipeline -------------------------------------------------------------------

  struct Item {
    size_t source = 0;
    PointBatch batch;
    size_t points = 0;  // input points this batch stands for
    size_t weight = 1;  // input points per batch point (sampled counting)
    // Output of the parallel stage.
    std::unique_ptr<uint8_t[]> records;  // 12 + stride bytes each, grouped by chunk
    size_t recordBytes = 0;
    std::vector<std::pair<uint32_t, uint32_t>> runs;  // (chunk, count) in record order
    Accounting acc;
    Box3d box;
    std::pair<uint64_t, double> outside{0, 0.0};  // beyond the declared bounds: count, farthest
  };

  // Reads every source, runs `work` on batches in parallel and `collect` in input order.
  template <class Work, class Collect>
  void readAll(const std::string& phase, Work work, Collect collect, size_t sampleStep = 1) {
    uint64_t total = 0;
    for (auto& s : sources_) total += s.reader->bytesTotal();
    progress_.begin(phase, total, "bytes");
    size_t current = 0;
    uint64_t consumedBefore = 0;
    for (auto& s : sources_) s.reader->rewind();
    // Batches between the stages are owned here until the last stage takes them: when a stage
    // throws (damaged input, a full disk), the pipeline drops the batches in flight, and they are
    // freed below rather than leaked.
    std::mutex liveMutex;
    std::unordered_set<Item*> live;
    auto adopt = [&](Item* it) {
      std::lock_guard<std::mutex> lock(liveMutex);
      live.insert(it);
    };
    auto release = [&](Item* it) {
      std::lock_guard<std::mutex> lock(liveMutex);
      live.erase(it);
    };
    try {
      tbb::parallel_pipeline(
          threads_ * 2,
          tbb::make_filter<void, Item*>(
              tbb::filter_mode::serial_in_order,
              [&](tbb::flow_control& fc) -> Item* {
                while (current < sources_.size()) {
                  auto item = std::make_unique<Item>();
                  auto& r = *sources_[current].reader;
                  // Compressed sources leave decoding to the
                  // parallel stage (batch.finish()).
                  const size_t weight = r.readDeferred(item->batch, kBatchPoints, sampleStep);
                  if (weight) {
                    item->source = current;
                    item->weight = weight;
                    item->points =
                        (item->batch.pending ? item->batch.pendingPoints : item->batch.size()) *
                        weight;
                    progress_.advance(r.bytesConsumed() - consumedBefore, item->points);
                    consumedBefore = r.bytesConsumed();
                    adopt(item.get());
                    return item.release();
                  }
                  ++current;
                  consumedBefore = 0;
                }
                fc.stop();
                return nullptr;
              }) &
              tbb::make_filter<Item*, Item*>(tbb::filter_mode::parallel,
                                             [&](Item* it) {
                                               if (it->batch.pending) {
                                                 it->batch.finish();  // may throw on damage
                                                 it->points = it->batch.size() * it->weight;
                                               }
                                               work(*it);
                                               return it;
                                             }) &
              tbb::make_filter<Item*, void>(tbb::filter_mode::serial_in_order, [&](Item* it) {
                release(it);
                std::unique_ptr<Item> own(it);
                collect(own);
              }));
    } catch (...) {
      for (Item* it : live) delete it;
      throw;
    }
    progress_.end();
  }

  // Quantises point k of the item; false (and counted) when rejected. Points beyond their
  // header's bounds are kept, and counted in `outside` (the distribute pass) for a warning.
  bool quantise(const SourceState& s, const double* p, uint32_t q[3], Accounting& acc,
                std::pair<uint64_t, double>* outside = nullptr) const {
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
      acc.rejected[reject::kNonFinite]++;
      return false;
    }
    if (outside && s.declared && !s.declared->contains(p[0], p[1], p[2], s.tolerance)) {
      double d = 0;
      for (int a = 0; a < 3; ++a)
        d = std::max({d, s.declared->min[a] - p[a], p[a] - s.declared->max[a]});
      outside->first++;
      outside->second = std::max(outside->second, d);
    }
    const int64_t maxInt = static_cast<int64_t>(meta_.cubeSize) - 1;
    for (int a = 0; a < 3; ++a) {
      // Truncation after +0.5 rounds every value at or above -0.5 (no libm call per coordinate);
      // anything outside the cube cannot be placed, and the cube is planned again.
      const double u = (p[a] - meta_.offset[a]) * invScale_[a] + 0.5;
      if (!(u >= 0 && u < double(maxInt) + 1)) {
        // Flagged, not thrown: an exception out of the pipeline's parallel stage would strand
        // the batches in flight. The pass ends and run() starts over (OutsideCube).
        outsideCube_.store(true, std::memory_order_relaxed);
        return false;
      }
      q[a] = static_cast<uint32_t>(std::min<int64_t>(static_cast<int64_t>(u), maxInt));
    }
    return true;
  }

  uint32_t gridCell(const uint32_t q[3]) const {
    return ((q[0] >> gridShift_) << (2 * gridLevel_)) | ((q[1] >> gridShift_) << gridLevel_) |
           (q[2] >> gridShift_);
  }
  uint32_t cubeBits() const {
    uint32_t b = 0;
    while ((uint64_t(1) << b) < meta_.cubeSize) ++b;
    return b;
  }

  // ---- count ----------------------------------------------------------------------------------

  void countPass() {
    gridLevel_ = std::min(kGridLevel, cubeBits());
    gridShift_ = cubeBits() - gridLevel_;
    const size_t cells = size_t(1) << (3 * gridLevel_);
    // One shared grid of relaxed atomics (16 MiB): per-thread grids would grow with the core count
    // and escape the memory budget, and with sampled counting the increments are few.
    std::vector<std::atomic<uint64_t>> shared(cells);
    readAll(
        "count",
        [&](Item& it) {
          const SourceState& s = sources_[it.source];
          uint32_t q[3];
          for (size_t k = 0, n = it.batch.size(); k < n; ++k)
            if (quantise(s, &it.batch.xyz[3 * k], q, it.acc))
              shared[gridCell(q)].fetch_add(it.weight, std::memory_order_relaxed);
        },
        [](std::unique_ptr<Item>&) {},
        // Counts only plan the chunks (a chunk that turns out too large is split later), so a
        // sample of the points is enough where a reader can skip cheaply.
        kCountSampleStep);
    std::vector<uint64_t> counts(cells);
    for (size_t i = 0; i < cells; ++i) counts[i] = shared[i].load(std::memory_order_relaxed);
    std::vector<std::atomic<uint64_t>>().swap(shared);

    // Chunks: top-down, the largest nodes of the counting pyramid that fit the budget.
    std::vector<std::vector<uint64_t>> pyramid(gridLevel_ + 1);
    pyramid[gridLevel_] = std::move(counts);
    for (int l = static_cast<int>(gridLevel_) - 1; l >= 0; --l) {
      pyramid[l].assign(size_t(1) << (3 * l), 0);
      const uint32_t n = 1u << (l + 1);
      for (uint32_t x = 0; x < n; ++x)
        for (uint32_t y = 0; y < n; ++y)
          for (uint32_t z = 0; z < n; ++z)
            pyramid[l][((x >> 1) << (2 * l)) | ((y >> 1) << l) | (z >> 1)] +=
                pyramid[l + 1][(size_t(x) << (2 * (l + 1))) | (y << (l + 1)) | z];
    }
    maxChunkPoints_ = chunkBudget();
    cellChunk_.assign(cells, -1);
    std::function<void(NodeKey)> visit = [&](NodeKey k) {
      uint64_t c = pyramid[k.level][(size_t(k.x) << (2 * k.level)) | (k.y << k.level) | k.z];
      // Sampled counts can miss sparse cells, so nodes counted empty become chunks too; a chunk
      // that receives no points costs nothing later.
      if (c <= maxChunkPoints_ || k.level == gridLevel_) {
        int id = static_cast<int>(chunks_.size());
        chunks_.push_back({k, c, tmp_ / ("chunk-" + k.name() + ".bin")});
        const uint32_t s = gridLevel_ - k.level, n = 1u << s;
        for (uint32_t x = 0; x < n; ++x)
          for (uint32_t y = 0; y < n; ++y)
            for (uint32_t z = 0; z < n; ++z) {
              uint32_t gx = (k.x << s) | x, gy = (k.y << s) | y, gz = (k.z << s) | z;
              cellChunk_[(size_t(gx) << (2 * gridLevel_)) | (gy << gridLevel_) | gz] = id;
            }
        return;
      }
      for (int i = 0; i < 8; ++i) visit(k.child(i));
    };
    visit(NodeKey::root());
  }

  uint64_t chunkBudget() const {
    if (opt_.inMemory) return UINT64_MAX;
    // Indexing holds a chunk's records twice (read and sorted) plus sort keys and index lists.
    const uint64_t perPoint = 2 * (12 + stride_) + 40 + (estimate_ ? 64 : 0);
    uint64_t b = opt_.memoryBytes / 2 / threads_ / perPoint;
    return std::max<uint64_t>(b, uint64_t(opt_.maxNodePoints) * 4);
  }

  // ---- distribute -----------------------------------------------------------------------------

  void distributePass() {
    const size_t rec = 12 + stride_;
    for (auto& c : chunks_) c.points = 0;
    // A writer thread appends batches to the chunk files while the pipeline reads on; batches
    // wait in memory only up to a quarter of the budget.
    const size_t budget = std::max<size_t>(opt_.memoryBytes / 4, 16 << 20);
    std::mutex m;
    std::condition_variable cv;
    std::deque<std::unique_ptr<Item>> queue;
    size_t queued = 0;
    bool done = false;
    std::exception_ptr writeError;
    std::thread writer([&] {
      std::vector<std::unique_ptr<Item>> group;
      size_t groupBytes = 0;
      auto writeGroup = [&] {
        std::vector<std::vector<std::pair<const uint8_t*, size_t>>> perChunk(chunks_.size());
        for (auto& it : group) {
          size_t at = 0;
          for (auto& [c, n] : it->runs) {
            perChunk[c].emplace_back(it->records.get() + at, size_t(n) * rec);
            at += size_t(n) * rec;
          }
        }
        for (size_t c = 0; c < perChunk.size(); ++c) {
          if (perChunk[c].empty()) continue;
          FILE* f = std::fopen(chunks_[c].file.c_str(), "ab");
          bool ok = f != nullptr;
          for (auto& [p, n] : perChunk[c]) ok = ok && std::fwrite(p, 1, n, f) == n;
          if (f) ok = std::fclose(f) == 0 && ok;
          if (!ok)
            throw Error(chunks_[c].file.string(), "", "cannot write chunk file (disk full?)");
        }
        std::lock_guard<std::mutex> lock(m);
        queued -= groupBytes;
        group.clear();
        groupBytes = 0;
        cv.notify_all();
      };
      try {
        for (;;) {
          std::unique_ptr<Item> it;
          {
            std::unique_lock<std::mutex> lock(m);
            cv.wait(lock, [&] { return done || !queue.empty(); });
            if (queue.empty()) break;
            it = std::move(queue.front());
            queue.pop_front();
            cv.notify_all();  // a producer may wait for the queue to drain
          }
          groupBytes += it->recordBytes;
          group.push_back(std::move(it));
          if (groupBytes >= budget / 4) writeGroup();
        }
        writeGroup();
      } catch (...) {
        std::lock_guard<std::mutex> lock(m);
        writeError = std::current_exception();
        done = true;
        cv.notify_all();
      }
    });
    auto stopWriter = [&] {
      {
        std::lock_guard<std::mutex> lock(m);
        done = true;
        cv.notify_all();
      }
      writer.join();
    };
    try {
      readAll(
          "distribute",
          [&](Item& it) {
            const SourceState& s = sources_[it.source];
            const SourceHeader& h = s.reader->header();
            const size_t n = it.batch.size(), srcStride = h.layout.stride();
            thread_local std::vector<uint8_t> recs;
            thread_local std::vector<uint32_t> chunkOf;
            if (recs.size() < n * rec) recs.resize(n * rec);
            if (chunkOf.size() < n) chunkOf.resize(n);
            size_t kept = 0;
            it.acc.input = n;
            for (size_t k = 0; k < n; ++k) {
              const double* p = &it.batch.xyz[3 * k];
              uint32_t q[3];
              if (!quantise(s, p, q, it.acc, &it.outside)) continue;
              it.box.extend(p[0], p[1], p[2]);
              uint8_t* r = &recs[kept * rec];
              std::memcpy(r, q, 12);
              if (s.identity) {
                if (stride_) std::memcpy(r + 12, it.batch.attrs.data() + k * srcStride, stride_);
              } else
                mapAttributes(s, h.layout, it.batch.attrs.data() + k * srcStride, r + 12);
              chunkOf[kept] = static_cast<uint32_t>(cellChunk_[gridCell(q)]);
              ++kept;
            }
            // Group by chunk (counting sort, stable).
            std::vector<uint32_t> count(chunks_.size() + 1, 0);
            for (size_t k = 0; k < kept; ++k) count[chunkOf[k] + 1]++;
            for (size_t c = 0; c < chunks_.size(); ++c) {
              if (count[c + 1]) it.runs.emplace_back(static_cast<uint32_t>(c), count[c + 1]);
              count[c + 1] += count[c];
            }
            it.recordBytes = kept * rec;
            it.records.reset(new uint8_t[std::max<size_t>(it.recordBytes, 1)]);
            for (size_t k = 0; k < kept; ++k)
              std::memcpy(&it.records[size_t(count[chunkOf[k]]++) * rec], &recs[k * rec], rec);
            PointBatch().xyz.swap(it.batch.xyz);  // the input is no longer needed
            PointBatch().attrs.swap(it.batch.attrs);
          },
          [&](std::unique_ptr<Item>& it) {
            sources_[it->source].read += it->points;
            sources_[it->source].outsideDeclared += it->outside.first;
            sources_[it->source].outsideMax =
                std::max(sources_[it->source].outsideMax, it->outside.second);
            accounting_.add(it->acc);
            meta_.bounds.extend(it->box);
            for (auto& [c, n] : it->runs) chunks_[c].points += n;
            std::unique_lock<std::mutex> lock(m);
            if (writeError) std::rethrow_exception(writeError);
            cv.wait(lock, [&] {
              return queued + it->recordBytes <= budget || queue.empty() || writeError;
            });
            if (writeError) std::rethrow_exception(writeError);
            queued += it->recordBytes;
            queue.push_back(std::move(it));
            cv.notify_all();
          });
    } catch (...) {
      stopWriter();
      throw;
    }
    stopWriter();
    if (writeError) std::rethrow_exception(writeError);
    // Points a source declares but could not decode (damaged LAZ chunks read leniently) are
    // input that was rejected, so that the accounting still covers every declared point.
    for (auto& src : sources_)
      if (const uint64_t lost = src.reader->pointsUnreadable()) {
        accounting_.input += lost;
        accounting_.rejected[reject::kUnreadable] += lost;
        src.unreadable = lost;
      }
    std::vector<int32_t>().swap(cellChunk_);
  }

  void mapAttributes(const SourceState& s, const PointLayout& src, const uint8_t* in,
                     uint8_t* out) const {
    for (size_t i = 0; i < layout_.size(); ++i) {
      const Attribute& a = layout_[i];
      uint8_t* o = out + layout_.offset(i);
      const auto& e = s.map.entries[i];
      if (e.copy) {
        std::memcpy(o, in + src.offset(e.src), a.byteSize());
      } else if (e.src >= 0) {
        const Attribute& sa = src[e.src];
        const size_t w = scalarSize(sa.type), ow = scalarSize(a.type);
        for (uint32_t c = 0; c < a.components; ++c)
          storeFromDouble(a.type, loadAsDouble(sa.type, in + src.offset(e.src) + c * w),
                          o + c * ow);
      } else if (static_cast<int>(i) == normalIndex_ && estimate_) {
        const float nan = std::nanf("");
        for (int c = 0; c < 3; ++c) std::memcpy(o + 4 * c, &nan, 4);
      } else {
        std::memset(o, 0, a.byteSize());
      }
    }
  }

  // ---- index ----------------------------------------------------------------------------------

  void splitOversizedChunks() {
    // A counting cell denser than the budget (a dense statue in a city scan, a million duplicates)
    // is split into its octants, file to file, until it fits or cannot be split further.
    const size_t rec = 12 + stride_;
    for (size_t i = 0; i < chunks_.size(); ++i) {
      Chunk c = chunks_[i];
      if (c.points <= maxChunkPoints_ || (meta_.cubeSize >> c.key.level) <= 1) continue;
      const uint32_t half = (meta_.cubeSize >> c.key.level) >> 1;
      std::vector<FILE*> out(8, nullptr);
      std::vector<uint64_t> counts(8, 0);
      FILE* in = std::fopen(c.file.c_str(), "rb");
      if (!in) throw Error(c.file.string(), "", "cannot read chunk file");
      std::vector<uint8_t> buf(rec * 65536);
      size_t got;
      while ((got = std::fread(buf.data(), rec, 65536, in)) > 0) {
        for (size_t k = 0; k < got; ++k) {
          uint32_t q[3];
          std::memcpy(q, &buf[k * rec], 12);
          int ci = ((q[0] & half) ? 4 : 0) | ((q[1] & half) ? 2 : 0) | ((q[2] & half) ? 1 : 0);
          if (!out[ci]) {
            fs::path p = tmp_ / ("chunk-" + c.key.child(ci).name() + ".bin");
            out[ci] = std::fopen(p.c_str(), "wb");
            if (!out[ci]) throw Error(p.string(), "", "cannot create chunk file");
          }
          std::fwrite(&buf[k * rec], rec, 1, out[ci]);
          counts[ci]++;
        }
      }
      std::fclose(in);
      fs::remove(c.file);
      bool first = true;
      for (int ci = 0; ci < 8; ++ci) {
        if (!out[ci]) continue;
        std::fclose(out[ci]);
        Chunk child{c.key.child(ci), counts[ci],
                    tmp_ / ("chunk-" + c.key.child(ci).name() + ".bin")};
        if (first) {
          chunks_[i] = child;
          first = false;
        } else {
          chunks_.push_back(child);
        }
      }
      --i;  // re-examine the chunk now at index i
    }
  }

  void indexChunks() {
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

  void indexChunk(size_t ci, std::atomic<uint64_t>& merged) {
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

  PointBuffer loadRecords(const fs::path& file) const {
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

  void saveRecords(const fs::path& file, const PointBuffer& pts,
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

  void sortPoints(PointBuffer& pts, const NodeKey& key) const {
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
  static uint32_t mask(uint32_t bits) { return bits >= 32 ? ~0u : ((1u << bits) - 1); }

  // Merges exact duplicates (same position and attributes), adjacent after sorting.
  uint64_t dedup(PointBuffer& pts) const {
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

  void estimateMissingNormals(PointBuffer& pts) const {
    const size_t n = pts.size();
    std::vector<float> normals(3 * n, 0.f);
    // The orientation centre: the middle of the scan's tight bounds, in integer units.
    double c[3];
    for (int a = 0; a < 3; ++a)
      c[a] = ((meta_.bounds.min[a] + meta_.bounds.max[a]) * 0.5 - meta_.offset[a]) / meta_.scale[a];
    int orient = opt_.normalOrientation == NormalOrientation::Up       ? 2
                 : opt_.normalOrientation == NormalOrientation::Inward ? 1
                                                                       : 0;
    estimateNormals(pts.pos.data(), n, opt_.normalNeighbours, orient, c, normals.data());
    const size_t off = layout_.offset(normalIndex_);
    for (size_t i = 0; i < n; ++i) {
      float cur[3];
      std::memcpy(cur, pts.attrs.data() + i * stride_ + off, 12);
      if (std::isnan(cur[0]))
        std::memcpy(pts.attrs.data() + i * stride_ + off, &normals[3 * i], 12);
    }
  }

  // Returns the node's current sample (indices into pts); writes every node below it.
  std::vector<uint32_t> buildSubtree(const PointBuffer& pts, const NodeKey& key, size_t b,
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
  std::vector<uint32_t> sampleAndWriteChildren(const PointBuffer& pts, const NodeKey& key,
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

  // Spatially even subsample (Poisson disk or grid) with spacing size/128, widened until the
  // sample fits maxNodePoints: a volume-filling scan (a cube of points) would otherwise put
  // 128^3 points into one node.
  std::vector<char> sample(const PointBuffer& pts, const NodeKey& key,
                           const std::vector<uint32_t>& cand) const {
    const double size = meta_.cubeSize >> key.level;
    const uint32_t base[3] = {key.x * (meta_.cubeSize >> key.level),
                              key.y * (meta_.cubeSize >> key.level),
                              key.z * (meta_.cubeSize >> key.level)};
    double r = size / 128.0;
    std::vector<char> chosen(cand.size());
    for (int attempt = 0;; ++attempt) {
      const size_t limit = opt_.maxNodePoints;
      size_t accepted = opt_.sampling == Sampling::Grid
                            ? sampleGrid(pts, cand, base, r, chosen, limit)
                            : samplePoisson(pts, cand, base, r, chosen, limit);
      if (accepted <= opt_.maxNodePoints || attempt > 60) {
        NL_CHECK(accepted <= opt_.maxNodePoints);
        return chosen;
      }
      // Surfaces thin out with r^2, volumes with r^3: the square root never overshoots.
      r *= std::max(1.05, std::sqrt(double(accepted) / opt_.maxNodePoints));
    }
  }

  // Open-addressing map from a grid cell to the head of its list of accepted points.
  struct CellMap {
    // Key and head side by side: a probe touches one cache line.
    struct Slot {
      uint32_t key;
      int32_t head;
    };
    static constexpr uint32_t kEmpty = ~0u;
    std::vector<Slot> slots;
    uint64_t mask;
    int shift;
    explicit CellMap(size_t n) {
      size_t cap = 16;
      int bits = 4;
      while (cap < 2 * n) cap <<= 1, ++bits;
      slots.assign(cap, Slot{kEmpty, -1});
      mask = cap - 1;
      shift = 64 - bits;
    }
    // Fibonacci hashing: the top bits of the product are the well-mixed ones.
    uint64_t home(uint32_t k) const { return (k * 0x9E3779B97F4A7C15ull) >> shift; }
    int32_t& slot(uint32_t k) {
      for (uint64_t i = home(k);; i = (i + 1) & mask) {
        if (slots[i].key == k || slots[i].key == kEmpty) {
          slots[i].key = k;
          return slots[i].head;
        }
      }
    }
    int32_t find(uint32_t k) const {
      for (uint64_t i = home(k);; i = (i + 1) & mask) {
        if (slots[i].key == k) return slots[i].head;
        if (slots[i].key == kEmpty) return -1;
      }
    }
  };
  // Cells of the sampling grid: r is at least size/128, so a node spans at most 129 cells per
  // axis; with one more on each side for neighbour probes a cell's index fits 32 bits.
  static constexpr int64_t kCellSide = 131;
  static uint32_t cellKey(int64_t x, int64_t y, int64_t z) {
    return static_cast<uint32_t>(((x + 1) * kCellSide + (y + 1)) * kCellSide + (z + 1));
  }

  // Both samplers give up once `limit` points are accepted and return an estimate of the total
  // they would have accepted, so that an over-full attempt costs only part of a pass.
  size_t samplePoisson(const PointBuffer& pts, const std::vector<uint32_t>& cand,
                       const uint32_t base[3], double r, std::vector<char>& chosen,
                       size_t limit) const {
    // Neighbour cells, own cell first: in dense data most candidates are rejected there.
    static const std::array<std::array<int, 3>, 27> offsets = [] {
      std::array<std::array<int, 3>, 27> o{};
      int n = 1;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz)
            if (dx || dy || dz) o[n++] = {dx, dy, dz};
      return o;
    }();
    CellMap cells(std::min(cand.size(), limit + 1));
    // Accepted points as (position, next in cell): the distance tests read them in acceptance
    // order, near each other, instead of gathering from the chunk's point array.
    struct Accepted {
      uint32_t p[3];
      int32_t next;
    };
    thread_local std::vector<Accepted> acc;
    acc.clear();
    const double r2 = r * r, inv = 1.0 / r;
    // Occupied cells as a dense bitmap over the cell keys; most neighbour probes end here.
    thread_local std::vector<uint64_t> occupied;
    occupied.assign((kCellSide * kCellSide * kCellSide + 63) / 64, 0);
    size_t accepted = 0;
    for (size_t k = 0; k < cand.size(); ++k) {
      const uint32_t* p = &pts.pos[3 * size_t(cand[k])];
      const double x = p[0] - base[0], y = p[1] - base[1], z = p[2] - base[2];
      const int64_t cx = int64_t(x * inv), cy = int64_t(y * inv), cz = int64_t(z * inv);
      bool ok = true;
      for (const auto& d : offsets) {
        const uint32_t b = cellKey(cx + d[0], cy + d[1], cz + d[2]);
        if (!(occupied[b >> 6] >> (b & 63) & 1)) continue;
        for (int32_t j = cells.find(b); j >= 0; j = acc[j].next) {
          const uint32_t* q = acc[j].p;
          const double ex = double(q[0]) - p[0], ey = double(q[1]) - p[1], ez = double(q[2]) - p[2];
          if (ex * ex + ey * ey + ez * ez < r2) {
            ok = false;
            break;
          }
        }
        if (!ok) break;
      }
      chosen[k] = ok;
      if (!ok) continue;
      if (++accepted > limit) return accepted * cand.size() / (k + 1);
      const uint32_t b = cellKey(cx, cy, cz);
      occupied[b >> 6] |= uint64_t(1) << (b & 63);
      int32_t& head = cells.slot(b);
      acc.push_back({{p[0], p[1], p[2]}, head});
      head = static_cast<int32_t>(acc.size() - 1);
    }
    return accepted;
  }

  size_t sampleGrid(const PointBuffer& pts, const std::vector<uint32_t>& cand,
                    const uint32_t base[3], double r, std::vector<char>& chosen,
                    size_t limit) const {
    CellMap cells(std::min(cand.size(), limit + 1));
    const double inv = 1.0 / r;
    size_t accepted = 0;
    for (size_t k = 0; k < cand.size(); ++k) {
      const uint32_t* p = &pts.pos[3 * size_t(cand[k])];
      int32_t& head =
          cells.slot(cellKey(int64_t((p[0] - base[0]) * inv), int64_t((p[1] - base[1]) * inv),
                             int64_t((p[2] - base[2]) * inv)));
      chosen[k] = head < 0;
      if (head < 0) {
        head = 0;
        if (++accepted > limit) return accepted * cand.size() / (k + 1);
      }
    }
    return accepted;
  }

  // `drawnSet`: `set` and the ancestors' points inside the node (a superset of `set`, in Morton
  // order), on which the node's spacing is measured.
  void writeNode(const NodeKey& key, const PointBuffer& pts, const std::vector<uint32_t>& set,
                 const std::vector<uint32_t>& drawnSet) {
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

  // ---- merge ----------------------------------------------------------------------------------

  fs::path provisionalFile(const NodeKey& k) const {
    return tmp_ / ("sample-" + k.name() + ".bin");
  }

  void saveProvisional(const NodeKey& key, const PointBuffer& pts, const std::vector<uint32_t>& set,
                       uint64_t subtreePoints) {
    saveRecords(provisionalFile(key), pts, set);
    std::lock_guard<std::mutex> lock(pendingMutex_);
    pending_.insert(key);
    subtreePoints_[key] = subtreePoints;
  }

  void mergeTop() {
    // Nodes above the chunks, deepest first; each level's nodes in parallel.
    std::map<uint32_t, std::set<NodeKey>> byLevel;
    for (const NodeKey& k : pending_)
      for (uint32_t l = 0; l < k.level; ++l) byLevel[l].insert(k.ancestor(l));
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
    // The root's current sample is final.
    fs::path rootFile = provisionalFile(NodeKey::root());
    PointBuffer root = loadRecords(rootFile);
    std::vector<uint32_t> all(root.size());
    std::iota(all.begin(), all.end(), 0u);
    writeNode(NodeKey::root(), root, all, all);
  }

  // ---- metadata -------------------------------------------------------------------------------

  void finishMetadata() {
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
      for (std::string w : s.reader->warnings()) {
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
        {"chunks", chunks_.size()},
        {"max_chunk_points", maxChunkPoints_ == UINT64_MAX ? json(nullptr) : json(maxChunkPoints_)},
        {"command_line", opt_.commandLine}};
    if (!buildNotes_.empty()) meta_.build["notes"] = buildNotes_;
  }
  BuildOptions opt_;
  Progress progress_;
  std::vector<SourceState> sources_;
  PointLayout layout_;
  std::set<std::string> widened_;
  size_t stride_ = 0;
  int normalIndex_ = -1;
  bool estimate_ = false;
  unsigned threads_ = 1;
  Metadata meta_;
  Vec3d invScale_{1000, 1000, 1000};
  Accounting accounting_;
  std::unique_ptr<OctreeWriter> writer_;
  fs::path tmp_;
  uint32_t gridLevel_ = 0;
  uint32_t gridShift_ = 0;  // cubeBits() - gridLevel_, per point in gridCell()
  uint64_t maxChunkPoints_ = 0;
  std::vector<int32_t> cellChunk_;
  std::vector<Chunk> chunks_;
  std::mutex pendingMutex_;
  std::set<NodeKey> pending_;
  std::map<NodeKey, uint64_t> subtreePoints_;
  std::atomic<uint64_t> stored_{0};
  bool measureBounds_ = false;  // plan the cube from the points even where headers declare bounds
  mutable std::atomic<bool> outsideCube_{false};  // a point beyond the planned cube was met
  std::vector<std::string>
      buildNotes_;  // facts of the build that `info` shows (metadata build.notes)
};

}  // namespace

BuildReport buildOctree(std::vector<std::unique_ptr<PointReader>> sources,
                        const BuildOptions& options) {
  Builder b(std::move(sources), options, false);
  try {
    return b.run();
  } catch (const OutsideCube&) {
    // A header declared bounds its points overstep by more than rounding: measure them instead.
  }
  Builder measured(b.takeSources(), options, true);
  BuildReport r = measured.run();
  r.warnings.push_back(
      "points lie far outside the bounds a header declares: the extent was measured from the "
      "points, which took one more reading of the input");
  return r;
}

}  // namespace nestlight
