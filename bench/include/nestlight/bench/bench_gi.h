// The evaluation harness of the GI methods (`nestlight bench gi`): the path-traced reference is
// rendered once to a tight error target and cached beside the results; every method asked for
// (default: every registered one) then renders the scene at each of its quality levels, timed
// (median of runs, loading excluded) and compared with the reference (gi/metrics). Writes CSV,
// JSON and an SVG plot of time against relative error.
#pragma once

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/gi/metrics.h"

namespace nestlight::bench {

struct BenchGiOptions {
  std::filesystem::path scene;
  std::filesystem::path out;  // empty: bench-gi beside the scene
  int runs = 3;
  double referenceError = 0.004;
  double referenceTimeLimit = 1800;
  int referenceSpp = 1 << 16;
  bool forceReference = false;
  std::vector<std::string> methods;  // empty: every registered method
  // Quality levels per method (samples per pixel, shadow-map texels, ...); a method not listed
  // takes its registered defaults.
  std::map<std::string, std::vector<int>> qualities;
  bool variants = true;       // also each method's variants (MethodInfo::variants)
  std::string mode;           // "albedo" or "radiance_cache": overrides the scene's
  int width = 0, height = 0;  // 0: the scene camera's
  std::string device;         // the CPU's name, for the report (the CLI reads /proc/cpuinfo)
};

struct BenchGiRow {
  std::string method;
  std::string variant;  // "" : the method as the scene sets it
  std::string qualityName;
  int quality = 0;
  std::vector<double> ms;  // per run, the method's frame time
  double medianMs = 0;
  double raysPerSecond = 0, samplesPerSecond = 0;
  std::vector<std::pair<std::string, double>> passMs;  // GL methods: GPU time per pass, first run
  gi::ImageComparison cmp;
  double relativeL2 = 0;
  double relativeL2Box4 = 0;       // of 4 x 4-pixel block means (shading, not pixel sampling)
  gi::ImageAttributes attributes;  // the first run's (clamp loss, ISM agreement, ...)
};

struct BenchGiReport {
  std::vector<BenchGiRow> rows;
  nlohmann::json json;  // what bench_gi.json holds
  std::filesystem::path dir;
};

// Throws nestlight::Error for unknown methods (before any rendering), bad scenes and failed
// renders. Progress and the table go to `log` (nullptr: silent).
BenchGiReport runBenchGi(const BenchGiOptions& options, std::FILE* log = stdout);

}  // namespace nestlight::bench
