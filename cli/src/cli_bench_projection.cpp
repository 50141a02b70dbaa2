// `nestlight bench projection`: options for bench::runBenchProjection
// (nestlight/bench/bench_projection.h).
#include "cli.h"
#include "nestlight/bench/bench_projection.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

void addBenchProjection(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "projection",
      "The projection method's micro-buffers against brute force's (Maletz et al. 2011, Fig. 7 "
      "and 9): at a few\n"
      "pixels, importance sampling (the paper), random sampling and fixed 1-, 2- and 3-texel "
      "splats, each\n"
      "compared texel by texel with the micro-buffer of every point of S: rms (of the luminance, "
      "relative to\n"
      "brute force's), holes (texels brute force covers that stay empty) and spill (texels covered "
      "where brute\n"
      "force has none). Targets: importance's rms at most half of random's; adaptive splats with "
      "fewer holes\n"
      "than 1-texel ones and less spill than 3-texel ones.\n"
      "Example: nestlight bench projection room/scene.json --width 160 --height 120");
  auto o = std::make_shared<bench::BenchProjectionOptions>();
  auto pixels = std::make_shared<std::vector<std::string>>();
  cmd->add_option("scene", o->scene, "Scene file")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--out", o->out, "Output folder (default: bench-projection beside the scene)");
  cmd->add_option("--pixel", *pixels,
                  "A pixel X,Y (top row 0) whose micro-buffers are compared; repeatable "
                  "(default: five receivers spread over those a 16 x 16 grid of the image finds)");
  cmd->add_option("--mode", o->mode, "radiance_cache or albedo (default: the scene's)")
      ->check(CLI::IsMember({"radiance_cache", "albedo"}));
  cmd->add_option("--points", o->points,
                  "Points of S (gi.parameters.points; default: the scene's, else 262144)")
      ->check(CLI::Range(1000, 1 << 24));
  cmd->add_option("--width", o->width, "Image width (default: the scene camera's)")
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height, "Image height (default: the scene camera's)")
      ->check(CLI::Range(16, 16384));
  cmd->callback([o, pixels, &exitCode]() {
    for (const std::string& p : *pixels) {
      int x = -1, y = -1;
      char tail = 0;
      if (std::sscanf(p.c_str(), "%d,%d%c", &x, &y, &tail) != 2 || x < 0 || y < 0)
        throw Error("--pixel", p, "expected X,Y (two non-negative integers)");
      o->pixels.push_back({x, y});
    }
    bench::runBenchProjection(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
