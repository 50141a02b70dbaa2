// `nestlight bench gi`: options for bench::runBenchGi (nestlight/bench/bench_gi.h).
#include <sstream>

#include "cli.h"
#include "nestlight/bench/bench_gi.h"
#include "nestlight/gi/methods.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace {

std::vector<int> parseIntList(const std::string& text, const std::string& option) {
  std::vector<int> v;
  for (double x : parseNumberList(text, option)) {
    if (!(x >= 1 && x <= (1 << 24)) || x != std::floor(x))
      throw Error(option + ": '" + std::to_string(x) + "' is not a positive integer");
    v.push_back(int(x));
  }
  if (v.empty()) throw Error(option + ": give at least one value");
  return v;
}

}  // namespace

void addBenchGi(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  std::string methods;
  for (const auto& m : gi::registeredMethods()) {
    std::string levels;
    for (int q : m.defaultQualities) levels += (levels.empty() ? "" : ",") + std::to_string(q);
    methods += "\n  " + m.name + ": " + m.summary + "; quality = " + m.qualityName + " (default " +
               levels + ")";
  }
  auto* cmd = bench->add_subcommand(
      "gi",
      "Speed against error of the GI methods on a scene: the path-traced reference is rendered "
      "once to\n"
      "--reference-error (cached in the output folder), then each method at each of its quality "
      "levels is\n"
      "timed (median of --runs; set-up reported apart) and compared with it; a method or variant "
      "that\ncannot apply to the scene (ibl without an environment) is skipped with its reason. "
      "On a scene with\ninserted meshes and a capture layer (make-scene diffrender) the reference "
      "is also rendered without\nthe inserted meshes (R0), diffrender's rows get dL, object and "
      "rho errors and pbgi and vpl a\ntwo-simulation row (docs/SCENE.md). "
      "Methods:" +
          methods +
          "\nExample: nestlight make-scene cornell -o cornell && nestlight bench gi "
          "cornell/scene.json\n"
          "         nestlight bench gi cornell/scene.json --methods raster --quality "
          "raster=512,2048");
  auto o = std::make_shared<bench::BenchGiOptions>();
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto spp = std::make_shared<std::string>();
  auto methodText = std::make_shared<std::string>();
  auto quality = std::make_shared<std::vector<std::string>>();
  cmd->add_option("scene", *scene, "Scene file (.json)")->required();
  cmd->add_option("-o,--out", *out, "Output folder (default: bench-gi beside the scene)");
  cmd->add_option("--runs", o->runs,
                  "Timed frames per setting, after the set-up (making the method and a GL "
                  "method's first frame, reported apart); the median is reported")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  cmd->add_option("--reference-error", o->referenceError,
                  "Relative error the cached reference is rendered to")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--reference-time-limit", o->referenceTimeLimit,
                  "Seconds the reference may take at most")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e7));
  cmd->add_option("--reference-spp", o->referenceSpp, "Samples per pixel of the reference at most")
      ->capture_default_str()
      ->check(CLI::Range(2, 1 << 24));
  cmd->add_option("--methods", *methodText,
                  "Methods to measure, comma-separated (default: all: " + gi::methodList() + ")");
  cmd->add_option("--quality", *quality,
                  "Quality levels of one method, METHOD=LIST (e.g. raster=512,1024); repeatable");
  cmd->add_option(
      "--spp", *spp,
      "Quality levels of every method whose quality is samples per pixel (e.g. 1,4,16)");
  cmd->add_option("--width", o->width, "Override the scene camera's width")
      ->check(CLI::Range(1, 16384));
  cmd->add_option("--height", o->height, "Override the scene camera's height")
      ->check(CLI::Range(1, 16384));
  cmd->add_flag("--force-reference", o->forceReference,
                "Render the reference again even when a cached one matches");
  cmd->add_option("--mode", o->mode,
                  "Override the scene's gi.mode: albedo (scan points reflect their colour) or "
                  "radiance_cache (they emit it)")
      ->check(CLI::IsMember({"albedo", "radiance_cache"}));
  auto noVariants = std::make_shared<bool>(false);
  cmd->add_flag("--no-variants", *noVariants,
                "Only each method as the scene sets it (default: also the variants each method "
                "declares in the registry, e.g. vpl at 1 to 3 bounces and with exact visibility, "
                "pbgi's traversals, ibl's estimators; those that cannot apply to the scene are "
                "skipped with their reason)");
  cmd->callback([=, &exitCode]() {
    bench::BenchGiOptions opt = *o;
    opt.variants = !*noVariants;
    opt.device = cpuName();
    opt.scene = *scene;
    opt.out = *out;
    std::stringstream ss(*methodText);
    for (std::string m; std::getline(ss, m, ',');)
      if (!m.empty()) opt.methods.push_back(m);
    if (!spp->empty()) {
      const std::vector<int> levels = parseIntList(*spp, "--spp");
      for (const auto& m : gi::registeredMethods())
        if (m.qualityName == "samples per pixel") opt.qualities[m.name] = levels;
    }
    for (const auto& q : *quality) {
      const auto eq = q.find('=');
      if (eq == std::string::npos || eq == 0)
        throw Error("--quality: expected METHOD=LIST, got '" + q + "'");
      opt.qualities[q.substr(0, eq)] =
          parseIntList(q.substr(eq + 1), "--quality " + q.substr(0, eq));
    }
    bench::runBenchGi(opt, stdout);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
