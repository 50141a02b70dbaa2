// `nestlight bench ibl`: options for bench::runBenchIbl (nestlight/bench/bench_ibl.h).
#include <cmath>
#include <sstream>

#include "cli.h"
#include "nestlight/bench/bench_ibl.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

void addBenchIbl(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "ibl",
      "Equal-time comparison of the ibl method's estimators under video light probes (Kronander et "
      "al.\n"
      "2014, Fig. 3, measured): a glossy sphere on a floor under a generated moving sun, the same "
      "sun on\n"
      "scanned receivers (the object scene's town in the albedo mode), and the shared stage map "
      "(and, with\n"
      "--scenes outdoor, the esplanade map) turning 4 degrees a frame. Every frame's ground truth "
      "is the\n"
      "reference's direct light through pixel centres (cached); each estimator renders the "
      "sequence at\n"
      "each sample count. Reports per frame the relative L2 error (also net of the reference's "
      "own\n"
      "noise, and of 4 x 4 block means with the ratio of the image means: on a scan the per-pixel "
      "error\n"
      "has the splats' colour blending as a floor), variance (two seeds) and flicker, frame times "
      "at\n"
      "--size and --timing-size, and per estimator the time to 5% and 2% error. Writes "
      "bench_ibl.csv,\n"
      "bench_ibl.json and SVG plots.\n"
      "Example: nestlight bench ibl -o bench-ibl --frames 8 --samples 4,16,64,256");
  auto o = std::make_shared<bench::BenchIblOptions>();
  auto scenes = std::make_shared<std::string>("moving-sun,scanned,shared");
  auto estimators = std::make_shared<std::string>("mis,bis,smc,env");
  auto samples = std::make_shared<std::string>("4,16,64");
  auto out = std::make_shared<std::string>("bench-ibl");
  auto shared = std::make_shared<std::string>();
  auto noVariance = std::make_shared<bool>(false);
  cmd->add_option("-o,--out", *out, "Output folder")->capture_default_str();
  cmd->add_option("--scenes", *scenes,
                  "moving-sun, scanned (the sun on a scan), shared (the stage map), outdoor (the "
                  "esplanade map); comma-separated")
      ->capture_default_str();
  cmd->add_option("--estimators", *estimators,
                  "mis, bis, smc, env (environment sampling alone), brdf")
      ->capture_default_str();
  cmd->add_option("--samples", *samples,
                  "Samples per pixel, comma-separated (the ibl method's quality levels)")
      ->capture_default_str();
  cmd->add_option("--frames", o->frames, "Frames of each probe sequence")
      ->capture_default_str()
      ->check(CLI::Range(2, 10000));
  cmd->add_option("--size", o->size, "Image side of the error study")
      ->capture_default_str()
      ->check(CLI::Range(8, 8192));
  cmd->add_option("--timing-size", o->timingSize,
                  "Image side at which frame times are also measured (0: not)")
      ->capture_default_str()
      ->check(CLI::Range(0, 8192));
  cmd->add_option("--reference-spp", o->referenceSpp, "Samples per pixel of each frame's reference")
      ->capture_default_str()
      ->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--roughness", o->roughness, "The sphere's GGX roughness")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--shared-data", *shared,
                  "The shared data folder (default: ../shared/data beside the working directory)");
  cmd->add_flag("--no-variance", *noVariance,
                "Skip the second seed (no variance figures; half the time)");
  cmd->callback([=, &exitCode]() {
    bench::BenchIblOptions opt = *o;
    opt.out = *out;
    opt.device = cpuName();
    opt.variance = !*noVariance;
    opt.sharedData =
        shared->empty() ? std::filesystem::path("../shared/data") : std::filesystem::path(*shared);
    auto split = [](const std::string& text) {
      std::vector<std::string> v;
      std::stringstream ss(text);
      for (std::string s; std::getline(ss, s, ',');)
        if (!s.empty()) v.push_back(s);
      return v;
    };
    opt.scenes = split(*scenes);
    opt.estimators = split(*estimators);
    opt.samples.clear();
    for (double x : parseNumberList(*samples, "--samples")) {
      if (!(x >= 1 && x <= 4096) || x != std::floor(x))
        throw Error("--samples: '" + std::to_string(x) + "' is not 1 to 4096");
      opt.samples.push_back(int(x));
    }
    bench::runBenchIbl(opt, stdout);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
