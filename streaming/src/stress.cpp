// The stress test of the scheduler. Camera paths follow what breaks streaming schedulers in
// practice (Potree's users fly fast and teleport through bookmarks): every frame a new random
// view, flights faster than the loaders, orbits that sweep the frustum across the whole scan,
// then stops, after which the cut must become complete within a bounded number of frames. The
// store checks the byte budget at every upload, not only between frames, and the render thread's
// reader calls are counted around each update().
#include "nestlight/streaming/stress.h"

#include <time.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>
#include <unordered_set>

#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/memory_store.h"

namespace nestlight::streaming {

namespace {

// The memory store, checking the scheduler's promises at every call.
class CheckingStore : public NodeStore {
 public:
  CheckingStore(const Metadata& meta, std::thread::id renderThread)
      : mem(meta, false), renderThread_(renderThread) {}

  void prepare(const NodeKey& key, PointBuffer&& points, PreparedNode& out) const override {
    if (std::this_thread::get_id() == renderThread_) preparesOnRenderThread.fetch_add(1);
    mem.prepare(key, std::move(points), out);
  }
  uint64_t upload(const PreparedNode& node) override {
    const uint64_t after = mem.liveBytes() + node.residentBytes();
    if (after > budget) ++uploadsOverBudget;
    maxLive = std::max(maxLive, after);
    return mem.upload(node);
  }
  void release(uint64_t handle) override { mem.release(handle); }

  MemoryStore mem;
  uint64_t budget = 0;  // the GPU budget of the update() running now
  uint64_t uploadsOverBudget = 0;
  uint64_t maxLive = 0;
  mutable std::atomic<uint64_t> preparesOnRenderThread{0};

 private:
  std::thread::id renderThread_;
};

double threadCpuMs() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(std::ceil(p * double(v.size())) - 1));
  return v[p <= 0 ? 0 : i];
}

class Run {
 public:
  Run(OctreeReader& reader, const StressOptions& o)
      : reader_(reader),
        opt_(o),
        rng_(o.seed),
        store_(reader.metadata(), std::this_thread::get_id()),
        budgets_(o.budgets) {
    const Box3d& b = reader.metadata().bounds;
    if (b.empty()) {
      lo_ = hi_ = glm::dvec3(reader.metadata().offset.x, reader.metadata().offset.y,
                             reader.metadata().offset.z);
    } else {
      lo_ = {b.min.x, b.min.y, b.min.z};
      hi_ = {b.max.x, b.max.y, b.max.z};
    }
    center_ = 0.5 * (lo_ + hi_);
    diag_ = std::max(glm::length(hi_ - lo_), 1.0);
    store_.budget = budgets_.gpuBytes;
  }

  StressReport run() {
    streamer_ = std::make_unique<Streamer>(reader_, store_, budgets_);
    streamer_->onBadNode([this](const BadNode& b) {
      std::lock_guard<std::mutex> lock(badMutex_);
      badMessages_.push_back(b.message);
    });
    eye_ = center_ + glm::dvec3(0, -diag_, 0.5 * diag_);
    target_ = center_;
    while (report_.frames < opt_.frames) {
      if (opt_.varyBudgets && uniform(0, 1) < 0.3) varyBudgets();
      // A moving phase, then (every other time or so) a stop where the cut must complete.
      const int phase = std::uniform_int_distribution<int>(0, 2)(rng_);
      if (phase == 0)
        teleports();
      else if (phase == 1)
        flight();
      else
        orbit();
      if (report_.frames < opt_.frames && uniform(0, 1) < 0.5) stop();
    }
    // The end: full budgets again, stop, and let every request finish.
    if (opt_.varyBudgets) setBudgets(opt_.budgets);
    stop();
    drain();
    streamer_.reset();
    finalChecks();
    return finish();
  }

 private:
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }
  glm::dvec3 randomPointInBounds() {
    return {uniform(lo_.x, hi_.x + 1e-9), uniform(lo_.y, hi_.y + 1e-9),
            uniform(lo_.z, hi_.z + 1e-9)};
  }
  glm::dvec3 randomEye() {
    // Half the time close to the scan, where the cut goes deep; else around it.
    if (uniform(0, 1) < 0.5)
      return randomPointInBounds() + glm::dvec3(0, 0, diag_ * uniform(0.005, 0.1));
    glm::dvec3 d(uniform(-1, 1), uniform(-1, 1), uniform(0.05, 1));
    return center_ + glm::normalize(d) * (diag_ * uniform(0.1, 1.5));
  }

  View view() const {
    glm::dvec3 dir = target_ - eye_;
    glm::dvec3 target = glm::length(dir) < 1e-6 * diag_ ? eye_ + glm::dvec3(0, diag_, 0) : target_;
    dir = glm::normalize(target - eye_);
    const glm::dvec3 up = std::abs(dir.z) > 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
    return perspectiveView(eye_, target, up, glm::radians(60.0), opt_.widthPx, opt_.heightPx,
                           std::max(1e-4 * diag_, 0.01), 20 * diag_);
  }

  void setBudgets(const Budgets& b) {
    budgets_ = b;
    streamer_->setBudgets(b);
    ++report_.budgetChanges;
  }
  void varyBudgets() {
    static const double scales[] = {0.25, 0.5, 1, 1, 2};
    auto pick = [&] { return scales[std::uniform_int_distribution<int>(0, 4)(rng_)]; };
    Budgets b = opt_.budgets;
    b.points = std::max<uint64_t>(1, static_cast<uint64_t>(double(b.points) * pick()));
    b.gpuBytes = std::max<uint64_t>(1, static_cast<uint64_t>(double(b.gpuBytes) * pick()));
    b.uploadBytesPerFrame =
        std::max<uint64_t>(1, static_cast<uint64_t>(double(b.uploadBytesPerFrame) * pick()));
    b.loaderThreads = std::uniform_int_distribution<int>(1, 3)(rng_);
    setBudgets(b);
  }

  void violation(const std::string& what) {
    ++report_.violationCount;
    if (report_.violations.size() < 20)
      report_.violations.push_back("frame " + std::to_string(report_.frames) + ": " + what);
  }

  // One update() and its checks.
  const FrameStats& frame() {
    store_.budget = budgets_.gpuBytes;
    const uint64_t callsBefore = OctreeReader::threadReadCalls();
    const View v = view();
    const double cpu0 = threadCpuMs();
    const auto t = std::chrono::steady_clock::now();
    const FrameStats& s = streamer_->update(v);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
    updateCpuMs_.push_back(threadCpuMs() - cpu0);
    const uint64_t calls = OctreeReader::threadReadCalls() - callsBefore;
    ++report_.frames;
    updateMs_.push_back(ms);
    report_.renderThreadReaderCalls += calls;
    if (calls)
      violation(std::to_string(calls) + " reader calls on the render thread inside update()");
    if (opt_.maxUpdateMs > 0 && ms > opt_.maxUpdateMs)
      violation("update() took " + std::to_string(ms) + " ms");
    if (s.residentBytes > budgets_.gpuBytes)
      violation("resident bytes " + std::to_string(s.residentBytes) + " over the budget " +
                std::to_string(budgets_.gpuBytes));
    if (store_.uploadsOverBudget) {
      violation("an upload took the store over the GPU budget");
      store_.uploadsOverBudget = 0;
    }
    if (s.residentBytes != store_.mem.liveBytes() || s.residentNodes != store_.mem.liveHandles())
      violation("stats disagree with the store: " + std::to_string(s.residentNodes) + " nodes, " +
                std::to_string(s.residentBytes) + " bytes against " +
                std::to_string(store_.mem.liveHandles()) + ", " +
                std::to_string(store_.mem.liveBytes()));
    if (s.cutPoints > budgets_.points || s.drawPoints > budgets_.points)
      violation("cut of " + std::to_string(s.cutPoints) + " points over the point budget");
    if (s.badNodes) {
      std::lock_guard<std::mutex> lock(badMutex_);
      violation("bad node: " + (badMessages_.empty() ? std::string("?") : badMessages_[0]));
    }
    drawn_.clear();
    for (const DrawNode& d : streamer_->drawList()) {
      if (d.key.level > 0 && !drawn_.count(d.key.parent()))
        violation("node " + d.key.name() + " drawn without its parent before it");
      if (!(store_.mem.keyOf(d.handle) == d.key))
        violation("node " + d.key.name() + " has a stale handle");
      drawn_.insert(d.key);
    }
    if (opt_.progress && opt_.progressEvery && report_.frames % opt_.progressEvery == 0)
      opt_.progress(report_.frames);
    if (opt_.frameMs > 0) {
      const double rest = opt_.frameMs - ms;
      if (rest > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(rest));
    }
    return s;
  }

  void teleports() {
    const int n = std::uniform_int_distribution<int>(10, 80)(rng_);
    for (int i = 0; i < n && report_.frames < opt_.frames; ++i) {
      eye_ = randomEye();
      target_ = randomPointInBounds();
      frame();
    }
  }
  void flight() {
    const glm::dvec3 a = randomEye(), b = randomEye();
    const int n = std::uniform_int_distribution<int>(30, 200)(rng_);
    for (int i = 0; i <= n && report_.frames < opt_.frames; ++i) {
      const double t = double(i) / n;
      eye_ = a + (b - a) * t;
      target_ = eye_ + (b - a) + glm::dvec3(0, 0, -0.2 * diag_);
      frame();
    }
  }
  void orbit() {
    const double radius = diag_ * uniform(0.2, 1.2), height = diag_ * uniform(0.02, 0.8);
    const double speed = glm::radians(uniform(0.5, 8.0)), start = uniform(0, 6.283);
    const int n = std::uniform_int_distribution<int>(60, 300)(rng_);
    for (int i = 0; i < n && report_.frames < opt_.frames; ++i) {
      const double a = start + speed * i;
      eye_ = center_ + glm::dvec3(radius * std::cos(a), radius * std::sin(a), height);
      target_ = center_;
      frame();
    }
  }
  void stop() {
    ++report_.stops;
    uint64_t n = 0;
    bool complete = false;
    while (n < opt_.settleFrames && !complete) {
      complete = frame().complete;
      ++n;
    }
    if (!complete) {
      const FrameStats& s = streamer_->stats();
      violation("the cut was not complete " + std::to_string(opt_.settleFrames) +
                " frames after the camera stopped (cut " + std::to_string(s.cutNodes) +
                " nodes, drawn " + std::to_string(s.drawNodes) + ", queue " +
                std::to_string(s.queueLength) + ", in flight " + std::to_string(s.inFlight) +
                ", ready " + std::to_string(s.readyWaiting) + ")");
    }
    settle_.push_back(double(n));
    // A complete cut stays complete while the camera stays.
    for (int i = 0; i < 5 && complete; ++i)
      if (!frame().complete) violation("the cut lost completeness with the camera stopped");
  }
  void drain() {
    for (uint64_t i = 0; i < opt_.settleFrames; ++i) {
      const FrameStats& s = frame();
      if (s.queueLength == 0 && s.inFlight == 0) break;
    }
    const Streamer::Totals t = streamer_->totals();
    const FrameStats& s = streamer_->stats();
    if (s.queueLength || s.inFlight)
      violation("requests still pending " + std::to_string(opt_.settleFrames) +
                " frames after the stop");
    else if (t.requested != t.completed + t.cancelled + t.failed)
      violation("requests " + std::to_string(t.requested) + " != completed " +
                std::to_string(t.completed) + " + cancelled " + std::to_string(t.cancelled) +
                " + failed " + std::to_string(t.failed));
    report_.totals = t;
  }
  void finalChecks() {
    if (store_.mem.liveHandles() || store_.mem.liveBytes())
      violation("the streamer left " + std::to_string(store_.mem.liveHandles()) +
                " handles resident");
    if (store_.mem.badReleases()) violation("handles released twice or never uploaded");
    if (store_.preparesOnRenderThread.load()) violation("prepare() ran on the render thread");
  }
  StressReport finish() {
    report_.updateMsMax = percentile(updateMs_, 1.0);
    report_.updateMsMedian = percentile(updateMs_, 0.5);
    report_.updateMsP99 = percentile(updateMs_, 0.99);
    report_.updateCpuMsMax = percentile(updateCpuMs_, 1.0);
    report_.updateCpuMsMedian = percentile(updateCpuMs_, 0.5);
    report_.updateCpuMsP99 = percentile(updateCpuMs_, 0.99);
    for (double f : settle_) report_.settleFrames.push_back(static_cast<uint64_t>(f));
    report_.settleFramesMax = static_cast<uint64_t>(percentile(settle_, 1.0));
    report_.settleFramesMedian = static_cast<uint64_t>(percentile(settle_, 0.5));
    report_.maxResidentBytes = store_.maxLive;
    return report_;
  }

  OctreeReader& reader_;
  StressOptions opt_;
  std::mt19937_64 rng_;
  CheckingStore store_;
  Budgets budgets_;
  std::unique_ptr<Streamer> streamer_;
  glm::dvec3 lo_, hi_, center_, eye_, target_;
  double diag_ = 1;
  StressReport report_;
  std::vector<double> updateMs_, updateCpuMs_, settle_;
  std::unordered_set<NodeKey, NodeKeyHash> drawn_;
  std::mutex badMutex_;
  std::vector<std::string> badMessages_;
};

}  // namespace

nlohmann::json StressReport::toJson() const {
  return {{"frames", frames},
          {"stops", stops},
          {"settle_frames_max", settleFramesMax},
          {"settle_frames_median", settleFramesMedian},
          {"update_ms", {{"max", updateMsMax}, {"median", updateMsMedian}, {"p99", updateMsP99}}},
          {"update_cpu_ms",
           {{"max", updateCpuMsMax}, {"median", updateCpuMsMedian}, {"p99", updateCpuMsP99}}},
          {"settle_frames", settleFrames},
          {"render_thread_reader_calls", renderThreadReaderCalls},
          {"max_resident_bytes", maxResidentBytes},
          {"budget_changes", budgetChanges},
          {"totals",
           {{"requested", totals.requested},
            {"completed", totals.completed},
            {"cancelled", totals.cancelled},
            {"failed", totals.failed},
            {"uploaded", totals.uploaded},
            {"evicted", totals.evicted},
            {"bytes_read", totals.bytesRead},
            {"discarded", totals.discarded}}},
          {"violation_count", violationCount},
          {"violations", violations},
          {"ok", ok()}};
}

StressReport runStress(OctreeReader& reader, const StressOptions& options) {
  return Run(reader, options).run();
}

}  // namespace nestlight::streaming
