// Level-of-detail paging of an octree under budgets.
//
// Each frame (update(), on the render thread): the cut is selected top-down from the root by
// screen-space priority (projected node size) under a point budget, with frustum culling; the
// load queue is replaced by the cut's missing nodes in priority order (requests no longer wanted
// are cancelled unless a loader already took them); finished loads are uploaded, at most
// Budgets::uploadBytesPerFrame per frame; least-recently-used resident nodes outside the cut are
// evicted to stay within Budgets::gpuBytes. Loader threads read, check and decode payloads and
// hierarchy chunks: update() itself never reads a file. A node is drawn only when it and all its
// ancestors are resident, so the picture never has holes.
//
// The cut is the prefix, in priority order, that fits both budgets: its points within
// Budgets::points and its resident bytes (known from earlier loads, else estimated from the
// store's bytes per point so far) within Budgets::gpuBytes, so a complete cut fits in GPU memory.
// Resident bytes never exceed Budgets::gpuBytes, not even within an update(): room is made
// before an upload (nodes outside the cut first, least recently wanted first; a cut node only
// for one of higher priority), and an upload that cannot fit waits. Loader threads run below the
// render thread's priority (Linux: SCHED_BATCH, nice 10).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/octree/node_key.h"
#include "nestlight/streaming/node_store.h"
#include "nestlight/streaming/view.h"

namespace nestlight {
class OctreeReader;
}

namespace nestlight::streaming {

struct Budgets {
  uint64_t points = 5'000'000;       // points in the cut
  uint64_t gpuBytes = 512ull << 20;  // resident bytes (NodeStore sizes), never exceeded
  uint64_t uploadBytesPerFrame = 32ull << 20;
  int loaderThreads = 2;
  // A node's children are wanted while its point spacing projects to more than this many
  // pixels: the screen-space error target. 0 refines everything the point budget allows.
  double spacingPixels = 1.0;
};

struct FrameStats {
  uint64_t frame = 0;
  uint32_t cutNodes = 0;  // nodes the view wants (within budgets)
  uint64_t cutPoints = 0;
  uint32_t drawNodes = 0;  // resident cut nodes with all ancestors resident
  uint64_t drawPoints = 0;
  uint32_t residentNodes = 0;
  uint64_t residentBytes = 0;
  uint32_t uploads = 0;  // this frame
  uint64_t uploadBytes = 0;
  uint32_t evictions = 0;
  uint32_t cancelled = 0;     // requests dropped from the queue this frame
  uint32_t queueLength = 0;   // requests waiting for a loader
  uint32_t inFlight = 0;      // taken by a loader, not yet finished
  uint32_t readyWaiting = 0;  // loaded, waiting for upload budget
  uint64_t bytesRead = 0;     // payload + hierarchy bytes read by loaders this frame
  uint32_t badNodes = 0;      // total so far
  bool complete = false;      // every cut node drawn, nothing pending for the cut
  double msCutSelection = 0;
  double msUpload = 0;
  double msUpdate = 0;  // the whole update()
};

// One node to draw this frame.
struct DrawNode {
  NodeKey key;
  uint64_t handle = 0;  // from NodeStore::upload
  uint32_t numPoints = 0;
  Box3d worldBounds;   // the node's cube in world units
  double spacing = 0;  // the node's nominal point spacing, world units
  // The measured spacing of the points drawn where this node is the finest drawn node (its own
  // and its ancestors' points in its cube), world units; the nominal spacing for octrees that
  // did not record it (format version 1). Splats are sized by it.
  double pointSpacing = 0;
};

struct BadNode {
  NodeKey key;
  std::string message;  // names the node and the file
};

class Streamer {
 public:
  // The reader must outlive the streamer; so must the store.
  Streamer(OctreeReader& reader, NodeStore& store, const Budgets& budgets);
  ~Streamer();  // stops loaders, releases every resident node
  Streamer(const Streamer&) = delete;
  Streamer& operator=(const Streamer&) = delete;

  const FrameStats& update(const View& view);
  const std::vector<DrawNode>& drawList() const;  // of the last update(), parents first
  const FrameStats& stats() const;
  void setBudgets(const Budgets& b);  // takes effect at the next update()
  const Budgets& budgets() const;
  std::vector<BadNode> badNodes() const;
  // Called once per bad node, from the loader thread that found it (from update() for a
  // hierarchy chunk that contradicts its parent chunk); default: a line on stderr. It must stay
  // callable until the streamer is destroyed.
  void onBadNode(std::function<void(const BadNode&)> log);

  // Totals since construction, for tests and the stress tool.
  struct Totals {
    uint64_t requested = 0, completed = 0, cancelled = 0, failed = 0, uploaded = 0, evicted = 0;
    uint64_t bytesRead = 0, discarded = 0;  // discarded: loaded but no longer wanted
    uint64_t maxResidentBytes = 0;
  };
  Totals totals() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nestlight::streaming
