// `nestlight bench frame`: options for bench::runBenchFrame (nestlight/bench/bench_frame.h).
#include "cli.h"
#include "nestlight/bench/bench_frame.h"
#include "nestlight/gi/methods.h"

namespace nestlight::cli {

void addBenchFrame(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand("frame",
                                    "GPU time per pass of a real-time GI method's frame (median of "
                                    "--runs), interactive (tone-mapped, no\n"
                                    "read-back) and as a still (linear, read back). Without a "
                                    "scene, the generated cornell scene.\n"
                                    "Example: nestlight bench frame --width 1280 --height 720");
  auto o = std::make_shared<bench::BenchFrameOptions>();
  cmd->add_option("scene", o->scene, "Scene file (default: make-scene cornell in --dir)");
  std::vector<std::string> realTime;  // the GL methods, which have a frame of passes
  for (const auto& m : gi::registeredMethods())
    if (m.gpu) realTime.push_back(m.name);
  std::string names;
  for (const auto& n : realTime) names += (names.empty() ? "" : ", ") + n;
  cmd->add_option("--method", o->method, "A real-time method (" + names + ")")
      ->check(CLI::IsMember(realTime))
      ->capture_default_str();
  cmd->add_option("--mode", o->mode, "radiance_cache or albedo")
      ->check(CLI::IsMember({"radiance_cache", "albedo"}))
      ->capture_default_str();
  cmd->add_option("--points", o->pointsName, "Points of the generated scene's scan")
      ->capture_default_str();
  cmd->add_option("--dir", o->dir, "Folder for the generated scene (reused)")
      ->capture_default_str();
  cmd->add_option("--width", o->width, "Frame width")
      ->capture_default_str()
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--height", o->height, "Frame height")
      ->capture_default_str()
      ->check(CLI::Range(16, 16384));
  cmd->add_option("--runs", o->runs, "Timed frames (the median is reported)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--json", o->out, "Where to write the results")->capture_default_str();
  cmd->add_option(
      "--param", o->params,
      "A method parameter as the scene's gi.parameters takes it, KEY=VALUE (VALUE as JSON, else a "
      "string),\n"
      "e.g. --param vpls=1024 --param variant=classic --param estimator=smc; repeatable");
  cmd->callback([o, &exitCode]() {
    // The scan's size matters only when the scene is generated.
    if (o->scene.empty()) o->points = parseCount(o->pointsName, "--points");
    bench::runBenchFrame(*o);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
