// `nestlight bench laz`: LAZ decoding speed on one core and on all cores (points/s and MB/s of
// compressed input), for given LAZ files and a generated one (also as LAS 1.4 point format 7, for
// the layered compressor), and conversion speed from LAZ against the same points from LAS (each
// conversion a child `nestlight convert`, harness.h, median of runs).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace nestlight::bench {

struct BenchLazOptions {
  std::vector<std::string> files;  // LAZ files whose decoding is measured as well
  // Points of the generated scan (0: none, and no conversion): its name in file names ("20M")
  // and the count.
  std::string pointsName = "20M";
  uint64_t points = 20'000'000;
  int runs = 3;  // of each measurement (the median is reported)
  std::string dir = "bench-data";
  std::string out = "bench-laz.json";
  std::string memory = "1G";  // passed to convert
};

// Prints the tables on stdout and writes the results as JSON in `out`. Throws nestlight::Error
// without files and without a generated scan, or when a conversion fails.
void runBenchLaz(const BenchLazOptions& options);

}  // namespace nestlight::bench
