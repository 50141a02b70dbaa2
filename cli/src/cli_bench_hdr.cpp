// `nestlight bench hdr`: options for bench::runBenchHdr and bench::runBenchHdrScan
// (nestlight/bench/bench_hdr.h).
#include <algorithm>

#include "cli.h"
#include "nestlight/bench/bench_hdr.h"

namespace nestlight::cli {

void addBenchHdr(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "hdr",
      "HDR expansion on the ground-truth protocol (make-scene hdr-room): stage timings and peak\n"
      "memory against point count, and the cloud colour's error against the truth for the LUM and\n"
      "RGB modes beside the LDR colour and a global inverse tone mapping (LANDIS-PC)");
  auto o = std::make_shared<bench::BenchHdrOptions>();
  auto sizes = std::make_shared<std::string>("300k,1M");
  cmd->add_option("--points", *sizes, "Scan sizes, comma-separated (e.g. 300k,1M,10M,100M)")
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "Expansions per size and mode (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  cmd->add_option("--auto-views", o->autoViews, "Cube maps per expansion")->capture_default_str();
  cmd->add_option("--face-size", o->faceSize, "Cube-map face size")->capture_default_str();
  cmd->add_option("--modes", o->modes, "rgb, luminance, both, or none (with --layers)")
      ->capture_default_str();
  cmd->add_flag(
      "--unregistered", o->unregistered,
      "Expand without the photograph's camera (auto views only), as for a photograph that is "
      "not registered with the scan");
  cmd->add_option(
      "--layers", o->layers,
      "Also judge these colour layers of the protocol octrees (comma-separated; e.g. made by "
      "expand-hdr with other options), with the cloud and relit errors");
  cmd->add_option("--dir", o->work, "Folder for the protocol scenes (reused when present)")
      ->capture_default_str();
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->add_option(
         "--relit", o->relit.method,
         "GI method of the relit renders (two boxes in the room lit by each colour source; "
         "none: skip them)")
      ->capture_default_str();
  cmd->add_option("--relit-width", o->relit.width, "Relit render width")
      ->capture_default_str()
      ->check(CLI::Range(8, 4096));
  cmd->add_option("--relit-height", o->relit.height, "Relit render height")
      ->capture_default_str()
      ->check(CLI::Range(8, 4096));
  cmd->add_option(
      "--scan", o->scanDemo,
      "Instead of the protocol: expand a copy of this scan with an HDR photograph rendered from\n"
      "its own colour with the highlights pushed beyond 1 (up to 16x), and write images before "
      "and\n"
      "after into --dir");
  cmd->add_option("--threshold", o->threshold, "t_l for --scan")->capture_default_str();
  cmd->callback([o, sizes, &exitCode]() {
    if (!o->scanDemo.empty()) {
      bench::runBenchHdrScan(*o);
    } else {
      o->sizes.clear();
      for (size_t at = 0; at <= sizes->size();) {
        const size_t comma = std::min(sizes->find(',', at), sizes->size());
        o->sizes.push_back(parseCount(sizes->substr(at, comma - at), "--points"));
        at = comma + 1;
      }
      bench::runBenchHdr(*o);
    }
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
