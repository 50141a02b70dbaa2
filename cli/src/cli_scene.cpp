// `nestlight make-scene`: the project's GI test scenes.
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "nestlight/bench/hdr_protocol.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/reference/bake_radiance.h"
#include "nestlight/gi/scene.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

namespace {

// The diffrender scene's capture: what the scan would have recorded without the inserted object,
// baked by the reference into the layer its gi.parameters.capture names. Baked every time (the
// light may have changed while the scan was reused); at 1M points and 2 paths it takes ~30 s.
void bakeDiffrenderCapture(const fs::path& sceneFile, int spp, bool quiet) {
  const gi::Scene s = gi::loadScene(sceneFile);
  gi::RadianceBakeOptions o;
  o.layer = s.gi.parameters.at("capture").get<std::string>();
  o.samplesPerPoint = spp;
  o.maxBounces = s.gi.maxBounces;
  o.seed = s.gi.seed;
  o.commandLine = {{"make-scene", "diffrender"}, {"spp", spp}};
  if (!quiet)
    std::printf("make-scene: baking the capture (layer '%s', %d paths a point)...\n",
                o.layer.c_str(), spp);
  const gi::RadianceBakeReport r = gi::bakeRadiance(s, o);
  std::printf(
      "make-scene: baked layer '%s' of %llu points in %.1f s: mean relative standard error "
      "%.4f (%llu black points left out)\n",
      o.layer.c_str(), (unsigned long long)r.points, r.seconds, r.meanRelativeStandardError,
      (unsigned long long)r.blackPoints);
}

}  // namespace

void addMakeScene(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "make-scene",
      "Generate a GI test scene: a synthetic scan converted into DIR/scan.octree, inserted meshes\n"
      "(OBJ) and DIR/scene.json for `nestlight render` and `nestlight bench gi`.\n"
      "  cornell  a closed 4 m room of coloured walls (a Cornell-box-like scan) with a glossy "
      "sphere\n"
      "  nave     a 40 m nave with two colonnades and a marble statue on a pedestal\n"
      "  object   the synthetic town scan with a gold torus, under a sky and a sun (albedo mode)\n"
      "  diffrender  differential rendering's ground truth: the cornell room's scan lit by a\n"
      "           spot light under the ceiling (with --light panel, a captured emissive ceiling\n"
      "           panel instead, a mesh with \"inserted\": false) and an inserted bronze object "
      "on\n"
      "           the floor: the Stanford bunny where --shared-data has meshes/bunny.ply (copied\n"
      "           into DIR), else a generated sphere; albedo mode, gi.method diffrender on the\n"
      "           colour layer 'captured', which make-scene bakes (nestlight bake-radiance, "
      "--bake-spp\n"
      "           paths a point) and `bench gi` measures against the reference\n"
      "  hdr-room the HDR expansion protocol: a textured room whose true HDR colour is known (the\n"
      "           octree's 'truth' layer), clipped to LDR by an exposure, and an HDR photograph of "
      "it\n"
      "           (DIR/photo.exr); `nestlight expand-hdr DIR/scan.octree --photo DIR/photo.exr`\n"
      "           restores it and `nestlight bench hdr` measures the error\n"
      "Example: nestlight make-scene cornell -o cornell && nestlight render cornell/scene.json");
  auto kind = std::make_shared<std::string>();
  auto dir = std::make_shared<std::string>();
  auto opt = std::make_shared<TestSceneOptions>();
  auto points = std::make_shared<std::string>("1M");
  auto light = std::make_shared<std::string>("spot");
  auto bakeSpp = std::make_shared<int>(2);
  auto shared = std::make_shared<std::string>("../shared/data");
  cmd->add_option("kind", *kind, "cornell, nave, object, diffrender or hdr-room")
      ->required()
      ->check(CLI::IsMember({"cornell", "nave", "object", "diffrender", "hdr-room"}));
  cmd->add_option("-o,--output", *dir, "Folder to write (created)")->required();
  cmd->add_option("-n,--points", *points, "Points in the scan (e.g. 200k, 2M)")
      ->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Seed of the synthetic scan")->capture_default_str();
  cmd->add_option("--width", opt->width, "Image width in the scene's camera")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_option("--height", opt->height, "Image height")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_flag("--overwrite", opt->overwrite,
                "Replace a scene.json, meshes and scan the folder already holds (without it, "
                "make-scene refuses a folder\n"
                "whose scene differs from the one it writes, and rebuilds nothing it can reuse)");
  cmd->add_flag("-q,--quiet", opt->quiet, "No progress output");
  auto* lightOpt =
      cmd->add_option(
             "--light", *light,
             "diffrender: what lights the room, spot (a spot light under the ceiling pointing "
             "down; the default: the reference\n"
             "samples it directly, so the baked capture converges fast) or panel (an emissive "
             "mesh under the ceiling, part of the\n"
             "captured scene, which the reference finds only by chance: a far noisier capture)")
          ->capture_default_str()
          ->check(CLI::IsMember({"panel", "spot"}));
  auto* bakeOpt =
      cmd->add_option(
             "--bake-spp", *bakeSpp,
             "diffrender: paths per scan point of the baked capture (layer 'captured'); "
             "2 bakes 1M points in about 15 s on two\n"
             "cores (stated error 0.44, 15% of points black); 16 in about 2 minutes (0.27, "
             "5%)")
          ->capture_default_str()
          ->check(CLI::Range(2, 1 << 16));
  auto* sharedOpt =
      cmd->add_option("--shared-data", *shared,
                      "diffrender: the shared data folder whose meshes/bunny.ply is the inserted "
                      "object; without that file\n"
                      "the object is a generated sphere")
          ->capture_default_str();
  cmd->callback([=, &exitCode]() {
    // Options of one kind given to another are mistakes, not silently ignored.
    if (*kind != "diffrender")
      for (const auto* given : {lightOpt, sharedOpt, bakeOpt})
        if (given->count() > 0)
          throw Error(given->get_name() + ": only make-scene diffrender takes it (the " + *kind +
                      " scene's lights and meshes are fixed)");
    opt->light = *light == "spot" ? DiffrenderLight::Spot : DiffrenderLight::Panel;
    opt->sharedData = *shared;
    opt->points = parseCount(*points, "--points");
    if (*kind == "hdr-room") {
      bench::ProtocolOptions po;
      po.points = opt->points;
      po.seed = opt->seed;
      po.overwrite = opt->overwrite;
      po.quiet = opt->quiet;
      const fs::path file = bench::makeHdrProtocol(*dir, po);
      std::printf("make-scene: wrote %s (scan.octree with its 'truth' layer, photo.exr)\n",
                  file.c_str());
      exitCode = 0;
      return;
    }
    fs::path file = makeTestScene(*parseTestSceneKind(*kind), *dir, *opt);
    if (*kind == "diffrender") bakeDiffrenderCapture(file, *bakeSpp, opt->quiet);
    std::printf("make-scene: wrote %s\n", file.c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
