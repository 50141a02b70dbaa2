// `nestlight bench render`: options for bench::runBenchRender (nestlight/bench/bench_render.h).
#include "cli.h"
#include "nestlight/bench/bench_render.h"

namespace nestlight::cli {

void addBenchRender(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand("render",
                                    "Rasteriser speed (points/s): GL_POINTS with basic and with "
                                    "high-quality splatting, and the compute path");
  auto o = std::make_shared<bench::BenchRenderOptions>();
  cmd->add_option("octree", o->octree, "Octree to render (default: a generated synthetic scan)");
  cmd->add_option("--generate", o->generateName,
                  "Points of the synthetic scan when no octree is given")
      ->capture_default_str();
  cmd->add_option("--dir", o->dir, "Folder for the generated scan (reused)")->capture_default_str();
  cmd->add_option("--width", o->width, "Frame width")->capture_default_str();
  cmd->add_option("--height", o->height, "Frame height")->capture_default_str();
  cmd->add_option("--runs", o->runs, "Timed frames per rasteriser (the median is reported)")
      ->capture_default_str();
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->callback([o, &exitCode]() {
    // The scan's size matters only when it is generated.
    if (o->octree.empty()) o->generate = parseCount(o->generateName, "--generate");
    bench::runBenchRender(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
