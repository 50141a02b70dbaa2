// `nestlight bench convert`: conversion speed, peak memory, payload size per codec and the time
// to open an octree's root, on generated LAS files (made once in `dir`, reused). Each conversion
// runs as a child `nestlight convert` (harness.h, runChild) so that its peak RSS is its own.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace nestlight::bench {

struct BenchConvertOptions {
  // Point counts of the generated LAS files: the name in file names and the table ("20M"), and
  // the count.
  std::vector<std::pair<std::string, uint64_t>> sizes = {{"20M", 20'000'000},
                                                         {"100M", 100'000'000}};
  std::vector<std::string> codecs = {"zstd", "raw", "draco"};  // compared on the first size
  int runs = 3;  // per size with zstd (the median is reported)
  std::string dir = "bench-data";
  std::string out = "bench-convert.json";
  std::string memory = "1G", sampling = "poisson";  // passed to convert
  // --mpi 1,2,4: instead of the codec table, each size as 8 tiles (files) converted by
  // `mpirun -n N nestlight convert --mpi` for each N (and by one process without MPI):
  // seconds, points/s, speed-up, bytes exchanged per point, each rank's peak memory and phases.
  std::vector<int> mpiRanks;
};

// Prints the table on stdout and writes the results as JSON in `out`. Throws nestlight::Error
// when a conversion fails.
void runBenchConvert(const BenchConvertOptions& options);

}  // namespace nestlight::bench
