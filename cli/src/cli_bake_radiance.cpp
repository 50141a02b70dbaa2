// `nestlight bake-radiance`: the captured radiance of a generated scene's scan points, baked by
// the path-traced reference into a colour layer (the ground truth of differential rendering).
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>

#include "cli.h"
#include "nestlight/gi/reference/bake_radiance.h"
#include "nestlight/gi/scene.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace {

constexpr const char* kBakeRadianceHelp =
    "Bake the radiance each scan point sends out into a colour layer of its octree: the capture\n"
    "of differential rendering (Rohmer, Jendersie and Grosch 2017). The scene must be in the\n"
    "albedo mode (gi.mode \"albedo\": scan colours are albedos); each point, a Lambert disc of\n"
    "that albedo, is lit by the scene's lights, environment and emissive meshes, with the meshes\n"
    "marked inserted (the default; \"inserted\": false keeps one) left out, and path traced by\n"
    "the reference with --spp paths a point. Every point of every level is baked, so each scan\n"
    "must fit its memory_budget whole and have normals. A scene that selects the layer\n"
    "(octrees[].colour) in the radiance-cache mode then shows the baked radiance as the scan's\n"
    "capture (colour_scale 1: the layer holds radiance). The estimate's standard error (mean\n"
    "over points of each point's relative standard error, from its paths' variance) is printed\n"
    "and kept in the layer's build notes (`nestlight info`).\n"
    "Example: nestlight make-scene object -o town -n 200k && "
    "nestlight bake-radiance town/scene.json --layer captured";

}  // namespace

void addBakeRadiance(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("bake-radiance", kBakeRadianceHelp);
  auto scene = std::make_shared<std::string>();
  auto o = std::make_shared<gi::RadianceBakeOptions>();
  auto bounces = std::make_shared<int>(0);
  auto seed = std::make_shared<uint64_t>(0);
  auto quiet = std::make_shared<bool>(false);
  cmd->add_option("scene", *scene, "Scene file (scene.json) in the albedo mode")->required();
  cmd->add_option("--layer", o->layer, "Name of the colour layer to write (not 'rgb')")->required();
  cmd->add_option("--spp", o->samplesPerPoint, "Paths per point (at least 2)")
      ->capture_default_str();
  auto* bouncesOpt =
      cmd->add_option("--bounces", *bounces,
                      "Scattering events, the point's own the first (default: gi.max_bounces)");
  auto* seedOpt = cmd->add_option("--seed", *seed, "Random seed (default: gi.seed)");
  cmd->add_flag("-q,--quiet", *quiet, "No progress output");
  cmd->callback([=, &exitCode]() {
    requireExists(*scene);
    const gi::Scene s = gi::loadScene(*scene);
    o->maxBounces = bouncesOpt->count() ? *bounces : s.gi.maxBounces;
    o->seed = seedOpt->count() ? *seed : s.gi.seed;
    o->commandLine = {{"scene", *scene},
                      {"spp", o->samplesPerPoint},
                      {"bounces", o->maxBounces},
                      {"seed", o->seed}};
    const auto t0 = std::chrono::steady_clock::now();
    if (!*quiet) {
      o->log = [](const std::string& line) {
        std::fprintf(stderr, "bake-radiance: %s\n", line.c_str());
      };
      auto last = std::make_shared<std::pair<double, uint64_t>>(-1.0, 0);
      o->progress = [t0, last](uint64_t done, uint64_t total) {
        const double t =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        // A line a second at most, and the last once.
        if (done == last->second || (t - last->first < 1.0 && done < total)) return;
        *last = {t, done};
        const double eta = done > 0 ? t * double(total - done) / double(done) : 0;
        std::fprintf(stderr, "bake-radiance: %s of %s points, %.0f s, ETA %.0f s\n",
                     humanCount(double(done)).c_str(), humanCount(double(total)).c_str(), t, eta);
      };
    }
    const gi::RadianceBakeReport r = gi::bakeRadiance(s, *o);
    std::printf("bake-radiance: %s, layer '%s' in %zu octree%s\n", scene->c_str(), o->layer.c_str(),
                s.octrees.size(), s.octrees.size() == 1 ? "" : "s");
    std::printf("  points        %llu, %d paths each, %d bounces, seed %llu\n",
                (unsigned long long)r.points, o->samplesPerPoint, o->maxBounces,
                (unsigned long long)o->seed);
    std::printf("  left out      %zu inserted mesh%s\n", r.meshesLeftOut,
                r.meshesLeftOut == 1 ? "" : "es");
    std::printf("  time          %.1f s, %s rays\n", r.seconds, humanCount(double(r.rays)).c_str());
    if (r.nonFiniteSamples)
      std::printf("  warning       %llu non-finite paths dropped\n",
                  (unsigned long long)r.nonFiniteSamples);
    std::printf("  std. error    %.4f (mean relative standard error over %llu points%s)\n",
                r.meanRelativeStandardError, (unsigned long long)(r.points - r.blackPoints),
                r.blackPoints
                    ? (", " + std::to_string(r.blackPoints) + " black points left out").c_str()
                    : "");
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
