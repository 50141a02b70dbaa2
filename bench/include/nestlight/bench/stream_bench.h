// `nestlight bench stream`: the streaming scheduler's CPU time per frame with every node of a
// large octree resident, the time to full detail after a teleport, and the bytes a converged view
// read against the bytes its nodes hold. The harness measures the streaming library as any program
// links it; the command line only parses options.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace nestlight::bench {

struct StreamBenchOptions {
  int frames = 600;              // frames timed per camera path with every node resident
  int teleports = 10;            // random views for the teleport and bytes-read measures
  double frameMs = 1000.0 / 60;  // frame period while waiting for full detail
  uint64_t seed = 7;             // of the random views
  std::string device;            // for the report
};

// Runs the three measures on `octree`; progress and tables go to `log` (nullptr: silent).
// Returns what `bench stream` writes as JSON. Throws nestlight::Error for a bad octree.
nlohmann::json runStreamBench(const std::filesystem::path& octree, const StreamBenchOptions& o,
                              std::FILE* log = stdout);

}  // namespace nestlight::bench
