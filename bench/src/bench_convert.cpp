// `nestlight bench convert`: conversion speed, peak memory, payload size per codec and the time
// to open an octree's root, on generated LAS files. Each conversion runs in a child process so
// that its peak RSS is its own. Prints a table and writes JSON.
#include "nestlight/bench/bench_convert.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::bench {

namespace fs = std::filesystem;

namespace {

// The job's scaling: the same tiles converted by one process and by N ranks under mpirun.
void runBenchConvertMpi(const BenchConvertOptions& o) {
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0)
    throw Error(
        "bench convert --mpi: mpirun is not installed (scripts/setup.sh installs Open MPI)");
  // Root may run the job (servers and CI containers run as root); ranks may outnumber the cores.
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  // --bind-to none: Open MPI binds each of one or two ranks to one core by default, which would
  // run a rank's threads on that core alone.
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  nlohmann::json results = {{"device", cpuName()},
                            {"cores", cores},
                            {"memory_per_rank", o.memory},
                            {"sampling", o.sampling},
                            {"runs", nlohmann::json::array()}};
  std::printf("%-8s %-6s %8s %10s %12s %8s %12s %12s  %s\n", "points", "ranks", "threads",
              "seconds", "points/s", "speedup", "sent B/pt", "max rank RSS",
              "phases (slowest rank)");
  for (const auto& [sz, n] : o.sizes) {
    // An archive of 8 tiles side by side, as national LiDAR archives come: the unit ranks are
    // dealt.
    std::vector<std::string> tiles;
    for (int k = 0; k < 8; ++k) {
      const std::string las =
          (fs::path(o.dir) / ("tiles_" + sz + "_" + std::to_string(k) + ".las")).string();
      if (!fs::exists(las)) {
        SyntheticSpec spec;
        spec.points = n / 8 + (uint64_t(k) < n % 8 ? 1 : 0);
        spec.seed = 42 + uint64_t(k);
        spec.origin = {100.0 * k, 0, 0};
        spec.intensity = false;
        std::fprintf(stderr, "bench: generating %s\n", las.c_str());
        writeSynthetic(spec, las);
      }
      tiles.push_back(las);
    }
    double single = 0;
    std::vector<int> counts{0};  // 0: one process without MPI, the baseline
    counts.insert(counts.end(), o.mpiRanks.begin(), o.mpiRanks.end());
    for (int ranks : counts) {
      const unsigned threads = std::max(1u, cores / unsigned(std::max(ranks, 1)));
      const std::string octree =
          (fs::path(o.dir) / ("tiles_" + sz + "_mpi" + std::to_string(ranks) + ".octree")).string();
      const std::string report = octree + ".report.json";
      std::string cmd =
          (ranks ? "mpirun --oversubscribe --bind-to none -n " + std::to_string(ranks) + " " : "") +
          self + " convert";
      for (const auto& t : tiles) cmd += " " + t;
      cmd += " -o " + octree + " --overwrite --progress quiet --memory " + o.memory +
             " --sampling " + o.sampling + " --threads " + std::to_string(threads) + " --report " +
             report + (ranks ? " --mpi" : "") + " > " + octree + ".log 2>&1";
      std::vector<double> secs;
      nlohmann::json rep;
      for (int r = 0; r < o.runs; ++r) {
        const auto t = std::chrono::steady_clock::now();
        if (std::system(cmd.c_str()) != 0)
          throw Error(octree + ".log", "", "the conversion failed in the benchmark: " + cmd);
        secs.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count());
        std::ifstream in(report);
        rep = nlohmann::json::parse(in);
      }
      const double s = median(secs);
      if (ranks == 0) single = s;
      uint64_t sent = 0, maxRss = rep.value("peak_rss_bytes", uint64_t(0));
      std::map<std::string, double> slowest;
      for (const auto& k : rep["ranks"]) {
        sent += k["bytes_sent"].get<uint64_t>();
        maxRss = std::max(maxRss, k["peak_rss_bytes"].get<uint64_t>());
        for (const auto& [phase, t] : k["phases"].items())
          slowest[phase] = std::max(slowest[phase], t.get<double>());
      }
      if (rep["ranks"].empty())
        for (const auto& [phase, t] : rep["phases"].items()) slowest[phase] = t.get<double>();
      std::string phases;
      for (const auto& [phase, t] : slowest) {
        char b[64];
        std::snprintf(b, sizeof b, "%s%s %.2f", phases.empty() ? "" : ", ", phase.c_str(), t);
        phases += b;
      }
      std::printf("%-8s %-6s %8u %10.2f %12s %8.2f %12.2f %12s  %s\n", sz.c_str(),
                  ranks ? std::to_string(ranks).c_str() : "1 (no MPI)", threads, s,
                  humanCount(double(n) / s).c_str(), single / s, double(sent) / double(n),
                  humanBytes(double(maxRss)).c_str(), phases.c_str());
      std::fflush(stdout);
      results["runs"].push_back({{"points", n},
                                 {"ranks", ranks},
                                 {"mpi", ranks > 0},
                                 {"threads_per_rank", threads},
                                 {"seconds_median", s},
                                 {"seconds", secs},
                                 {"points_per_second", double(n) / s},
                                 {"speedup", single / s},
                                 {"bytes_sent", sent},
                                 {"bytes_sent_per_point", double(sent) / double(n)},
                                 {"max_rank_peak_rss_bytes", maxRss},
                                 {"slowest_rank_phases", slowest},
                                 {"report", rep}});
    }
  }
  std::ofstream(o.out) << results.dump(2) << "\n";
  std::printf("results written to %s\n", o.out.c_str());
}

}  // namespace

void runBenchConvert(const BenchConvertOptions& o) {
  fs::create_directories(o.dir);
  if (!o.mpiRanks.empty()) return runBenchConvertMpi(o);
  nlohmann::json results = {{"device", cpuName()},
                            {"cores", std::thread::hardware_concurrency()},
                            {"memory", o.memory},
                            {"sampling", o.sampling},
                            {"sizes", nlohmann::json::array()}};
  std::printf("%-8s %-6s %10s %12s %10s %10s %12s %10s\n", "points", "codec", "seconds", "points/s",
              "peak RSS", "bytes/pt", "open root", "temp disk");
  bool first = true;
  for (const auto& [sz, n] : o.sizes) {
    const std::string las = (fs::path(o.dir) / ("synthetic_" + sz + ".las")).string();
    if (!fs::exists(las)) {
      SyntheticSpec spec;
      spec.points = n;
      spec.seed = 42;
      spec.intensity = false;  // xyz + rgb, the case the bytes-per-point target speaks of
      std::fprintf(stderr, "bench: generating %s\n", las.c_str());
      writeSynthetic(spec, las);
    }
    std::vector<std::string> codecList = first ? o.codecs : std::vector<std::string>{"zstd"};
    if (std::find(codecList.begin(), codecList.end(), "zstd") == codecList.end())
      codecList.insert(codecList.begin(), "zstd");
    for (const auto& codec : codecList) {
      const std::string octree =
          (fs::path(o.dir) / ("synthetic_" + sz + "_" + codec + ".octree")).string();
      const int nruns = codec == "zstd" ? o.runs : 1;
      std::vector<double> secs, rss, temp;
      for (int r = 0; r < nruns; ++r) {
        ChildRun c =
            runChild({"nestlight", "convert", las, "-o", octree, "--overwrite", "--progress",
                      "quiet", "--codec", codec, "--memory", o.memory, "--sampling", o.sampling},
                     octree);
        if (c.status != 0)
          throw Error(las, "",
                      "conversion failed in the benchmark (exit " + std::to_string(c.status) + ")");
        secs.push_back(c.seconds);
        rss.push_back(double(c.peakRss));
        temp.push_back(double(c.peakTempBytes));
      }
      // Time to open: metadata, root hierarchy chunk and root payload, warm cache, median of 9.
      std::vector<double> open;
      uint64_t hierarchyRead = 0;
      for (int k = 0; k < 9; ++k) {
        auto t = std::chrono::steady_clock::now();
        OctreeReader reader(octree);
        PointBuffer root = reader.readNode(NodeKey::root());
        open.push_back(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t)
                .count());
        hierarchyRead = reader.hierarchyBytesRead();
      }
      OctreeReader reader(octree);
      const Metadata& m = reader.metadata();
      const double s = median(secs), bpp = m.points ? double(m.payloadBytes) / m.points : 0;
      std::printf("%-8s %-6s %10.2f %12s %10s %10.2f %9.2f ms %10s\n", sz.c_str(), codec.c_str(), s,
                  humanCount(n / s).c_str(), humanBytes(median(rss)).c_str(), bpp, median(open),
                  humanBytes(median(temp)).c_str());
      std::fflush(stdout);
      results["sizes"].push_back({{"points", n},
                                  {"codec", codec},
                                  {"runs", nruns},
                                  {"seconds_median", s},
                                  {"seconds", secs},
                                  {"points_per_second", n / s},
                                  {"peak_rss_bytes_median", median(rss)},
                                  {"payload_bytes", m.payloadBytes},
                                  {"peak_temp_bytes_median", median(temp)},
                                  {"input_bytes", fs::file_size(las)},
                                  {"bytes_per_point", bpp},
                                  {"nodes", m.nodes},
                                  {"open_root_ms_median", median(open)},
                                  {"hierarchy_bytes_read_on_open", hierarchyRead}});
    }
    first = false;
  }
  std::ofstream(o.out) << results.dump(2) << "\n";
  std::printf("results written to %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
