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
      "With --levels, the paper's Fig. 11 and 8 instead: the image after each level of the "
      "adaptive sampling\n"
      "(gi.parameters.levels: what the viewer shows as it refines) and with every pixel gathered, "
      "against the\n"
      "path-traced reference: pixels gathered, time (the projection passes' wall times), rel L2 "
      "and box 4.\n"
      "Target: the adaptive image within 10% of every pixel's box-4 error at <= 35% of its pixels "
      "and <= 1/3\n"
      "of its time. And the indirect light alone (frame less raster's direct light) against the "
      "reference's.\n"
      "Examples: nestlight bench projection room/scene.json --width 160 --height 120\n"
      "          nestlight bench projection room/scene.json --levels --mode albedo");
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
  auto levels = std::make_shared<bool>(false);
  cmd->add_flag("--levels", *levels,
                "Fig. 11 and 8: each level's image and every pixel's against the path-traced "
                "reference");
  cmd->add_option("--runs", o->runs, "--levels: timed frames per configuration (the median)")
      ->check(CLI::Range(1, 100));
  cmd->add_option("--reference-spp", o->referenceSpp,
                  "--levels: the reference's samples per pixel at most (default 1024)")
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--reference-error", o->referenceError,
                  "--levels: the reference's relative error target (default 0.01; one that stops "
                  "short of it by samples is used, not cached)")
      ->check(CLI::Range(1e-5, 1.0));
  cmd->add_option("--reference", o->reference,
                  "--levels: the reference's cache file (default: OUT/reference.exr)");
  cmd->add_option("--width", o->width, "Image width (default: the scene camera's)")
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height, "Image height (default: the scene camera's)")
      ->check(CLI::Range(16, 16384));
  cmd->callback([o, pixels, levels, &exitCode]() {
    for (const std::string& p : *pixels) {
      int x = -1, y = -1;
      char tail = 0;
      if (std::sscanf(p.c_str(), "%d,%d%c", &x, &y, &tail) != 2 || x < 0 || y < 0)
        throw Error("--pixel", p, "expected X,Y (two non-negative integers)");
      o->pixels.push_back({x, y});
    }
    if (*levels && !pixels->empty())
      throw Error("--pixel", "", "--levels measures whole images: it takes no pixels");
    if (*levels)
      bench::runBenchProjectionLevels(*o);
    else
      bench::runBenchProjection(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
