// `nestlight bench render`: points per second of each of the point view's rasterisers on this
// machine's GL (an NVIDIA GPU through EGL, or llvmpipe on the CPU), with the whole view's cut
// resident: GL_POINTS with basic and with high-quality splatting, and the compute path (two 32-bit
// passes, and one 64-bit pass where the driver has 64-bit atomics).
#pragma once

#include <cstdint>
#include <string>

namespace nestlight::bench {

struct BenchRenderOptions {
  std::string octree;  // empty: a generated synthetic scan in `dir` (reused)
  // Points of the generated scan: its name in the folder's name ("5M") and the count.
  std::string generateName = "5M";
  uint64_t generate = 5'000'000;
  std::string dir = "bench-data";
  int width = 1920, height = 1080;
  int runs = 5;  // timed frames per rasteriser (the median is reported)
  std::string out = "bench-render.json";
};

// Prints the table on stdout and writes the results as JSON in `out`. Throws nestlight::Error
// when the cut does not load within 10 minutes.
void runBenchRender(const BenchRenderOptions& options);

}  // namespace nestlight::bench
