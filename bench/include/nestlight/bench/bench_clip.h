// `nestlight bench clip`: the heritage tools' reads on a large octree. `export --clip` (a box
// holding about a tenth of the scan, to LAS), `info --clip` (the same box, counted) and
// `profile` (a line across the scan, to LAS and PNG), each a child process (harness.h): median
// seconds, points read per second (the points of the nodes the volumes reach), payload bytes read
// per second, points kept, and the child's peak memory.
#pragma once

#include <cstdint>
#include <string>

namespace nestlight::bench {

struct BenchClipOptions {
  std::string octree;             // an existing octree; empty: a generated one of `points`
  std::string pointsName = "1B";  // its name in the folder ("1B")
  uint64_t points = 1'000'000'000;
  int runs = 3;
  std::string dir = "bench-data";
  std::string out = "bench-clip.json";
};

// Prints a table on stdout and writes the results as JSON in `out`. Throws nestlight::Error when
// a child fails.
void runBenchClip(const BenchClipOptions& options);

}  // namespace nestlight::bench
