// `bench diffrender`'s parts (nestlight/bench/bench_diffrender.h): the measuring in
// bench_diffrender.cpp, the tables in bench_diffrender_tables.cpp. Private to bench/src.
#pragma once

#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_gi_differential.h"
#include "nestlight/bench/bench_diffrender.h"
#include "nestlight/gi/scene.h"

namespace nestlight::bench::drbench {

// The bench's state: the scene, the ground truth and every configuration measured so far.
struct Bench {
  explicit Bench(const BenchDiffrenderOptions& options) : o(options) {}
  const BenchDiffrenderOptions& o;
  std::filesystem::path sceneFile, dir;
  gi::Scene probe;  // as loaded
  int W = 0, H = 0;
  std::FILE* log = nullptr;
  double exposure = 0;   // the PNGs' (the reference's automatic exposure)
  std::string glDevice;  // the headless GL context's renderer
  differential::Truth truth;
  // rho's floor: blocks at dL's resolution (lowWidth wide), how many, the albedo's mean there and
  // how they were chosen.
  std::vector<bool> floorBlocks;
  int lowWidth = 0;
  size_t floorCount = 0;
  double floorAlbedo = 0;
  std::string floorRule;
  std::vector<DiffrenderRun> runs;
  std::map<std::string, size_t> memo;  // resolved parameters: index into runs

  // The scene as diffrender renders it for the bench, `overrides` set in gi.parameters.
  gi::Scene scene(const nlohmann::json& overrides) const;
  // The configuration measured (once: one that resolves to the same parameters as an earlier one
  // is that one). Throws nestlight::Error naming a bad parameter value.
  DiffrenderRun run(const nlohmann::json& overrides, const std::string& label);
  // R1, R0 and the truth's images, the floor's blocks.
  void prepareTruth();
};

void checkOptions(const BenchDiffrenderOptions& o);
// The equal-time sweep's queries (BenchDiffrenderOptions::sweepQueries).
std::vector<std::string> sweepQueries(const BenchDiffrenderOptions& o);
const std::vector<std::string>& tableNames();
// Every configuration the tables asked for will render, for checking them before the reference.
std::vector<nlohmann::json> plannedOverrides(const BenchDiffrenderOptions& o);
// Measures what the tables need, then writes and prints them.
BenchDiffrenderReport makeTables(Bench& b);

}  // namespace nestlight::bench::drbench
