// `nestlight bench convert`: conversion speed, peak memory, payload size per codec and the time
// to open an octree's root, on generated LAS files. Each conversion runs in a child process so
// that its peak RSS is its own. Prints a table and writes JSON.
// `nestlight bench stream`: the streaming scheduler's CPU time per frame with every node of a
// large octree resident, the time to full detail after a teleport, and the bytes a converged view
// read against the bytes its nodes hold.
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cli.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/memory_store.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

std::string cpuName() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

uint64_t writeSynthetic(const SyntheticSpec& spec, const std::string& path);

namespace {

struct ChildRun {
  double seconds = 0;
  uint64_t peakRss = 0;
  int status = 0;
};

ChildRun runChild(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  auto t = std::chrono::steady_clock::now();
  pid_t pid = ::fork();
  if (pid == 0) {
    if (FILE* devnull = std::fopen("/dev/null", "w")) ::dup2(::fileno(devnull), 1);
    ::execv("/proc/self/exe", argv.data());
    ::_exit(127);
  }
  int status = 0;
  struct rusage ru {};
  ::wait4(pid, &status, 0, &ru);
  ChildRun r;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  r.peakRss = static_cast<uint64_t>(ru.ru_maxrss) * 1024;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  return r;
}


double threadCpuMs() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

double percentileOf(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(std::ceil(p * double(v.size()))) - (p > 0 ? 1 : 0))];
}

// Cameras over the scan's bounds for `bench stream`.
struct SceneFrame {
  glm::dvec3 lo, hi, center;
  double diag;
  explicit SceneFrame(const Metadata& m)
      : lo(m.bounds.min.x, m.bounds.min.y, m.bounds.min.z),
        hi(m.bounds.max.x, m.bounds.max.y, m.bounds.max.z),
        center(0.5 * (lo + hi)),
        diag(std::max(glm::length(hi - lo), 1e-3)) {}
  streaming::View look(const glm::dvec3& eye, const glm::dvec3& target) const {
    glm::dvec3 dir = glm::normalize(target - eye);
    const glm::dvec3 up = std::abs(dir.z) > 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
    return streaming::perspectiveView(eye, target, up, glm::radians(60.0), 1920, 1080,
                                      std::max(1e-4 * diag, 0.01), 20 * diag);
  }
  // The whole scan in view, from `angle` around it.
  streaming::View overview(double angle) const {
    return look(center + glm::dvec3(std::cos(angle), std::sin(angle), 0.6) * diag, center);
  }
  // A random close view: the eye above the scan, looking at a point of it.
  streaming::View random(std::mt19937_64& rng) const {
    std::uniform_real_distribution<double> u(0, 1);
    const glm::dvec3 target = lo + (hi - lo) * glm::dvec3(u(rng), u(rng), u(rng));
    const glm::dvec3 eye = target + glm::dvec3(u(rng) - 0.5, u(rng) - 0.5, 0.2 + 0.3 * u(rng)) * diag * (0.1 + 0.4 * u(rng));
    return look(eye, target);
  }
};

void sleepRest(std::chrono::steady_clock::time_point frameStart, double frameMs) {
  const double used = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frameStart).count();
  if (frameMs > used) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(frameMs - used));
}

void addBenchStream(CLI::App* bench, int& exitCode) {
  auto* cmd = bench->add_subcommand(
      "stream", "Streaming scheduler: CPU time per frame with every node resident, time to full detail after\n"
                "a teleport, bytes read per converged view against the bytes its nodes hold");
  auto dir = std::make_shared<std::string>();
  auto generate = std::make_shared<std::string>();
  auto work = std::make_shared<std::string>("bench-data");
  auto frames = std::make_shared<int>(600);
  auto teleports = std::make_shared<int>(10);
  auto frameMs = std::make_shared<double>(1000.0 / 60);
  auto out = std::make_shared<std::string>("bench-stream.json");
  auto seed = std::make_shared<uint64_t>(7);
  cmd->add_option("octree", *dir, "Octree folder (or --generate)");
  cmd->add_option("--generate", *generate, "Generate and convert a synthetic scan of this many points (e.g. 100M)");
  cmd->add_option("--dir", *work, "Folder for --generate (reused when it holds that octree)")->capture_default_str();
  cmd->add_option("--frames", *frames, "Frames timed per camera path with every node resident")->capture_default_str();
  cmd->add_option("--teleports", *teleports, "Random views for the teleport and bytes-read measures")->capture_default_str();
  cmd->add_option("--frame-ms", *frameMs, "Frame period while waiting for full detail")->capture_default_str();
  cmd->add_option("--seed", *seed, "Seed of the random views")->capture_default_str();
  cmd->add_option("--json", *out, "Where to write the results")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    if (dir->empty() == generate->empty()) throw Error("", "", "give an octree folder or --generate N (one of them)");
    fs::path octree = *dir;
    if (!generate->empty()) {
      const uint64_t n = parseCount(*generate, "--generate");
      octree = ensureSyntheticOctree(n, fs::path(*work) / ("stream_" + *generate + ".octree"));
    }
    OctreeReader reader(octree);
    const Metadata& m = reader.metadata();
    const SceneFrame scene(m);
    nlohmann::json results = {{"device", cpuName()}, {"cores", std::thread::hardware_concurrency()},
                              {"octree", octree.string()}, {"points", m.points}, {"nodes", m.nodes}};
    std::printf("bench stream: %s (%s points, %llu nodes), %s, %u cores\n", octree.c_str(),
                humanCount(double(m.points)).c_str(), (unsigned long long)m.nodes, cpuName().c_str(),
                std::thread::hardware_concurrency());

    // 1. Scheduler CPU time per frame with every node resident: unlimited budgets, the whole scan
    //    in view and refined to its leaves, then camera paths whose cut keeps (or changes over)
    //    that resident set. The store keeps sizes only: the time is the scheduler's.
    {
      streaming::Budgets b;
      b.points = uint64_t(1) << 50;
      b.gpuBytes = uint64_t(1) << 50;
      b.uploadBytesPerFrame = uint64_t(1) << 50;
      b.spacingPixels = 0;
      streaming::MemoryStore store(m, false);
      streaming::Streamer s(reader, store, b);
      auto t = std::chrono::steady_clock::now();
      int loadFrames = 0;
      while (!s.update(scene.overview(0)).complete) {
        ++loadFrames;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      }
      const double loadSec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
      std::printf("  loaded every node: %u resident (%s) in %.1f s, %d frames\n", s.stats().residentNodes,
                  humanBytes(double(s.stats().residentBytes)).c_str(), loadSec, loadFrames);
      results["all_resident"] = {{"resident_nodes", s.stats().residentNodes}, {"resident_bytes", s.stats().residentBytes},
                                 {"load_seconds", loadSec}};
      std::printf("  %-34s %9s %9s %10s %10s %10s\n", "camera path (every node resident)", "cut", "drawn",
                  "cpu med", "cpu p99", "wall p99");
      struct Path {
        const char* name;
        double spacingPixels;
        std::function<streaming::View(int)> view;
      };
      std::mt19937_64 rng(*seed);
      std::vector<streaming::View> randomViews;
      for (int i = 0; i < *frames; ++i) randomViews.push_back(scene.random(rng));
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
        for (int f = 0; f < *frames; ++f) {
          const streaming::View v = p.view(f);
          const double c0 = threadCpuMs();
          const streaming::FrameStats& st = s.update(v);
          cpu.push_back(threadCpuMs() - c0);
          wall.push_back(st.msUpdate);
          cut += st.cutNodes, drawn += st.drawNodes, resident += st.residentNodes;
        }
        const double n = double(*frames);
        std::printf("  %-34s %9.0f %9.0f %7.3f ms %7.3f ms %7.3f ms\n", p.name, double(cut) / n,
                    double(drawn) / n, percentileOf(cpu, 0.5), percentileOf(cpu, 0.99), percentileOf(wall, 0.99));
        results["paths"].push_back({{"path", p.name}, {"frames", *frames}, {"cut_nodes_mean", double(cut) / n},
                                    {"draw_nodes_mean", double(drawn) / n}, {"resident_nodes_mean", double(resident) / n},
                                    {"cpu_ms_median", percentileOf(cpu, 0.5)}, {"cpu_ms_p99", percentileOf(cpu, 0.99)},
                                    {"cpu_ms_max", percentileOf(cpu, 1.0)}, {"wall_ms_median", percentileOf(wall, 0.5)},
                                    {"wall_ms_p99", percentileOf(wall, 0.99)}});
      }
    }

    // 2. Time to full detail after a teleport, default budgets, frames paced at --frame-ms.
    // 3. Bytes read for a converged view from a cold start against the payload bytes of the
    //    nodes it draws (a ratio above 1: reads that were cancelled late, discarded or evicted).
    {
      const streaming::Budgets b;  // the defaults a viewer starts with
      std::mt19937_64 rng(*seed + 1);
      std::vector<streaming::View> views;
      for (int i = 0; i < *teleports; ++i) views.push_back(scene.random(rng));
      streaming::MemoryStore store(m, false);
      std::vector<double> tpFrames, tpMs, ratio, coldMs;
      {
        OctreeReader fresh(octree);  // hierarchy chunks are read as the views need them
        streaming::Streamer s(fresh, store, b);
        while (!s.update(scene.overview(0)).complete) std::this_thread::sleep_for(std::chrono::milliseconds(2));
        for (const auto& v : views) {
          const auto t = std::chrono::steady_clock::now();
          int f = 0;
          for (;;) {
            const auto fs0 = std::chrono::steady_clock::now();
            ++f;
            if (s.update(v).complete) break;
            sleepRest(fs0, *frameMs);
          }
          tpFrames.push_back(f);
          tpMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
        }
      }
      results["teleports"] = nlohmann::json::array();
      uint64_t sumRead = 0, sumNeeded = 0;
      uint64_t sumHierarchy = 0;
      for (const auto& v : views) {
        OctreeReader cold(octree);  // nothing below the root chunk read yet
        const uint64_t rootChunk = cold.hierarchyBytesRead();
        streaming::Streamer s(cold, store, b);
        const auto t = std::chrono::steady_clock::now();
        for (;;) {
          const auto fs0 = std::chrono::steady_clock::now();
          if (s.update(v).complete) break;
          sleepRest(fs0, *frameMs);
        }
        coldMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
        uint64_t needed = 0;
        for (const auto& d : s.drawList()) needed += reader.node(d.key)->byteSize;
        const uint64_t read = s.totals().bytesRead;
        const uint64_t hierarchy = cold.hierarchyBytesRead() - rootChunk;
        ratio.push_back(needed ? double(read) / double(needed) : 0);
        sumRead += read, sumNeeded += needed, sumHierarchy += hierarchy;
        results["teleports"].push_back({{"cut_nodes", s.stats().cutNodes}, {"cut_points", s.stats().cutPoints},
                                        {"bytes_read", read}, {"hierarchy_bytes_read", hierarchy},
                                        {"payload_bytes_needed", needed},
                                        {"cold_ms", coldMs.back()}});
      }
      std::printf("  teleport to full detail (%d random views, default budgets, %.1f ms frames):\n", *teleports, *frameMs);
      std::printf("    frames median %.0f, max %.0f; time median %.0f ms, max %.0f ms; from a cold start median %.0f ms\n",
                  percentileOf(tpFrames, 0.5), percentileOf(tpFrames, 1.0), percentileOf(tpMs, 0.5),
                  percentileOf(tpMs, 1.0), percentileOf(coldMs, 0.5));
      std::printf("  cold start to a converged view, bytes read / payload bytes of the nodes it draws: median %.4f, "
                  "max %.4f\n    (total %s read, %s of it hierarchy, for %s of payload)\n",
                  percentileOf(ratio, 0.5), percentileOf(ratio, 1.0), humanBytes(double(sumRead)).c_str(),
                  humanBytes(double(sumHierarchy)).c_str(), humanBytes(double(sumNeeded)).c_str());
      results["teleport"] = {{"frame_ms", *frameMs}, {"frames_median", percentileOf(tpFrames, 0.5)},
                             {"frames_max", percentileOf(tpFrames, 1.0)}, {"ms_median", percentileOf(tpMs, 0.5)},
                             {"ms_max", percentileOf(tpMs, 1.0)}, {"cold_ms_median", percentileOf(coldMs, 0.5)}};
      results["bytes_read_ratio"] = {{"median", percentileOf(ratio, 0.5)}, {"max", percentileOf(ratio, 1.0)},
                                     {"bytes_read", sumRead}, {"hierarchy_bytes_read", sumHierarchy},
                                     {"payload_bytes_needed", sumNeeded}};
    }
    std::ofstream(*out) << results.dump(2) << "\n";
    std::printf("results written to %s\n", out->c_str());
    exitCode = 0;
  });
}

}  // namespace

void addBench(CLI::App& app, int& exitCode) {
  auto* bench = app.add_subcommand("bench", "Benchmarks: speed against size (and, later, error)");
  bench->require_subcommand(1);
  auto* cmd = bench->add_subcommand("convert", "Conversion speed, peak RSS, bytes/point per codec, time to open the root");
  auto sizes = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"20M", "100M"});
  auto codecs = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"zstd", "raw", "draco"});
  auto runs = std::make_shared<int>(3);
  auto dir = std::make_shared<std::string>("bench-data");
  auto out = std::make_shared<std::string>("bench-convert.json");
  auto memory = std::make_shared<std::string>("1G");
  auto sampling = std::make_shared<std::string>("poisson");
  cmd->add_option("--sizes", *sizes, "Point counts of the generated LAS files")->delimiter(',')->capture_default_str();
  cmd->add_option("--codecs", *codecs, "Codecs compared on the first size (one run each)")->delimiter(',')->capture_default_str();
  cmd->add_option("--runs", *runs, "Runs per size with zstd (the median is reported)")->capture_default_str();
  cmd->add_option("--dir", *dir, "Folder for the generated scans and octrees (reused)")->capture_default_str();
  cmd->add_option("--memory", *memory, "--memory passed to convert")->capture_default_str();
  cmd->add_option("--sampling", *sampling, "--sampling passed to convert")->capture_default_str();
  cmd->add_option("--json", *out, "Where to write the results")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    fs::create_directories(*dir);
    nlohmann::json results = {{"device", cpuName()}, {"cores", std::thread::hardware_concurrency()},
                              {"memory", *memory}, {"sampling", *sampling}, {"sizes", nlohmann::json::array()}};
    std::printf("%-8s %-6s %10s %12s %10s %10s %12s\n", "points", "codec", "seconds", "points/s", "peak RSS",
                "bytes/pt", "open root");
    bool first = true;
    for (const auto& sz : *sizes) {
      const uint64_t n = parseCount(sz, "--sizes");
      const std::string las = (fs::path(*dir) / ("synthetic_" + sz + ".las")).string();
      if (!fs::exists(las)) {
        SyntheticSpec spec;
        spec.points = n;
        spec.seed = 42;
        spec.intensity = false;  // xyz + rgb, the case the bytes-per-point target speaks of
        std::fprintf(stderr, "bench: generating %s\n", las.c_str());
        writeSynthetic(spec, las);
      }
      std::vector<std::string> codecList = first ? *codecs : std::vector<std::string>{"zstd"};
      if (std::find(codecList.begin(), codecList.end(), "zstd") == codecList.end()) codecList.insert(codecList.begin(), "zstd");
      for (const auto& codec : codecList) {
        const std::string octree = (fs::path(*dir) / ("synthetic_" + sz + "_" + codec + ".octree")).string();
        const int nruns = codec == "zstd" ? *runs : 1;
        std::vector<double> secs, rss;
        for (int r = 0; r < nruns; ++r) {
          ChildRun c = runChild({"nestlight", "convert", las, "-o", octree, "--overwrite", "--progress", "quiet",
                                 "--codec", codec, "--memory", *memory, "--sampling", *sampling});
          if (c.status != 0) throw Error(las, "", "conversion failed in the benchmark (exit " + std::to_string(c.status) + ")");
          secs.push_back(c.seconds);
          rss.push_back(double(c.peakRss));
        }
        // Time to open: metadata, root hierarchy chunk and root payload, warm cache, median of 9.
        std::vector<double> open;
        uint64_t hierarchyRead = 0;
        for (int k = 0; k < 9; ++k) {
          auto t = std::chrono::steady_clock::now();
          OctreeReader reader(octree);
          PointBuffer root = reader.readNode(NodeKey::root());
          open.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count());
          hierarchyRead = reader.hierarchyBytesRead();
        }
        OctreeReader reader(octree);
        const Metadata& m = reader.metadata();
        const double s = median(secs), bpp = m.points ? double(m.payloadBytes) / m.points : 0;
        std::printf("%-8s %-6s %10.2f %12s %10s %10.2f %9.2f ms\n", sz.c_str(), codec.c_str(), s,
                    humanCount(n / s).c_str(), humanBytes(median(rss)).c_str(), bpp, median(open));
        std::fflush(stdout);
        results["sizes"].push_back({{"points", n}, {"codec", codec}, {"runs", nruns}, {"seconds_median", s},
                                    {"seconds", secs}, {"points_per_second", n / s},
                                    {"peak_rss_bytes_median", median(rss)}, {"payload_bytes", m.payloadBytes},
                                    {"bytes_per_point", bpp}, {"nodes", m.nodes},
                                    {"open_root_ms_median", median(open)}, {"hierarchy_bytes_read_on_open", hierarchyRead}});
      }
      first = false;
    }
    std::ofstream(*out) << results.dump(2) << "\n";
    std::printf("results written to %s\n", out->c_str());
    exitCode = 0;
  });
  addBenchStream(bench, exitCode);
}

}  // namespace nestlight::cli
