// What every benchmark harness shares: progress lines to an optional log, medians, the CPU's
// name for reports, human-readable counts and sizes, and child runs of the `nestlight` program
// that measure a command's own time and peak memory.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace nestlight::bench {

// printf to `log` and flush it (progress must show while a long measure runs); nullptr: silent.
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
void say(std::FILE* log, const char* format, ...);

double median(std::vector<double> v);  // of an even count, the mean of the middle two; empty: 0
std::string cpuName();                 // /proc/cpuinfo's model name
std::string humanBytes(double bytes);  // "1.5 MiB"
std::string humanCount(double n);      // "1.50 M", "800.0 k"

// Text rows in columns as wide as their widest cell (UTF-8 counted in code points, so "—" is
// one), two spaces apart, each line ending in '\n'; the first row is the header, underlined.
// right[c]: column c aligned right (numbers); missing: left.
std::string alignedTable(const std::vector<std::vector<std::string>>& rows,
                         const std::vector<bool>& right = {});

// Runs the program this process runs (/proc/self/exe: the `nestlight` command line) with `args`
// in a child process (stdout discarded): wall time, the child's own peak RSS, and the peak size
// of the converter's temporary folder under `watch` (an octree folder being built; empty: not
// measured). args[0] is the child's argv[0].
struct ChildRun {
  double seconds = 0;
  uint64_t peakRss = 0;
  uint64_t peakTempBytes = 0;
  int status = 0;
};
ChildRun runChild(const std::vector<std::string>& args, const std::string& watch = "");

// Runs this program with `args` (no argv[0]), its standard output into `log`; returns that
// output. Throws nestlight::Error naming `log` when the child fails.
std::string runSelf(const std::vector<std::string>& args, const std::filesystem::path& log);

}  // namespace nestlight::bench
