// `nestlight bench hdr`: HDR expansion on the ground-truth protocol (Sabbadin et al., "High
// Dynamic Range Point Clouds for Real-Time Relighting", 2019, section 6.2; hdr_protocol.h):
// stage timings and peak memory against point count (their Table 1), the cloud colour's error
// against the truth beside the baselines (their Table 2's point-cloud column) for both modes, and
// the error of relit renders of inserted objects against the render lit by the truth (Table 2's
// rendering columns). Each expansion runs as a child `nestlight expand-hdr` (harness.h, runSelf)
// so that its peak memory is its own: these run inside the `nestlight` program only.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "nestlight/bench/hdr_relit.h"

namespace nestlight::bench {

struct BenchHdrOptions {
  std::vector<uint64_t> sizes = {300'000, 1'000'000};  // points of each protocol scene
  std::string work = "bench-data";                     // the protocol scenes (reused when there)
  std::string out = "bench-hdr.json";
  int runs = 3;  // expansions per size and mode (the median is reported)
  int autoViews = 2;
  int faceSize = 384;
  std::string modes = "rgb,luminance";  // "rgb", "luminance", "both" or "none" (with layers)
  std::string layers;                   // also judge these colour layers (comma-separated)
  bool unregistered = false;            // expand without the photograph's camera
  RelitOptions relit;
  std::string scanDemo;  // runBenchHdrScan's scan
  double threshold = 0.9;
};

// The protocol: a table row per size and mode (and per layer and baseline), and the results as
// JSON in `out`. Throws nestlight::Error when an expansion fails.
void runBenchHdr(const BenchHdrOptions& options);

// The --scan demo: expands a copy of the user's scan `scanDemo` (in `work`) with a photograph
// rendered from its own colour, and writes images before and after, and the report in `out`.
void runBenchHdrScan(const BenchHdrOptions& options);

}  // namespace nestlight::bench
