// The out-of-core builder's state, shared by its passes (one file each: plan.cpp, distribute.cpp,
// index.cpp, sample.cpp, merge.cpp; builder.cpp runs them). The algorithm and its papers are
// described at the top of builder.cpp.
#pragma once

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
#include <optional>
#include <set>
#include <thread>
#include <unordered_set>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/normals.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/node_key.h"
#include "nestlight/octree/octree_writer.h"
#include "nestlight/octree/spacing.h"
#include "nestlight/octree/staged_directory.h"

namespace nestlight::build_passes {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// The shortest text that reads back as `v` (a scale such as 1.1645e-06).
inline std::string shortNumber(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

constexpr size_t kBatchPoints = 1 << 18;
constexpr uint32_t kGridLevel = 7;  // counting grid: 128^3 cells
constexpr size_t kCountSampleStep = 8;
// The share of a conversion's time each phase with progress takes, for the overall ETA
// (Progress::plan, which scales the phases to come by the time the measured ones took). 3 M
// points on 2 cores: LAS count 0.27 s, distribute 0.95 s, index 4.3 s, merge 0.04 s; LAZ 1.15,
// 5.7, 4.0, 0.04 s. Reading (bounds, count, distribute) scales with the input's decoding, index
// with the points: the shares lie between the two, and index's own rate takes over once it runs.
inline const std::vector<std::pair<std::string, double>> kPhaseShares = {
    {"bounds", 0.7}, {"count", 0.25}, {"distribute", 1.0}, {"index", 2.0}, {"merge", 0.05}};

inline double seconds(Clock::time_point a) {
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
  fs::path file;  // another rank's chunk: this rank's outbox for that rank (distributed.cpp)
  int owner = 0;  // the rank that indexes it
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
  bool owned = true;  // this rank reads it (a job of several ranks deals the inputs out)
  std::optional<std::vector<std::string>> remoteWarnings;  // the reading rank's reader's warnings
  uint64_t read = 0;
  uint64_t unreadable = 0;       // declared points it could not decode (lenient), in the input
  uint64_t outsideDeclared = 0;  // points beyond the declared bounds (and tolerance), kept
  double outsideMax = 0;         // the farthest of them, in units of the input
};

// A point beyond the cube planned from declared bounds: the conversion starts again with the
// bounds measured from the points (buildOctree).
struct OutsideCube {};

inline bool validBox(const Box3d& b) {
  return !b.empty() && std::isfinite(b.min.x) && std::isfinite(b.min.y) && std::isfinite(b.min.z) &&
         std::isfinite(b.max.x) && std::isfinite(b.max.y) && std::isfinite(b.max.z);
}

// This process's folder for chunk files and the other temporary data: in --scratch (named after
// the output, so that a rerun finds and removes what a killed one left), else inside the staging
// folder `staged`.
fs::path scratchFolder(const BuildOptions& o, const fs::path& staged, int rank, bool distributed);

class Builder {
  using json = nlohmann::json;

 public:
  Builder(std::vector<std::unique_ptr<PointReader>> sources, const BuildOptions& o,
          bool measureBounds);
  std::vector<std::unique_ptr<PointReader>> takeSources();

  BuildReport run();

 private:
  // ---- planning -------------------------------------------------------------------------------

  // Planning visits sources sorted by path, so that the layout and the grid's offset do not
  // depend on the order the inputs were given in.
  std::vector<SourceState*> planningOrder();

  void planLayout();

  void planQuantisation(BuildReport& report);

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
  void readAll(const std::string& phase, Work work, Collect collect, size_t sampleStep = 1);

  // Quantises point k of the item; false (and counted) when rejected. Points beyond their
  // header's bounds are kept, and counted in `outside` (the distribute pass) for a warning.
  bool quantise(const SourceState& s, const double* p, uint32_t q[3], Accounting& acc,
                std::pair<uint64_t, double>* outside = nullptr) const;

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

  void countPass();

  uint64_t chunkBudget() const;

  // ---- distribute -----------------------------------------------------------------------------

  void distributePass();

  void mapAttributes(const SourceState& s, const PointLayout& src, const uint8_t* in,
                     uint8_t* out) const;

  // ---- index ----------------------------------------------------------------------------------

  void splitOversizedChunks();

  void indexChunks();

  void indexChunk(size_t ci, std::atomic<uint64_t>& merged);

  PointBuffer loadRecords(const fs::path& file) const;

  void saveRecords(const fs::path& file, const PointBuffer& pts,
                   const std::vector<uint32_t>& set) const;

  void sortPoints(PointBuffer& pts, const NodeKey& key) const;
  static uint32_t mask(uint32_t bits) { return bits >= 32 ? ~0u : ((1u << bits) - 1); }

  // Merges exact duplicates (same position and attributes), adjacent after sorting.
  uint64_t dedup(PointBuffer& pts) const;

  void estimateMissingNormals(PointBuffer& pts) const;

  // Returns the node's current sample (indices into pts); writes every node below it.
  std::vector<uint32_t> buildSubtree(const PointBuffer& pts, const NodeKey& key, size_t b,
                                     size_t e);

  // Selects `key`'s sample from its children's current samples and writes the children.
  std::vector<uint32_t> sampleAndWriteChildren(const PointBuffer& pts, const NodeKey& key,
                                               std::array<std::vector<uint32_t>, 8>& sets);

  // Spatially even subsample (Poisson disk or grid) with spacing size/128, widened until the
  // sample fits maxNodePoints: a volume-filling scan (a cube of points) would otherwise put
  // 128^3 points into one node.
  std::vector<char> sample(const PointBuffer& pts, const NodeKey& key,
                           const std::vector<uint32_t>& cand) const;

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
                       size_t limit) const;

  size_t sampleGrid(const PointBuffer& pts, const std::vector<uint32_t>& cand,
                    const uint32_t base[3], double r, std::vector<char>& chosen,
                    size_t limit) const;

  // `drawnSet`: `set` and the ancestors' points inside the node (a superset of `set`, in Morton
  // order), on which the node's spacing is measured.
  void writeNode(const NodeKey& key, const PointBuffer& pts, const std::vector<uint32_t>& set,
                 const std::vector<uint32_t>& drawnSet);

  // ---- merge ----------------------------------------------------------------------------------

  fs::path provisionalFile(const NodeKey& k) const {
    return tmp_ / ("sample-" + k.name() + ".bin");
  }

  void saveProvisional(const NodeKey& key, const PointBuffer& pts, const std::vector<uint32_t>& set,
                       uint64_t subtreePoints);

  void mergeTop();
  // Merges `nodes` (each from its children's provisional samples, here), deepest level first.
  void mergeNodes(const std::set<NodeKey>& nodes);
  // Writes the root from its provisional sample (none: an empty root).
  void writeRoot();

  // ---- a job of several ranks (distributed.cpp) -------------------------------------------------

  bool distributed() const { return comm_ && comm_->size() > 1; }
  // Inputs dealt to ranks by size, largest first to the least loaded (ties: lower rank).
  void dealSources();
  // Chunks (in Morton order) cut into one contiguous range per rank with equal counted points.
  void assignChunks();
  // Every rank's outboxes to their chunks' owners, in rounds within the memory budget.
  void exchangeRecords();
  // The levels above the chunks: each rank merges the nodes whose chunks are all its own; rank 0
  // the rest, from the other ranks' samples of the nodes just below them.
  void mergeTopDistributed();
  // Accounting, bounds and the sources' counts and warnings brought together on every rank.
  void reduceTotals();
  // Each rank's part of the payload copied into the output at offsets agreed from their sizes;
  // rank 0 writes the hierarchy and metadata.
  void assembleOutput(const fs::path& staged);
  // Per rank: input bytes, points indexed, bytes sent, peak memory, phases (rank 0 gets all).
  nlohmann::json gatherRankReports(const BuildReport& mine);
  int rank() const { return comm_ ? comm_->rank() : 0; }
  int ranks() const { return comm_ ? comm_->size() : 1; }

  // ---- metadata -------------------------------------------------------------------------------

  void finishMetadata();
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
  Communicator* comm_ = nullptr;
  uint64_t bytesSent_ = 0;    // records sent to other ranks
  uint64_t indexed_ = 0;      // points of this rank's chunks
  uint64_t chunksTotal_ = 0;  // a job's chunks (each rank knows its own after splitting)
};

}  // namespace nestlight::build_passes
