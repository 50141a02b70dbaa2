// `nestlight make-scene`: the project's GI test scenes.
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "nestlight/bench/hdr_protocol.h"
#include "nestlight/converters/test_scenes.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

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
      "           captured emissive ceiling panel (a mesh with \"inserted\": false; with\n"
      "           --light spot, a spot light instead) and an inserted bronze object on the floor:\n"
      "           the Stanford bunny where --shared-data has meshes/bunny.ply (copied into DIR),\n"
      "           else a generated sphere; albedo mode, gi.method diffrender (`nestlight render\n"
      "           DIR/scene.json --method reference` renders its ground truth)\n"
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
  auto light = std::make_shared<std::string>();
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
             "diffrender: what lights the room, panel (an emissive mesh under the ceiling, "
             "part of the captured scene)\n"
             "or spot (a spot light under the ceiling pointing down) [default: panel]")
          ->check(CLI::IsMember({"panel", "spot"}));
  auto* sharedOpt =
      cmd->add_option("--shared-data", *shared,
                      "diffrender: the shared data folder whose meshes/bunny.ply is the inserted "
                      "object; without that file\n"
                      "the object is a generated sphere")
          ->capture_default_str();
  cmd->callback([=, &exitCode]() {
    // Options of one kind given to another are mistakes, not silently ignored.
    if (*kind != "diffrender")
      for (const auto* given : {lightOpt, sharedOpt})
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
    std::printf("make-scene: wrote %s\n", file.c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
