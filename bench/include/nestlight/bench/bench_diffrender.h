// `nestlight bench diffrender`: the evaluation of Rohmer, Jendersie and Grosch, "Natural
// Environment Illumination: Coherent Interactive Augmented Reality for Mobile and non-Mobile
// Devices" (IEEE TVCG 2017), section 8, made measurable on a scene with inserted meshes and a
// capture layer (`make-scene diffrender`). The ground truth is `bench gi`'s (R1 the reference,
// R0 the reference without the inserted meshes, cached in the output folder; the capture, the
// scan's albedo and diffrender's mask: bench/src/bench_gi_differential.h). Then diffrender renders
// with gi.parameters overridden, each configuration once set up (made, one untimed frame) and
// timed over `runs` frames (the medians of its frame time and of every pass's time), and once
// more with its AOVs for the errors. The tables:
//   presets      Tables 2 and 3: per query and preset, the per-pass times and the errors
//                (composite against R1, dL against R1 - R0, the inserted meshes' pixels against
//                R1, the material estimate against the albedo, rho clamped);
//   cache        Table 4: DIT at the med preset, samples N x cache (cache <= N), the dL pass's
//                time and the errors, with and without self-shadow;
//   self-shadow  Fig. 9: the inserted meshes' error per query without self-shadow (low) and
//                with it (med);
//   material     Fig. 10: the rho and |dL| images, and the mean rho on the floor against the
//                true albedo;
//   equal-time   Fig. 11: dL error over N per query, and at equal frame time (each query's
//                largest N whose median frame time is within the budget).
// Writes bench_diffrender.md (the tables as printed), bench_diffrender_<table>.csv, one CSV row
// per configuration (bench_diffrender_runs.csv) and bench_diffrender.json.
#pragma once

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace nestlight::bench {

struct BenchDiffrenderOptions {
  std::filesystem::path scene;
  std::filesystem::path out;  // empty: bench-diffrender beside the scene
  std::vector<std::string> queries = {"em", "dit", "vct", "exact"};
  std::vector<std::string> presets = {"low", "med", "high"};
  std::vector<int> samples = {8, 16, 32, 64, 128};  // N of the cache and equal-time sweeps
  std::vector<int> caches = {8, 16, 32};            // the cache sweep's; cache <= N only
  // The queries of the convergence and equal-time sweep; empty: `queries` without exact (its
  // frames take seconds on a CPU rasteriser, and the paper's Fig. 11 compares EM, DIT and VCT).
  std::vector<std::string> sweepQueries;
  // The convergence and equal-time sweep's cache, shrunk to N where N is smaller (the med
  // preset's: its N = 16 is DIT med itself).
  int sweepCache = 8;
  std::vector<std::string> tables = {"presets", "cache", "self-shadow", "material", "equal-time"};
  int runs = 3;  // timed frames per configuration, after the set-up frame
  // Fig. 11's budget, ms of frame time; empty: DIT at the med preset's median frame time.
  std::optional<double> equalTimeMs;
  double referenceError = 0.01;
  double referenceTimeLimit = 1800;
  int referenceSpp = 1 << 16;
  bool forceReference = false;
  int width = 0, height = 0;  // 0: the scene camera's
  std::string device;         // the CPU's name, for the report
};

// One configuration of diffrender, as measured.
struct DiffrenderRun {
  std::string label;         // "dit med", "dit N=32 cache=16", ...
  nlohmann::json overrides;  // the gi.parameters set over the scene's
  // As diffrender resolved them.
  std::string query, preset;
  int samples = 0, cache = 0, objectSamples = 0;
  bool selfShadow = false, secondaryBounce = false;
  double setupMs = 0;           // making the method and its first, untimed frame
  std::vector<double> frameMs;  // per timed run
  double medianMs = 0;
  // Per pass, medians over the timed runs: the GPU timer query's and the wall time between
  // glFinish() before and after the pass (on a CPU rasteriser the timer charges compute work to
  // a later pass; the synchronised wall time charges each pass its own). In the order they ran.
  std::vector<std::string> passes;
  std::map<std::string, double> passGpuMs, passWallMs;
  // The set-up frame's synchronised pass times: the impostor and vct's scene volume are built
  // there and not again while the cut and the environment stay (a still camera).
  std::map<std::string, double> setupPassWallMs;
  // Errors (relative L2) of the AOV frame: composite against R1 (and of 4 x 4 block means), dL on
  // whole scan blocks against R1 - R0, the inserted meshes' pixels against R1, rho against the
  // albedo on the scan blocks.
  double compositeL2 = 0, compositeL2Box4 = 0, deltaL2 = 0, objectL2 = 0, rhoL2 = 0;
  // The mean material estimate (mean of its channels) on the floor's blocks, the albedo's there,
  // and |rho - albedo| / albedo of those means.
  double floorRho = 0, floorAlbedo = 0, floorRhoError = 0;
  // The method's counters in the AOV frame (its render info), -1 where it reports none.
  long long rhoClamped = -1, ditUnconverged = -1, ditHidden = -1, scanSamples = -1;
  std::filesystem::path aovs;  // diffrender_delta.exr, diffrender_rho.exr, diffrender_mask.exr
};

// Fig. 11's pick: of (N, median frame ms) in the sweep's order, the index of the largest N whose
// time is at most `budgetMs`; empty when none is.
std::optional<size_t> equalTimePick(const std::vector<std::pair<int, double>>& sweep,
                                    double budgetMs);

struct BenchDiffrenderReport {
  std::vector<DiffrenderRun> runs;  // every configuration, in the order measured
  std::string markdown;             // what bench_diffrender.md holds
  nlohmann::json json;              // what bench_diffrender.json holds
  std::filesystem::path dir;
};

// Throws nestlight::Error naming the option for bad options (before anything is rendered), for a
// scene without inserted meshes or capture, and for failed renders. Progress and the tables go
// to `log` (nullptr: silent).
BenchDiffrenderReport runBenchDiffrender(const BenchDiffrenderOptions& options,
                                         std::FILE* log = stdout);

}  // namespace nestlight::bench
