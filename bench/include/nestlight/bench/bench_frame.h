// `nestlight bench frame`: the GI frame's cost per pass (GPU time of each pass, median of runs) for
// a scene and a real-time method at a given size, interactive (tone-mapped, no read-back) and as a
// still (linear, read back): what every method built on the frame pays before its own work.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace nestlight::bench {

struct BenchFrameOptions {
  std::string scene;  // empty: make-scene cornell in `dir`
  std::string method = "raster";
  std::string mode = "albedo";  // or "radiance_cache"
  // Points of the generated scene's scan: its name in the folder's name ("1M") and the count.
  std::string pointsName = "1M";
  uint64_t points = 1'000'000;
  std::string dir = "bench-data";
  int width = 1280, height = 720;
  int runs = 5;  // timed frames (the median is reported)
  std::string out = "bench-frame.json";
  // Method parameters as the scene's gi.parameters takes them: KEY=VALUE, VALUE as JSON, else a
  // string.
  std::vector<std::string> params;
};

// Prints the tables on stdout and writes the results as JSON in `out`. Throws nestlight::Error
// for a method that is unknown or not real-time, and for a malformed parameter.
void runBenchFrame(const BenchFrameOptions& options);

}  // namespace nestlight::bench
