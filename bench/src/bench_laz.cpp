// `nestlight bench laz`: LAZ decoding speed on one core and on all cores (points/s and MB/s of
// compressed input), for given LAZ files and a generated one, and conversion speed from LAZ
// against the same points from LAS (each conversion in a child process, median of runs).
#include "nestlight/bench/bench_laz.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/converters/reader.h"
#include "nestlight/converters/synthetic.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;

namespace {

struct Decode {
  double pointsPerSecond = 0, bytesPerSecond = 0;
  uint64_t points = 0;
};

// Decodes the whole file again and again for at least `minSeconds`, `runs` times; the median
// run's rate. The file is mapped once (warm page cache): this measures decoding, not the disk.
Decode decodeRate(const std::string& path, unsigned threads, int runs, double minSeconds) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  auto src = mapFile(path);
  std::vector<double> rates;
  uint64_t perPass = 0;
  for (int r = 0; r < runs; ++r) {
    const auto t = std::chrono::steady_clock::now();
    uint64_t n = 0, passes = 0;
    double s = 0;
    do {
      readLasRecords(src, {}, [&](const uint8_t*, size_t k, size_t) { n += k; });
      ++passes;
      s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    } while (s < minSeconds);
    rates.push_back(double(n) / s);
    perPass = n / passes;
  }
  Decode d;
  d.pointsPerSecond = median(rates);
  d.points = perPass;
  d.bytesPerSecond = perPass ? d.pointsPerSecond * double(src->size()) / double(perPass) : 0;
  return d;
}

// The generated scan again as LAS 1.4 point format 7 and its LAZ, so that the layered compressor
// of formats 6-10 is measured too. The same points gain the GPS time of a 100 kHz scanner and two
// scanner channels in turns of 100,000 points (as two heads of a mobile scanner), and a 16-bit
// scan angle in place of the 8-bit rank; the LAS writer then chooses format 7 for both files
// (one pass, two writers).
void writeFormat7(const std::string& from, const std::string& las7, const std::string& laz7) {
  auto r = openReader(from);
  const PointLayout& in = r->header().layout;
  SourceHeader h = r->header();
  h.layout = PointLayout();
  std::vector<std::pair<size_t, size_t>> copied;  // (offset in, offset out) of kept attributes
  for (size_t i = 0; i < in.size(); ++i)
    if (in[i].name != "scan_angle_rank") copied.emplace_back(i, h.layout.add(in[i]));
  const int rank = in.find("scan_angle_rank");
  const size_t angle = h.layout.add({"scan_angle", ScalarType::I16, 1, ""});
  const size_t channel = h.layout.add({"scanner_channel", ScalarType::U8, 1, ""});
  const size_t time = h.layout.add({"gps_time", ScalarType::F64, 1, ""});
  auto las = createWriter(las7, h), laz = createWriter(laz7, h);
  PointBatch b, out;
  uint64_t index = 0;
  const size_t sIn = in.stride(), sOut = h.layout.stride();
  while (r->read(b, 1 << 20)) {
    const size_t n = b.size();
    out.xyz = b.xyz;
    out.attrs.assign(n * sOut, 0);
    for (size_t p = 0; p < n; ++p, ++index) {
      const uint8_t* src = b.attrs.data() + p * sIn;
      uint8_t* dst = out.attrs.data() + p * sOut;
      for (const auto& [i, o] : copied)
        std::memcpy(dst + h.layout.offset(o), src + in.offset(i), in[i].byteSize());
      const double degrees = rank >= 0 ? loadAsDouble(ScalarType::I8, src + in.offset(rank)) : 0;
      storeFromDouble(ScalarType::I16, degrees / 0.006, dst + h.layout.offset(angle));
      dst[h.layout.offset(channel)] = uint8_t((index / 100000) % 2);
      const double t = 1e5 + double(index) * 1e-5;
      std::memcpy(dst + h.layout.offset(time), &t, sizeof t);
    }
    las->write(out);
    laz->write(out);
  }
  las->close();
  laz->close();
}

// Decoding speed of each file on one core and on `cores`: the table's rows and results["decode"].
void measureDecoding(const BenchLazOptions& o, const std::vector<std::string>& decodeFiles,
                     unsigned cores, nlohmann::json& results) {
  std::printf("%-40s %10s %10s %14s %14s %12s\n", "LAZ file", "points", "bytes/pt", "1 core pts/s",
              std::to_string(cores).append(" cores pts/s").c_str(), "MB/s (all)");
  for (const std::string& f : decodeFiles) {
    const Decode one = decodeRate(f, 1, o.runs, 1.0);
    const Decode all = decodeRate(f, cores, o.runs, 1.0);
    const double bpp = one.points ? double(fs::file_size(f)) / double(one.points) : 0;
    std::printf("%-40s %10s %10.2f %14s %14s %12.1f\n", fs::path(f).filename().c_str(),
                humanCount(double(one.points)).c_str(), bpp,
                humanCount(one.pointsPerSecond).c_str(), humanCount(all.pointsPerSecond).c_str(),
                all.bytesPerSecond / 1e6);
    std::fflush(stdout);
    results["decode"].push_back({{"file", f},
                                 {"points", one.points},
                                 {"bytes_per_point", bpp},
                                 {"points_per_second_1_core", one.pointsPerSecond},
                                 {"points_per_second_all_cores", all.pointsPerSecond},
                                 {"bytes_per_second_all_cores", all.bytesPerSecond}});
  }
}

// Conversion of the same points from LAS and from LAZ: format 2 (LASzip's pointwise compressor)
// and format 7 (the layered one), each conversion a child `nestlight convert`.
void measureConversions(const BenchLazOptions& o, const std::string& las, const std::string& laz,
                        const std::string& las7, const std::string& laz7, nlohmann::json& results) {
  const uint64_t n = o.points;
  std::printf("\n%-12s %10s %12s %10s %10s\n", "input", "seconds", "points/s", "peak RSS", "input");
  struct Pair {
    const char *name, *las, *laz, *key;
    std::string lasPath, lazPath;
  };
  const Pair pairs[2] = {
      {"format 2", "convert_las", "convert_laz", "laz_over_las", las, laz},
      {"format 7", "convert_las14", "convert_laz14", "laz14_over_las14", las7, laz7}};
  for (const Pair& pair : pairs) {
    double rate[2] = {0, 0};
    const std::string inputs[2] = {pair.lasPath, pair.lazPath};
    for (int k = 0; k < 2; ++k) {
      const std::string octree = fs::path(inputs[k]).replace_extension("").string() +
                                 (k ? "_from_laz" : "_from_las") + ".octree";
      std::vector<double> secs, rss;
      for (int r = 0; r < o.runs; ++r) {
        ChildRun c = runChild({"nestlight", "convert", inputs[k], "-o", octree, "--overwrite",
                               "--progress", "quiet", "--memory", o.memory});
        if (c.status != 0)
          throw Error(inputs[k], "",
                      "conversion failed in the benchmark (exit " + std::to_string(c.status) + ")");
        secs.push_back(c.seconds);
        rss.push_back(double(c.peakRss));
      }
      const double sec = median(secs);
      rate[k] = double(n) / sec;
      std::printf("%-12s %10.2f %12s %10s %10s\n",
                  (std::string(k ? "LAZ " : "LAS ") + pair.name).c_str(), sec,
                  humanCount(rate[k]).c_str(), humanBytes(median(rss)).c_str(),
                  humanBytes(double(fs::file_size(inputs[k]))).c_str());
      std::fflush(stdout);
      results[k ? pair.laz : pair.las] = {{"points", n},
                                          {"runs", o.runs},
                                          {"seconds", secs},
                                          {"seconds_median", sec},
                                          {"points_per_second", rate[k]},
                                          {"peak_rss_bytes_median", median(rss)},
                                          {"input_bytes", fs::file_size(inputs[k])}};
    }
    results[pair.key] = rate[0] > 0 ? rate[1] / rate[0] : 0;
    std::printf("%s: LAZ path at %.2fx the LAS path's points/s (target: at least 0.7x)\n",
                pair.name, rate[0] > 0 ? rate[1] / rate[0] : 0);
  }
}

}  // namespace

void runBenchLaz(const BenchLazOptions& o) {
  const uint64_t n = o.points;
  if (n == 0 && o.files.empty())
    throw Error("--points 0 measures only the LAZ files given, and none was given");
  fs::create_directories(o.dir);
  const std::string stem = (fs::path(o.dir) / ("synthetic_" + o.pointsName)).string();
  const std::string las = stem + ".las", laz = stem + ".laz";
  const std::string las7 = stem + "_f7.las", laz7 = stem + "_f7.laz";
  SyntheticSpec spec;
  spec.points = n;
  spec.seed = 42;
  for (const std::string& f : {las, laz})
    if (n > 0 && !fs::exists(f)) {
      std::fprintf(stderr, "bench: generating %s\n", f.c_str());
      writeSynthetic(spec, f);
    }
  if (n > 0 && !(fs::exists(las7) && fs::exists(laz7))) {
    std::fprintf(stderr, "bench: generating %s and %s\n", las7.c_str(), laz7.c_str());
    writeFormat7(las, las7, laz7);
  }
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  nlohmann::json results = {
      {"device", cpuName()}, {"cores", cores}, {"decode", nlohmann::json::array()}};
  std::vector<std::string> decodeFiles = o.files;
  if (n > 0) decodeFiles.insert(decodeFiles.end(), {laz, laz7});
  measureDecoding(o, decodeFiles, cores, results);
  // --points 0: the files given only, no conversion.
  if (n > 0) measureConversions(o, las, laz, las7, laz7, results);
  std::ofstream(o.out) << results.dump(2) << "\n";
  std::printf("results written to %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
