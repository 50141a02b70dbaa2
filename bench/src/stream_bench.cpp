// `nestlight bench stream` (nestlight/bench/stream_bench.h).
#include "nestlight/bench/stream_bench.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <functional>
#include <random>
#include <thread>
#include <vector>

#include "nestlight/bench/harness.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/memory_store.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using namespace streaming;
using streaming::View;  // gi has a View too, and a unity build sees both directives

namespace {

double threadCpuMs() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double percentileOf(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<size_t>(std::ceil(p * double(v.size()))) - (p > 0 ? 1 : 0))];
}

// Cameras over the scan's bounds.
struct StreamScene {
  glm::dvec3 lo, hi, center;
  double diag;
  explicit StreamScene(const Metadata& m)
      : lo(m.bounds.min.x, m.bounds.min.y, m.bounds.min.z),
        hi(m.bounds.max.x, m.bounds.max.y, m.bounds.max.z),
        center(0.5 * (lo + hi)),
        diag(std::max(glm::length(hi - lo), 1e-3)) {}
  View look(const glm::dvec3& eye, const glm::dvec3& target) const {
    glm::dvec3 dir = glm::normalize(target - eye);
    const glm::dvec3 up = std::abs(dir.z) > 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
    return perspectiveView(eye, target, up, glm::radians(60.0), 1920, 1080,
                           std::max(1e-4 * diag, 0.01), 20 * diag);
  }
  // The whole scan in view, from `angle` around it.
  View overview(double angle) const {
    return look(center + glm::dvec3(std::cos(angle), std::sin(angle), 0.6) * diag, center);
  }
  // A random close view: the eye above the scan, looking at a point of it.
  View random(std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> u(0, 1);
    const glm::dvec3 target = lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dvec3 eye = target + glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, 0.2 + 0.3 * u(rng)) *
                                        diag * (0.1 + 0.4 * u(rng));
    return look(eye, target);
  }
};

void sleepRest(std::chrono::steady_clock::time_point frameStart, double frameMs) {
  const double used =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frameStart)
          .count();
  if (frameMs > used)
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(frameMs - used));
}

std::string mib(double bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", bytes / 1048576.0);
  return b;
}

// 1. Scheduler CPU time per frame with every node resident: unlimited budgets, the whole scan
//    in view and refined to its leaves, then camera paths whose cut keeps (or changes over)
//    that resident set. The store keeps sizes only: the time is the scheduler's.
void measureAllResident(OctreeReader& reader, const StreamScene& scene, const StreamBenchOptions& o,
                        nlohmann::json& results, std::FILE* log) {
  Budgets b;
  b.points = uint64_t(1) << 50;
  b.gpuBytes = uint64_t(1) << 50;
  b.uploadBytesPerFrame = uint64_t(1) << 50;
  b.spacingPixels = 0;
  MemoryStore store(reader.metadata(), false);
  Streamer s(reader, store, b);
  auto t = std::chrono::steady_clock::now();
  int loadFrames = 0;
  while (!s.update(scene.overview(0)).complete) {
    ++loadFrames;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const double loadSec =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  say(log, "  loaded every node: %u resident (%s) in %.1f s, %d frames\n", s.stats().residentNodes,
      mib(double(s.stats().residentBytes)).c_str(), loadSec, loadFrames);
  results["all_resident"] = {{"resident_nodes", s.stats().residentNodes},
                             {"resident_bytes", s.stats().residentBytes},
                             {"load_seconds", loadSec}};
  say(log, "  %-34s %9s %9s %10s %10s %10s\n", "camera path (every node resident)", "cut", "drawn",
      "cpu med", "cpu p99", "wall p99");
  struct Path {
    const char* name;
    double spacingPixels;
    std::function<View(int)> view;
  };
  std::mt19937_64 rng(o.seed);
  std::vector<View> randomViews;
  for (int i = 0; i < o.frames; ++i) randomViews.push_back(scene.random(rng));
  const std::vector<Path> paths = {
      {"orbit, whole scan, leaves", 0, [&](int f) { return scene.overview(f * 0.01); }},
      {"orbit, whole scan, 1 px", 1, [&](int f) { return scene.overview(f * 0.01); }},
      {"random close views, 1 px", 1, [&](int f) { return randomViews[size_t(f)]; }},
  };
  results["paths"] = nlohmann::json::array();
  for (const Path& p : paths) {
    b.spacingPixels = p.spacingPixels;
    s.setBudgets(b);
    std::vector<double> cpu, wall;
    uint64_t cut = 0, drawn = 0, resident = 0;
    for (int f = 0; f < o.frames; ++f) {
      const View v = p.view(f);
      const double c0 = threadCpuMs();
      const FrameStats& st = s.update(v);
      cpu.push_back(threadCpuMs() - c0);
      wall.push_back(st.msUpdate);
      cut += st.cutNodes, drawn += st.drawNodes, resident += st.residentNodes;
    }
    const double n = double(o.frames);
    say(log, "  %-34s %9.0f %9.0f %7.3f ms %7.3f ms %7.3f ms\n", p.name, double(cut) / n,
        double(drawn) / n, percentileOf(cpu, 0.5), percentileOf(cpu, 0.99),
        percentileOf(wall, 0.99));
    results["paths"].push_back({{"path", p.name},
                                {"frames", o.frames},
                                {"cut_nodes_mean", double(cut) / n},
                                {"draw_nodes_mean", double(drawn) / n},
                                {"resident_nodes_mean", double(resident) / n},
                                {"cpu_ms_median", percentileOf(cpu, 0.5)},
                                {"cpu_ms_p99", percentileOf(cpu, 0.99)},
                                {"cpu_ms_max", percentileOf(cpu, 1.0)},
                                {"wall_ms_median", percentileOf(wall, 0.5)},
                                {"wall_ms_p99", percentileOf(wall, 0.99)}});
  }
}

// 2. Time to full detail after a teleport to each view, frames paced at --frame-ms, one streamer
//    that goes from view to view: frames and milliseconds per view.
void teleportTimes(const fs::path& octree, const StreamScene& scene, const std::vector<View>& views,
                   MemoryStore& store, const StreamBenchOptions& o, std::vector<double>& tpFrames,
                   std::vector<double>& tpMs) {
  const Budgets b;             // the defaults a viewer starts with
  OctreeReader fresh(octree);  // hierarchy chunks are read as the views need them
  Streamer s(fresh, store, b);
  while (!s.update(scene.overview(0)).complete)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  for (const auto& v : views) {
    const auto t = std::chrono::steady_clock::now();
    int f = 0;
    for (;;) {
      const auto fs0 = std::chrono::steady_clock::now();
      ++f;
      if (s.update(v).complete) break;
      sleepRest(fs0, o.frameMs);
    }
    tpFrames.push_back(f);
    tpMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
  }
}

// 2. and 3. Time to full detail after a teleport, default budgets; bytes read for a converged
//    view from a cold start against the payload bytes of the nodes it draws (a ratio above 1:
//    reads that were cancelled late, discarded or evicted).
void measureTeleports(const fs::path& octree, OctreeReader& reader, const StreamScene& scene,
                      const StreamBenchOptions& o, nlohmann::json& results, std::FILE* log) {
  const Budgets b;  // the defaults a viewer starts with
  std::mt19937_64 rng(o.seed + 1);
  std::vector<View> views;
  for (int i = 0; i < o.teleports; ++i) views.push_back(scene.random(rng));
  MemoryStore store(reader.metadata(), false);
  std::vector<double> tpFrames, tpMs, ratio, coldMs;
  teleportTimes(octree, scene, views, store, o, tpFrames, tpMs);
  results["teleports"] = nlohmann::json::array();
  uint64_t sumRead = 0, sumNeeded = 0;
  uint64_t sumHierarchy = 0;
  for (const auto& v : views) {
    OctreeReader cold(octree);  // nothing below the root chunk read yet
    const uint64_t rootChunk = cold.hierarchyBytesRead();
    Streamer s(cold, store, b);
    const auto t = std::chrono::steady_clock::now();
    for (;;) {
      const auto fs0 = std::chrono::steady_clock::now();
      if (s.update(v).complete) break;
      sleepRest(fs0, o.frameMs);
    }
    coldMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
    uint64_t needed = 0;
    for (const auto& d : s.drawList()) needed += reader.node(d.key)->byteSize;
    const uint64_t read = s.totals().bytesRead;
    const uint64_t hierarchy = cold.hierarchyBytesRead() - rootChunk;
    ratio.push_back(needed ? double(read) / double(needed) : 0);
    sumRead += read, sumNeeded += needed, sumHierarchy += hierarchy;
    results["teleports"].push_back({{"cut_nodes", s.stats().cutNodes},
                                    {"cut_points", s.stats().cutPoints},
                                    {"bytes_read", read},
                                    {"hierarchy_bytes_read", hierarchy},
                                    {"payload_bytes_needed", needed},
                                    {"cold_ms", coldMs.back()}});
  }
  say(log, "  teleport to full detail (%d random views, default budgets, %.1f ms frames):\n",
      o.teleports, o.frameMs);
  say(log,
      "    frames median %.0f, max %.0f; time median %.0f ms, max %.0f ms; from a cold start "
      "median %.0f ms\n",
      percentileOf(tpFrames, 0.5), percentileOf(tpFrames, 1.0), percentileOf(tpMs, 0.5),
      percentileOf(tpMs, 1.0), percentileOf(coldMs, 0.5));
  say(log,
      "  cold start to a converged view, bytes read / payload bytes of the nodes it draws: "
      "median %.4f, "
      "max %.4f\n    (total %s read, %s of it hierarchy, for %s of payload)\n",
      percentileOf(ratio, 0.5), percentileOf(ratio, 1.0), mib(double(sumRead)).c_str(),
      mib(double(sumHierarchy)).c_str(), mib(double(sumNeeded)).c_str());
  results["teleport"] = {{"frame_ms", o.frameMs},
                         {"frames_median", percentileOf(tpFrames, 0.5)},
                         {"frames_max", percentileOf(tpFrames, 1.0)},
                         {"ms_median", percentileOf(tpMs, 0.5)},
                         {"ms_max", percentileOf(tpMs, 1.0)},
                         {"cold_ms_median", percentileOf(coldMs, 0.5)}};
  results["bytes_read_ratio"] = {{"median", percentileOf(ratio, 0.5)},
                                 {"max", percentileOf(ratio, 1.0)},
                                 {"bytes_read", sumRead},
                                 {"hierarchy_bytes_read", sumHierarchy},
                                 {"payload_bytes_needed", sumNeeded}};
}

}  // namespace

nlohmann::json runStreamBench(const fs::path& octree, const StreamBenchOptions& o, std::FILE* log) {
  OctreeReader reader(octree);
  const Metadata& m = reader.metadata();
  const StreamScene scene(m);
  nlohmann::json results = {{"device", o.device},
                            {"cores", std::thread::hardware_concurrency()},
                            {"octree", octree.string()},
                            {"points", m.points},
                            {"nodes", m.nodes}};
  say(log, "bench stream: %s (%llu points, %llu nodes), %s, %u cores\n", octree.c_str(),
      (unsigned long long)m.points, (unsigned long long)m.nodes, o.device.c_str(),
      std::thread::hardware_concurrency());
  measureAllResident(reader, scene, o, results, log);
  measureTeleports(octree, reader, scene, o, results, log);
  return results;
}

}  // namespace nestlight::bench
