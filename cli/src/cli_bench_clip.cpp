// `nestlight bench clip`: options for bench::runBenchClip (nestlight/bench/bench_clip.h).
#include "cli.h"
#include "nestlight/bench/bench_clip.h"

namespace nestlight::cli {

void addBenchClip(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "clip", "export --clip, info --clip and profile on a large octree: points/s and peak memory");
  auto o = std::make_shared<bench::BenchClipOptions>();
  cmd->add_option("--octree", o->octree, "An octree to measure (default: a generated one)");
  cmd->add_option("--points", o->pointsName, "Points of the generated octree (reused in --dir)")
      ->capture_default_str();
  cmd->add_option("--runs", o->runs, "Runs of each operation (the median is reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--dir", o->dir, "Folder for the generated octree and the outputs")
      ->capture_default_str();
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->callback([o, &exitCode]() {
    o->points = parseCount(o->pointsName, "--points");
    bench::runBenchClip(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
