// `nestlight view`: the interactive viewer.
#include <algorithm>
#include <cstdio>
#include <functional>
#include <memory>

#include "cli.h"
#include "nestlight/gi/method_parameters.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/scene_overrides.h"
#include "nestlight/octree/error.h"
#include "nestlight/viewer/window_app.h"

namespace nestlight::cli {

namespace {
// A scene file opens its first scan with the scene's camera and display settings (docs/SCENE.md);
// what the command line says explicitly wins over the file (`given`: an option was on it).
void applyScene(const std::filesystem::path& file, viewer::ViewerOptions& opt,
                const std::function<bool(const char*)>& given,
                const gi::SceneRenderOverrides& overrides) {
  auto loaded = std::make_shared<gi::Scene>(gi::loadScene(file));
  gi::checkSceneMethod(*loaded);  // the registry names the methods, not the scene parser
  // --method, --variant, --param, ...: as `render` takes them, checked before a window opens.
  gi::applySceneOverrides(*loaded, overrides);
  const gi::MethodInfo& info = *gi::findMethod(loaded->gi.method);
  if (!info.parameters.empty()) gi::resolveParameters(*loaded, info.parameters);
  const gi::Scene& scene = *loaded;
  opt.scene = loaded;
  // A scene of meshes alone is viewed through its GI method; there is no point view.
  if (scene.octrees.empty()) {
    if (given("--show") && opt.startWithPoints)
      throw Error(file.string(), "scene.octrees",
                  "--show points: the scene has no scan to show as points");
    opt.octree.clear();
  } else {
    opt.octree = scene.octrees.front().path;
    // Its points view hides what the GI frame does not see (the scene's and --clip's volumes).
    if (!scene.octrees.front().clipping.empty())
      opt.settings.clip = std::make_shared<const ClipSet>(scene.octrees.front().clipping);
  }
  if (scene.cameraSet && !given("--camera")) {
    frame::Camera c;
    c.eye = scene.camera.eye;
    c.target = scene.camera.target;
    c.up = scene.camera.up;
    c.fovYDegrees = scene.camera.fovYDegrees;
    opt.camera = c;
  }
  const gi::SceneDisplay& d = scene.display;
  if (d.rasteriser && !given("--rasteriser")) {
    opt.settings.rasteriser = frame::parseRasteriser(*d.rasteriser);
    if (!given("--fixed-point-size"))
      opt.settings.fixedPointSize =
          opt.settings.rasteriser == frame::Rasteriser::Compute ? 1.f : 0.f;
  }
  if (d.splatting && !given("--splatting"))
    opt.settings.splatting = frame::parseSplatting(*d.splatting);
  if (d.pointSize && !given("--point-size")) opt.settings.sizeScale = *d.pointSize;
  if (d.edlStrength && !given("--edl")) opt.settings.edlStrength = *d.edlStrength;
}

// --dry-run: the method and the parameters the window would open with, as the method resolves
// them (defaults included).
void printView(const viewer::ViewerOptions& opt) {
  if (!opt.scene) {
    std::printf("view: %s: points\n", opt.octree.c_str());
    return;
  }
  const gi::Scene& s = *opt.scene;
  const gi::MethodInfo& info = *gi::findMethod(s.gi.method);
  std::printf("view: %s: method %s, %s mode, %d bounces, %d samples per pixel at most%s\n",
              s.file.c_str(), s.gi.method.c_str(),
              s.gi.mode == gi::RadianceMode::Albedo ? "albedo" : "radiance_cache", s.gi.maxBounces,
              s.gi.samplesPerPixel, opt.startWithPoints ? "; opens on the points" : "");
  if (!info.parameters.empty())
    std::printf("view: parameters %s\n",
                gi::resolveParameters(s, info.parameters).values().dump().c_str());
}
}  // namespace

void addView(CLI::App& app, int& exitCode) {
  auto* cmd =
      app.add_subcommand("view",
                         "Open an octree in a window and fly through it; nodes stream in under the "
                         "budgets. Given a scene file,\n"
                         "the scene is lit by its gi.method or --method: the GL methods in real "
                         "time through the GI frame, the\n"
                         "path tracer (reference, direct) progressively, accumulating while the "
                         "camera rests. The panel switches\n"
                         "between every registered method, variant and parameter live; the "
                         "scene's first\n"
                         "scan is also shown as points with its camera and \"display\" settings. A "
                         "scene of meshes alone is shown\n"
                         "through its GI method, framed by the meshes when it has no camera.\n"
                         "Orbit: drag (rotate), middle-drag (pan), wheel (zoom). Fly: WASD, Q/E "
                         "down/up, shift faster.\n"
                         "The panel sets rasteriser, splatting, colouring, point size, eye-dome "
                         "lighting and budgets, and takes "
                         "screenshots.");
  auto opt = std::make_shared<viewer::ViewerOptions>();
  auto job = std::make_shared<viewer::RenderJob>();
  auto text = std::make_shared<RenderOptionText>();
  auto input = std::make_shared<std::string>();
  cmd->add_option("input", *input,
                  "Octree folder made by `nestlight convert`, or a scene file (.json)")
      ->required();
  cmd->add_option("--frames", opt->frames,
                  "Close after this many frames (scripted runs; 0: when closed)");
  cmd->add_option("--orbit", opt->orbitDegreesPerFrame,
                  "Turn the camera by this many degrees per frame");
  cmd->add_option("--screenshot", opt->screenshot,
                  "Save the last frame to this PNG/EXR (with --frames; the path tracer's "
                  "progressive view once it holds --spp samples per pixel)");
  auto show = std::make_shared<std::string>("gi");
  cmd->add_option("--show", *show,
                  "Scene files: open on the GI method's frame (gi) or the scan's points (points)")
      ->check(CLI::IsMember({"gi", "points"}))
      ->capture_default_str();
  addRenderOptions(cmd, *job, text);
  cmd->add_option("--tool", opt->tool,
                  "The tool a click uses: pick, distance, polyline, area, height, angle, "
                  "annotate, clip-polygon, profile (the panel's \"tools\" section chooses it too)");
  auto clicks = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--click", *clicks,
                  "Scripted click at pixel X,Y with --tool, once the view's cut is loaded; "
                  "repeatable, one per frame (tests and reproducible figures; with --frames)");
  cmd->add_option("--save-state", opt->saveState,
                  "Save the view state (camera, colouring, budgets, splatting, clipping, "
                  "measurements, annotations; for a scene file the GI method and parameters the "
                  "panel shows) to this JSON after the last frame, as Ctrl+S and the panel's "
                  "button do");
  // The method and its settings, as `render` takes them (the panel changes them live).
  auto sc = std::make_shared<gi::SceneRenderOverrides>();
  auto methodText = std::make_shared<SceneMethodText>();
  const std::string group = "Scene files";
  addSceneMethodOptions(cmd, *sc, *methodText, group);
  addSceneBounceOptions(cmd, *sc, group);
  auto dryRun = std::make_shared<bool>(false);
  cmd->add_flag("--dry-run", *dryRun,
                "Check the input and the options, print the method and parameters the window "
                "would open with, and exit without opening one");
  cmd->callback([=, &exitCode]() {
    // A missing input names a near file; a scan file, the convert command for it.
    if (std::filesystem::path(*input).extension() == ".json")
      requireExists(*input);
    else
      requireOctreeFolder(*input, "view");
    job->octree = *input;
    applyRenderOptions(*job, *text);
    const auto given = [cmd](const char* o) { return cmd->count(o) > 0; };
    if (std::filesystem::path(*input).extension() == ".json") {
      // The state's camera, method, parameters and clipping go into the scene; its colouring,
      // budgets, splatting, annotations and measurements into the points view of its first scan.
      applySceneMethodOptions(*methodText, *sc);
      const std::optional<frame::ViewState> state =
          applyViewStateToScene(*input, *text, given, *sc);
      if (state) applyViewState(*job, *state, given);
    } else {
      applyViewStateOptions(*job, *text, given);
    }
    opt->octree = job->octree;
    opt->width = job->width;
    opt->height = job->height;
    opt->camera = job->camera;
    opt->azimuth = job->azimuth, opt->elevation = job->elevation,
    opt->fovYDegrees = job->fovYDegrees;
    opt->settings = job->settings;
    opt->budgets = job->budgets;
    opt->colour = job->colour;
    opt->colourLayer = job->colourLayer;
    opt->annotations = job->annotations;
    opt->measurements = job->measurements;
    for (const std::string& c : *clicks) {
      const std::vector<double> v = parseNumberList(c, "--click");
      if (v.size() != 2 || v[0] < 0 || v[1] < 0 || v[0] >= job->width || v[1] >= job->height)
        throw Error("--click " + c + ": expected X,Y, a pixel of the " +
                    std::to_string(job->width) + "x" + std::to_string(job->height) + " window");
      opt->clicks.push_back({v[0], v[1]});
    }
    if (!opt->tool.empty()) {
      const auto names = viewer::toolNames();
      if (std::find(names.begin(), names.end(), opt->tool) == names.end())
        throw Error("--tool: unknown tool '" + opt->tool + "'");
    }
    opt->stateFile = text->state;
    opt->startWithPoints = *show == "points";
    if (std::filesystem::path(*input).extension() == ".json") {
      applyScene(*input, *opt, given, *sc);
    } else {
      for (const CLI::Option* o : cmd->get_options())
        if (o->get_group() == group && o->count() > 0)
          throw Error(o->get_name() + ": applies to scene files (.json), whose GI method it sets");
    }
    if (*dryRun) {
      printView(*opt);
      exitCode = 0;
      return;
    }
    exitCode = viewer::runViewer(*opt);
  });
}

}  // namespace nestlight::cli
