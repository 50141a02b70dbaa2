// `nestlight bench convert`: conversion speed, peak memory, payload size per codec and the time
// to open an octree's root, on generated LAS files. Each conversion runs in a child process so
// that its peak RSS is its own. Prints a table and writes JSON.
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cli.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/converters/synthetic_octree.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty()
             ? 0
             : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

std::string cpuName() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

uint64_t writeSynthetic(const SyntheticSpec& spec, const std::string& path);

// Bytes of the files under `dir` (missing: 0).
static uint64_t folderBytes(const fs::path& dir) {
  uint64_t total = 0;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file(ec)) total += it->file_size(ec);
  return total;
}

ChildRun runChild(const std::vector<std::string>& args, const std::string& watch) {
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
  ChildRun r;
  // The converter builds WATCH beside it, in .WATCH.build-PID (octree/staged_directory.h), with its
  // temporary files in chunks.tmp there: sample their size while it runs.
  std::atomic<bool> done{false};
  std::thread watcher;
  if (!watch.empty())
    watcher = std::thread([&] {
      const fs::path w(watch);
      const fs::path tmp = w.parent_path() /
                           ("." + w.filename().string() + ".build-" + std::to_string(pid)) /
                           "chunks.tmp";
      while (!done.load()) {
        r.peakTempBytes = std::max(r.peakTempBytes, folderBytes(tmp));
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
      }
    });
  ::wait4(pid, &status, 0, &ru);
  // Timed before the watcher is joined: its sleep would add up to a quarter of a second.
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  done = true;
  if (watcher.joinable()) watcher.join();
  r.peakRss = static_cast<uint64_t>(ru.ru_maxrss) * 1024;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  return r;
}

void addBench(CLI::App& app, int& exitCode) {
  auto* bench = app.add_subcommand("bench", "Benchmarks: speed against size (and, later, error)");
  bench->require_subcommand(1);
  auto* cmd = bench->add_subcommand(
      "convert", "Conversion speed, peak RSS, bytes/point per codec, time to open the root");
  auto sizes = std::make_shared<std::vector<std::string>>(std::vector<std::string>{"20M", "100M"});
  auto codecs =
      std::make_shared<std::vector<std::string>>(std::vector<std::string>{"zstd", "raw", "draco"});
  auto runs = std::make_shared<int>(3);
  auto dir = std::make_shared<std::string>("bench-data");
  auto out = std::make_shared<std::string>("bench-convert.json");
  auto memory = std::make_shared<std::string>("1G");
  auto sampling = std::make_shared<std::string>("poisson");
  cmd->add_option("--sizes", *sizes, "Point counts of the generated LAS files")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--codecs", *codecs, "Codecs compared on the first size (one run each)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--runs", *runs, "Runs per size with zstd (the median is reported)")
      ->capture_default_str();
  cmd->add_option("--dir", *dir, "Folder for the generated scans and octrees (reused)")
      ->capture_default_str();
  cmd->add_option("--memory", *memory, "--memory passed to convert")->capture_default_str();
  cmd->add_option("--sampling", *sampling, "--sampling passed to convert")->capture_default_str();
  cmd->add_option("--json", *out, "Where to write the results")->capture_default_str();
  cmd->callback([=, &exitCode]() {
    fs::create_directories(*dir);
    nlohmann::json results = {{"device", cpuName()},
                              {"cores", std::thread::hardware_concurrency()},
                              {"memory", *memory},
                              {"sampling", *sampling},
                              {"sizes", nlohmann::json::array()}};
    std::printf("%-8s %-6s %10s %12s %10s %10s %12s %10s\n", "points", "codec", "seconds",
                "points/s", "peak RSS", "bytes/pt", "open root", "temp disk");
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
      if (std::find(codecList.begin(), codecList.end(), "zstd") == codecList.end())
        codecList.insert(codecList.begin(), "zstd");
      for (const auto& codec : codecList) {
        const std::string octree =
            (fs::path(*dir) / ("synthetic_" + sz + "_" + codec + ".octree")).string();
        const int nruns = codec == "zstd" ? *runs : 1;
        std::vector<double> secs, rss, temp;
        for (int r = 0; r < nruns; ++r) {
          ChildRun c =
              runChild({"nestlight", "convert", las, "-o", octree, "--overwrite", "--progress",
                        "quiet", "--codec", codec, "--memory", *memory, "--sampling", *sampling},
                       octree);
          if (c.status != 0)
            throw Error(
                las, "",
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
        std::printf("%-8s %-6s %10.2f %12s %10s %10.2f %9.2f ms %10s\n", sz.c_str(), codec.c_str(),
                    s, humanCount(n / s).c_str(), humanBytes(median(rss)).c_str(), bpp,
                    median(open), humanBytes(median(temp)).c_str());
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
    std::ofstream(*out) << results.dump(2) << "\n";
    std::printf("results written to %s\n", out->c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
