// The evaluation harness of the GI methods (`nestlight bench gi`): the path-traced reference is
// rendered once to a tight error target and cached beside the results; every method asked for
// (default: every registered one) then renders the scene at each of its quality levels, timed
// (median of runs; the set-up, making the method and a GL method's first frame with its shader
// compilation, reported apart) and compared with the reference (gi/metrics). A method or variant
// that cannot apply to the scene (gi::whyNotApplicable) is skipped with its reason. Writes CSV,
// JSON and a plot of time against relative error (SVG, and PNG beside it).
#pragma once

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/metrics.h"

namespace nestlight::bench {

struct BenchGiOptions {
  std::filesystem::path scene;
  std::filesystem::path out;  // empty: bench-gi beside the scene
  int runs = 3;  // timed frames per setting, after the set-up (a GL method's first frame)
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
  std::string qualityUnit;  // short, for labels: "spp", "VPLs"
  double setupMs = 0;  // making the method (loading, building) and, for GL methods, a first frame
  std::vector<double> ms;  // per run, the method's frame time, after the set-up
  double medianMs = 0;
  double raysPerSecond = 0, samplesPerSecond = 0;
  std::vector<std::pair<std::string, double>> passMs;  // GL methods: GPU time per pass, first run
  gi::ImageComparison cmp;
  double relativeL2 = 0;
  double relativeL2Box4 = 0;       // of 4 x 4-pixel block means (shading, not pixel sampling)
  gi::ImageAttributes attributes;  // the first run's (clamp loss, ISM agreement, ...)
  // Differential rendering (a scene with inserted meshes and gi.parameters.capture; diffrender
  // and the two-simulation variants only): relative L2 of dL on whole scan blocks against
  // R1 - R0, of the inserted meshes' pixels against R1, and of diffrender's material estimate
  // against the scan's albedo. Empty elsewhere.
  std::optional<double> deltaL2, objectL2, rhoL2;
};

// A method or variant not measured, and why (gi::whyNotApplicable).
struct BenchGiSkip {
  std::string method, variant, reason;
};

struct BenchGiReport {
  std::vector<BenchGiRow> rows;
  std::vector<BenchGiSkip> skipped;
  // R0 (the reference without the inserted meshes: differential rendering not done) against R1,
  // where the scene has inserted meshes and a capture; empty elsewhere.
  std::optional<double> r0RelativeL2;
  nlohmann::json json;  // what bench_gi.json holds
  std::filesystem::path dir;
};

// The time at which a curve of (time, error) points, in order of quality, reaches `target`: the
// first point at or below it (log-log interpolated from the one before), else an extrapolation
// of the straight line fitted to log error against log time over the last kTimeFitPoints points,
// made only where that slope is at most kTimeFitSlope (the error clearly falls with time: a Monte
// Carlo estimator's is -1/2) and the time it gives is at most kTimeFitReach times the longest
// measured, and only where those points span at least kTimeFitSpan in time (over a narrower span
// the slope is the times' noise); otherwise not reached (ms empty). One rule for every method.
constexpr int kTimeFitPoints = 3;
constexpr double kTimeFitSlope = -0.2, kTimeFitReach = 10, kTimeFitSpan = 2;
struct ErrorPoint {
  double ms = 0, error = 0;
  std::string label;  // "32 spp"
};
struct TimeToError {
  std::optional<double> ms;
  std::string how;
  std::optional<double> slope;  // of the fit, where one was made
};
TimeToError timeToError(const std::vector<ErrorPoint>& curve, double target);

// With a capture layer (gi.parameters.capture) and inserted meshes, the reference is rendered
// also without the inserted meshes (R0, cached beside the other as reference_without.exr), and
// diffrender's rows get dL, object and material errors (bench_gi_differential.h); pbgi and vpl
// get a "two-simulation" variant: rendered with and without the inserted meshes, the difference
// added to the capture on scan pixels, the row's time the two frames' (a baseline, run with or
// without `variants`).
// Throws nestlight::Error for unknown methods (before any rendering), bad scenes and failed
// renders. Progress and the table go to `log` (nullptr: silent).
BenchGiReport runBenchGi(const BenchGiOptions& options, std::FILE* log = stdout);

}  // namespace nestlight::bench
