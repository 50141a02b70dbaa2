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
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::bench {

namespace fs = std::filesystem;

void runBenchConvert(const BenchConvertOptions& o) {
  fs::create_directories(o.dir);
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
