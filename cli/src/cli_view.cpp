// `nestlight view`: the interactive viewer.
#include <functional>
#include <memory>

#include "cli.h"
#include "nestlight/gi/scene.h"
#include "nestlight/octree/error.h"
#include "nestlight/viewer/window_app.h"

namespace nestlight::cli {

namespace {
// A scene file opens its first scan with the scene's camera and display settings (docs/SCENE.md);
// what the command line says explicitly wins over the file (`given`: an option was on it).
void applyScene(const std::filesystem::path& file, viewer::ViewerOptions& opt,
                const std::function<bool(const char*)>& given) {
  const gi::Scene scene = gi::loadScene(file);
  if (scene.octrees.empty()) throw Error(file.string(), "scene.octrees", "the viewer needs a scan to show");
  opt.octree = scene.octrees.front().path;
  if (scene.cameraSet && !given("--camera")) {
    viewer::Camera c;
    c.eye = scene.camera.eye;
    c.target = scene.camera.target;
    c.up = scene.camera.up;
    c.fovYDegrees = scene.camera.fovYDegrees;
    opt.camera = c;
  }
  const gi::SceneDisplay& d = scene.display;
  if (d.rasteriser && !given("--rasteriser")) {
    opt.settings.rasteriser = viewer::parseRasteriser(*d.rasteriser);
    if (!given("--fixed-point-size"))
      opt.settings.fixedPointSize = opt.settings.rasteriser == viewer::Rasteriser::Compute ? 1.f : 0.f;
  }
  if (d.splatting && !given("--splatting")) opt.settings.splatting = viewer::parseSplatting(*d.splatting);
  if (d.pointSize && !given("--point-size")) opt.settings.sizeScale = *d.pointSize;
  if (d.edlStrength && !given("--edl")) opt.settings.edlStrength = *d.edlStrength;
}
}  // namespace

void addView(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "view",
      "Open an octree (or a scene file's first scan, with the scene's camera and \"display\" settings) "
      "in a window and fly through it; nodes stream in under the budgets.\n"
      "Orbit: drag (rotate), middle-drag (pan), wheel (zoom). Fly: WASD, Q/E down/up, shift faster.\n"
      "The panel sets rasteriser, splatting, colouring, point size, eye-dome lighting and budgets, and takes "
      "screenshots.");
  auto opt = std::make_shared<viewer::ViewerOptions>();
  auto job = std::make_shared<viewer::RenderJob>();
  auto text = std::make_shared<RenderOptionText>();
  auto input = std::make_shared<std::string>();
  cmd->add_option("input", *input, "Octree folder made by `nestlight convert`, or a scene file (.json)")->required();
  cmd->add_option("--frames", opt->frames, "Close after this many frames (scripted runs; 0: when closed)");
  cmd->add_option("--orbit", opt->orbitDegreesPerFrame, "Turn the camera by this many degrees per frame");
  cmd->add_option("--screenshot", opt->screenshot, "Save the last frame to this PNG/EXR (with --frames)");
  addRenderOptions(cmd, *job, text);
  cmd->callback([=, &exitCode]() {
    job->octree = *input;
    applyRenderOptions(*job, *text);
    opt->octree = job->octree;
    opt->width = job->width;
    opt->height = job->height;
    opt->camera = job->camera;
    opt->azimuth = job->azimuth, opt->elevation = job->elevation, opt->fovYDegrees = job->fovYDegrees;
    opt->settings = job->settings;
    opt->budgets = job->budgets;
    opt->colour = job->colour;
    if (std::filesystem::path(*input).extension() == ".json")
      applyScene(*input, *opt, [cmd](const char* name) { return cmd->count(name) > 0; });
    exitCode = viewer::runViewer(*opt);
  });
}

}  // namespace nestlight::cli
