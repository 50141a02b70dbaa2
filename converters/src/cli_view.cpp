// `nestlight view`: the interactive viewer.
#include <memory>

#include "cli.h"
#include "nestlight/viewer/window_app.h"

namespace nestlight::cli {

void addView(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "view",
      "Open an octree in a window and fly through it; nodes stream in under the budgets.\n"
      "Orbit: drag (rotate), middle-drag (pan), wheel (zoom). Fly: WASD, Q/E down/up, shift faster.\n"
      "The panel sets rasteriser, colouring, point size, eye-dome lighting and budgets, and takes screenshots.");
  auto opt = std::make_shared<viewer::ViewerOptions>();
  auto job = std::make_shared<viewer::RenderJob>();
  auto text = std::make_shared<RenderOptionText>();
  auto octree = std::make_shared<std::string>();
  cmd->add_option("octree", *octree, "Octree folder made by `nestlight convert`")->required();
  cmd->add_option("--frames", opt->frames, "Close after this many frames (scripted runs; 0: when closed)");
  cmd->add_option("--orbit", opt->orbitDegreesPerFrame, "Turn the camera by this many degrees per frame");
  cmd->add_option("--screenshot", opt->screenshot, "Save the last frame to this PNG/EXR (with --frames)");
  addRenderOptions(cmd, *job, text);
  cmd->callback([=, &exitCode]() {
    job->octree = *octree;
    applyRenderOptions(*job, *text);
    opt->octree = job->octree;
    opt->width = job->width;
    opt->height = job->height;
    opt->camera = job->camera;
    opt->azimuth = job->azimuth, opt->elevation = job->elevation, opt->fovYDegrees = job->fovYDegrees;
    opt->settings = job->settings;
    opt->budgets = job->budgets;
    opt->colour = job->colour;
    exitCode = viewer::runViewer(*opt);
  });
}

}  // namespace nestlight::cli
