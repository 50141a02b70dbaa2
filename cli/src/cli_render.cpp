// `nestlight render`: headless images of an octree (EGL; llvmpipe on machines without a GPU).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "cli.h"
#include "nestlight/frame/gpu_clip.h"
#include "nestlight/frame/picking.h"
#include "nestlight/frame/view_state.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/render_scene.h"
#include "nestlight/octree/crs.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/annotations.h"
#include "nestlight/viewer/headless.h"
#include "nestlight/viewer/image.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

std::vector<double> parseNumberList(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error(option + ": '" + item + "' is not a number");
    }
  }
  return v;
}

namespace {
std::vector<double> parseNumbers(const std::string& text, size_t n, const std::string& option) {
  std::vector<double> v = parseNumberList(text, option);
  if (v.size() != n)
    throw Error(option + ": expected " + std::to_string(n) + " comma-separated numbers");
  return v;
}
}  // namespace

// The output's folder is made before rendering (as convert and export make theirs), so that a
// long render never ends in "cannot write".
void makeOutputFolder(const fs::path& output) {
  const fs::path parent = output.parent_path();
  std::error_code ec;
  if (output.empty() || parent.empty() || fs::exists(parent, ec)) return;
  if (!fs::create_directories(parent, ec))
    throw Error(output.string(), "",
                "cannot create its folder " + parent.string() + ": " + ec.message());
}

// The options of octree renders, given with a scene file: those the real-time methods take become
// the scene's gi.parameters; the others, and any for a method that does not stream (the path
// tracer loads whole levels within each octree's memory_budget), are refused by name rather than
// ignored.
void applySceneScanOptions(const CLI::App& cmd, const std::string& file,
                           const viewer::RenderJob& job, const RenderOptionText& text,
                           gi::SceneRenderOverrides& sc) {
  auto given = [&](const char* o) { return cmd.count(o) > 0; };
  std::vector<std::string> notForScenes;
  for (const char* o : {"--camera", "--view", "--colour", "--layer", "--fixed-point-size", "--edl",
                        "--upload-budget", "--spacing-pixels", "--loaders", "--path", "--stats",
                        "--wait-complete", "--pick"})
    if (given(o)) notForScenes.push_back(o);
  if (!notForScenes.empty()) {
    std::string names;
    for (const auto& o : notForScenes) names += (names.empty() ? "" : ", ") + o;
    throw Error(names + (notForScenes.size() > 1 ? " do" : " does") +
                " not apply to a scene file, whose camera, camera path, scans and colours come "
                "from the file "
                "(docs/SCENE.md); they are options of octree renders");
  }
  // The PNG's exposure: wins over the scene's output.exposure and the automatic one.
  if (given("--exposure")) sc.exposure = double(job.settings.exposureStops);
  nlohmann::json p;
  if (given("--point-budget"))
    p["point_budget"] = double(parseCount(text.pointBudget, "--point-budget"));
  if (given("--gpu-budget"))
    p["gpu_budget_mb"] = double((parseBytes(text.gpuBudget) + (1u << 20) - 1) >> 20);
  if (given("--rasteriser")) p["rasteriser"] = text.rasteriser;
  if (given("--splatting")) p["splatting"] = text.splatting;
  if (given("--point-size")) p["splat_scale"] = job.settings.sizeScale;
  if (given("--timeout")) p["stream_timeout"] = job.timeoutSeconds;
  if (p.empty()) return;
  std::string method = sc.method.value_or("");
  if (method.empty()) {
    std::ifstream in(file);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    method = j.is_object() && j.contains("gi") && j["gi"].is_object() &&
                     j["gi"].contains("method") && j["gi"]["method"].is_string()
                 ? j["gi"]["method"].get<std::string>()
                 : "reference";
  }
  const gi::MethodInfo* info = gi::findMethod(method);
  if (info && !info->gpu)
    throw Error(
        p.begin().key() == "point_budget"
            ? std::string("--point-budget")
            : "--" + p.begin().key() + " (and the other streaming options)",
        "",
        "applies to the real-time (GL) methods; '" + method +
            "' loads whole levels of each octree within its \"memory_budget\" in the scene file");
  for (const auto& [k, v] : p.items()) sc.parameters[k] = v;
}

void addRenderOptions(CLI::App* cmd, viewer::RenderJob& job,
                      std::shared_ptr<RenderOptionText> text) {
  cmd->add_option("--width", job.width, "Width in pixels of the image (view: of the window)")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_option("--height", job.height, "Height in pixels of the image (view: of the window)")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_option(
      "--camera", text->camera,
      "Camera as EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z in world coordinates (z up); "
      "default: the whole scan seen from --view");
  cmd->add_option("--view", text->view, "Azimuth,elevation in degrees of the default camera")
      ->capture_default_str();
  cmd->add_option("--fov", job.fovYDegrees, "Vertical field of view, degrees")
      ->capture_default_str();
  cmd->add_option(
         "--rasteriser", text->rasteriser,
         "points: GL_POINTS splats sized by the measured point spacing; compute: compute-shader "
         "rasteriser (Schuetz et al. 2021), one pixel per point")
      ->capture_default_str();
  cmd->add_option(
         "--splatting", text->splatting,
         "Points rasteriser: hqs (high-quality splatting: splats within a small depth of the front "
         "surface blend, weighted; smooth colour and depth, about twice the cost) or basic (the "
         "nearest splat wins each pixel)")
      ->capture_default_str();
  cmd->add_option(
      "--colour", text->colour,
      "rgb, intensity, classification, elevation, normal or hdr (default: rgb when the scan has "
      "colour, else elevation). hdr: the scan's HDR colour layer (nestlight expand-hdr), drawn "
      "in linear colour: EXR files hold it whole (times 2^--exposure), PNG files show it through "
      "--exposure; eye-dome "
      "lighting is off unless --edl is given");
  cmd->add_option("--layer", job.colourLayer, "The colour layer --colour hdr draws")
      ->capture_default_str();
  cmd->add_option(
         "--exposure", job.settings.exposureStops,
         "Exposure in stops: colour times 2^stops before the PNG's clamp and sRGB curve. Scenes: "
         "the PNG only (the EXR stays linear and unscaled); given, it wins over the scene's "
         "output.exposure, and without either the PNG is exposed automatically: the 99th "
         "percentile of the lit pixels' luminance (finite, above black, Rec. 709) lands at 0.8, "
         "just below white (docs/SCENE.md). Octrees: 0 by default, no automatic exposure (scan "
         "colours are display colours already); with --colour hdr the EXR too is times 2^stops")
      ->capture_default_str()
      ->check(CLI::Range(-64.0, 64.0));
  cmd->add_option(
         "--point-size", job.settings.sizeScale,
         "Splat diameter in point spacings: the measured spacing of the finest drawn node at each "
         "point (points rasteriser)")
      ->capture_default_str();
  cmd->add_option("--fixed-point-size", job.settings.fixedPointSize,
                  "Every splat this many pixels (0: by spacing)");
  text->edl =
      cmd->add_option("--edl", job.settings.edlStrength, "Eye-dome lighting strength (0: off)")
          ->capture_default_str();
  cmd->add_option("--point-budget", text->pointBudget, "Points in the cut")->capture_default_str();
  cmd->add_option("--gpu-budget", text->gpuBudget, "GPU memory for resident nodes")
      ->capture_default_str();
  cmd->add_option("--upload-budget", text->uploadBudget, "Bytes uploaded per frame")
      ->capture_default_str();
  cmd->add_option("--spacing-pixels", job.budgets.spacingPixels,
                  "Refine until a node's point spacing projects to at most this many pixels")
      ->capture_default_str();
  cmd->add_option("--loaders", job.budgets.loaderThreads, "Loader threads")->capture_default_str();
  cmd->add_option("--state", text->state,
                  "View state JSON saved by the viewer (docs/VIEWER.md, \"Measurements and view "
                  "states\"): its camera, colouring, budgets, splatting, clipping volumes, "
                  "measurements and annotations (drawn over the image); options given here win "
                  "over it. For a scene file: its camera, GI method and parameters, clipping "
                  "volumes (added to every scan's), annotations and measurements");
  cmd->add_option("--clip", text->clip,
                  "Clipping volumes JSON (boxes, polygons, corridors; the file `export --clip` "
                  "reads): what they remove is hidden on the GPU and never loaded (a scene file: "
                  "added to every scan's octrees[].clipping)");
}

void applyViewState(viewer::RenderJob& job, const frame::ViewState& st,
                    const std::function<bool(const char*)>& given) {
  if (st.camera && !given("--camera")) {
    job.camera = *st.camera;
    if (given("--fov")) job.camera->fovYDegrees = job.fovYDegrees;
  }
  if (st.colour && !given("--colour")) job.colour = *st.colour;
  if (!given("--layer")) job.colourLayer = st.colourLayer;
  const streaming::Budgets& b = st.budgets;
  if (!given("--point-budget")) job.budgets.points = b.points;
  if (!given("--gpu-budget")) job.budgets.gpuBytes = b.gpuBytes;
  if (!given("--upload-budget")) job.budgets.uploadBytesPerFrame = b.uploadBytesPerFrame;
  if (!given("--loaders")) job.budgets.loaderThreads = b.loaderThreads;
  if (!given("--spacing-pixels")) job.budgets.spacingPixels = b.spacingPixels;
  const frame::RenderSettings& r = st.settings;
  frame::RenderSettings& o = job.settings;
  if (!given("--rasteriser")) o.rasteriser = r.rasteriser;
  if (!given("--splatting")) o.splatting = r.splatting;
  if (!given("--point-size")) o.sizeScale = r.sizeScale;
  if (!given("--fixed-point-size") && !given("--rasteriser")) o.fixedPointSize = r.fixedPointSize;
  if (!given("--edl")) o.edlStrength = r.edlStrength;
  if (!given("--exposure")) o.exposureStops = r.exposureStops;
  o.minPointSize = r.minPointSize, o.maxPointSize = r.maxPointSize;
  o.roundPoints = r.roundPoints, o.edlRadius = r.edlRadius, o.background = r.background;
  if (!st.clipping.empty()) o.clip = std::make_shared<const ClipSet>(st.clipping);
  job.annotations = st.annotations;
  job.measurements = st.measurements;
}

void applyViewStateOptions(viewer::RenderJob& job, const RenderOptionText& text,
                           const std::function<bool(const char*)>& given) {
  if (!text.state.empty()) {
    requireExists(text.state);
    const frame::ViewState st = frame::ViewState::load(text.state);
    const std::string warning = st.boundsWarning(OctreeReader(job.octree).metadata().bounds);
    if (!warning.empty())
      std::fprintf(stderr, "%s: warning: %s\n", text.state.c_str(), warning.c_str());
    applyViewState(job, st, given);
  }
  if (!text.clip.empty()) {
    requireExists(text.clip);
    job.settings.clip = std::make_shared<const ClipSet>(ClipSet::load(text.clip));
  }
  // What the GPU draws at most: refused here, before any work, rather than clipped wrongly.
  if (job.settings.clip) frame::encodeClipBlock(*job.settings.clip, Vec3d{});
}

std::optional<frame::ViewState> applyViewStateToScene(const std::string& sceneFile,
                                                      const RenderOptionText& text,
                                                      const std::function<bool(const char*)>& given,
                                                      gi::SceneRenderOverrides& sc) {
  std::optional<frame::ViewState> state;
  if (!text.state.empty()) {
    requireExists(text.state);
    state = frame::ViewState::load(text.state);
    const frame::ViewState& st = *state;
    Box3d bounds;
    for (const gi::SceneOctree& o : gi::loadScene(sceneFile).octrees)
      bounds.extend(OctreeReader(o.path).metadata().bounds);
    const std::string warning = bounds.empty() ? "" : st.boundsWarning(bounds);
    if (!warning.empty())
      std::fprintf(stderr, "%s: warning: %s\n", text.state.c_str(), warning.c_str());
    if (st.camera) {
      sc.camera = gi::SceneRenderOverrides::Pose{st.camera->eye, st.camera->target, st.camera->up};
      if (!given("--fov")) sc.fov = st.camera->fovYDegrees;
    }
    if (st.gi.is_object() && st.gi.contains("method")) {
      const std::string method = st.gi["method"].get<std::string>();
      if (!gi::findMethod(method))
        throw Error(text.state, "gi.method", "unknown method '" + method + "'");
      if (!sc.method) sc.method = method;
      // Its parameters are that method's: another one given on the command line leaves them.
      if (*sc.method == method && st.gi.contains("parameters"))
        for (const auto& [k, v] : st.gi["parameters"].items())
          if (!sc.parameters.contains(k)) sc.parameters[k] = v;
    }
    sc.clipping.volumes.insert(sc.clipping.volumes.end(), st.clipping.volumes.begin(),
                               st.clipping.volumes.end());
  }
  if (!text.clip.empty()) {
    requireExists(text.clip);
    const ClipSet c = ClipSet::load(text.clip);
    sc.clipping.volumes.insert(sc.clipping.volumes.end(), c.volumes.begin(), c.volumes.end());
  }
  return state;
}

void applyRenderOptions(viewer::RenderJob& job, const RenderOptionText& text) {
  if (!text.camera.empty()) {
    auto v = parseNumbers(text.camera, 6, "--camera");
    frame::Camera c;
    c.eye = {v[0], v[1], v[2]};
    c.target = {v[3], v[4], v[5]};
    if (glm::length(c.eye - c.target) <= 0) throw Error("--camera: eye and target coincide");
    c.fovYDegrees = job.fovYDegrees;
    job.camera = c;
  }
  auto view = parseNumbers(text.view, 2, "--view");
  job.azimuth = view[0], job.elevation = view[1];
  job.settings.rasteriser = frame::parseRasteriser(text.rasteriser);
  job.settings.splatting = frame::parseSplatting(text.splatting);
  if (!text.colour.empty()) job.colour = frame::parseColourMode(text.colour);
  if (job.colour == frame::ColourMode::Hdr && text.edl && text.edl->count() == 0)
    job.settings.edlStrength = 0;
  job.budgets.points = parseCount(text.pointBudget, "--point-budget");
  job.budgets.gpuBytes = parseBytes(text.gpuBudget);
  job.budgets.uploadBytesPerFrame = parseBytes(text.uploadBudget);
  if (job.settings.rasteriser == frame::Rasteriser::Compute) job.settings.fixedPointSize = 1;
}

namespace {

// A view state's annotations and measurements over a scene's still PNG (the EXR stays the
// method's radiance alone), projected through the scene's camera; units from its first scan.
void overlaySceneImage(const gi::SceneRenderReport& rep, const frame::ViewState& st) {
  if (st.annotations.empty() && st.measurements.empty()) return;
  const fs::path png = rep.scene.output.png;
  if (rep.frames != 1 || png.empty() || !fs::exists(png)) {
    std::fprintf(stderr,
                 "render: the state's annotations and measurements are drawn over a still's PNG "
                 "only (the scene writes %s)\n",
                 png.empty() ? "no PNG" : "one per frame");
    return;
  }
  frame::Camera camera;
  camera.eye = rep.scene.camera.eye;
  camera.target = rep.scene.camera.target;
  camera.up = rep.scene.camera.up;
  camera.fovYDegrees = rep.scene.camera.fovYDegrees;
  std::string unit = "m";
  if (!rep.scene.octrees.empty()) {
    const OctreeReader reader(rep.scene.octrees.front().path);
    unit = describeCrs(reader.metadata().crs).unitSymbol();
  }
  viewer::Image image = viewer::readImage(png.string());
  viewer::drawMeasurements(image, camera, st.measurements, unit);
  viewer::drawAnnotations(image, camera, st.annotations);
  viewer::writeImage(image, png.string());
}

// `render --help`: every registered method, with the choices of the flags it declares, from the
// registry (gi/methods), so that the list cannot fall behind it.
std::string renderDescription() {
  std::string s =
      "Render an octree headless to PNG or EXR (EGL: an NVIDIA GPU, or Mesa's llvmpipe on the "
      "CPU).\n"
      "A still by default; --path renders a camera path (JSON keyframes) to an image sequence.\n"
      "Example: nestlight render scan.octree -o view.png --width 1920 --height 1080 "
      "--wait-complete\n\n"
      "Given a scene file (.json, docs/SCENE.md) it renders the scene's GI instead, to linear EXR "
      "(and the\n"
      "scene's PNG), with the method the scene's gi.method or --method names:\n";
  size_t width = 0;
  for (const auto& m : gi::registeredMethods()) width = std::max(width, m.name.size());
  for (const auto& m : gi::registeredMethods()) {
    s += "  " + m.name + std::string(width + 2 - m.name.size(), ' ') + m.summary;
    for (const auto& p : m.parameters)
      if (p.flag && p.type == gi::ParameterType::Choice && !p.choices.empty()) {
        std::string dashed = p.name;
        std::replace(dashed.begin(), dashed.end(), '_', '-');
        std::string choices;
        for (const auto& c : p.choices) choices += (choices.empty() ? "" : "|") + c;
        s += "; --" + dashed + " " + choices;
      }
    s += "\n";
  }
  s += "The path tracer (reference, direct) refines until --target-error, --time-limit or the "
       "sample cap\n"
       "(--spp, else the scene's gi.samples_per_pixel, default 256), whichever comes first; a "
       "--time-limit\n"
       "given without --spp lifts the cap, so that the time limit decides.\n"
       "Example: nestlight render cornell/scene.json --target-error 0.01 -o cornell.exr\n"
       "         nestlight render cornell/scene.json --method raster -o cornell-raster.exr";
  return s;
}

}  // namespace

void addRender(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("render", renderDescription());
  auto job = std::make_shared<viewer::RenderJob>();
  auto text = std::make_shared<RenderOptionText>();
  auto octree = std::make_shared<std::string>();
  auto path = std::make_shared<std::string>();
  cmd->add_option("input", *octree,
                  "Octree folder made by `nestlight convert`, or a scene file (.json)")
      ->required();
  cmd->add_option("-o,--output", job->output,
                  "Image file (.png or .exr); with --path a pattern with %04d. Scenes: .exr, "
                  "default from the scene");
  cmd->add_option("--path", *path,
                  "Camera path JSON: {\"fps\": 30, \"fov\": 60, \"keyframes\": "
                  "[{\"time\": 0, \"eye\": [x,y,z], \"target\": [x,y,z]}, ...]}");
  cmd->add_option("--stats", job->statsCsv,
                  "Per-frame stats CSV (cut, resident bytes, loads, timings)");
  cmd->add_flag("--wait-complete", job->waitComplete,
                "Render each frame only once its cut is fully loaded (deterministic images)");
  cmd->add_option("--timeout", job->timeoutSeconds, "Seconds to wait for a complete cut")
      ->capture_default_str();
  auto picks = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--pick", *picks,
                  "Print the scan point under pixel X,Y of the still (column, row from the "
                  "top-left): its coordinates in the scan's system to the scan's precision, its "
                  "node and attributes; repeatable. The nearest point to the pixel's centre on "
                  "the front surface within --pick-radius pixels; nothing over background");
  cmd->add_option("--pick-radius", job->pickRadius, "Picking's search window, pixels each side")
      ->capture_default_str()
      ->check(CLI::Range(0, 64));
  addRenderOptions(cmd, *job, text);
  cmd->get_option("--width")->description(
      "Image width in pixels, up to 16384 (large octree images render in tiles)");
  cmd->get_option("--height")->description("Image height in pixels, up to 16384");
  auto sc = std::make_shared<gi::SceneRenderOverrides>();
  auto methodText = std::make_shared<SceneMethodText>();
  std::string group = "Scene files";
  addSceneMethodOptions(cmd, *sc, *methodText, group);
  cmd->add_option(
         "--target-error", sc->targetError,
         "Scenes: stop when the estimated relative error (two half-sample images) falls below")
      ->check(CLI::Range(0.0, 1.0))
      ->group(group);
  cmd->add_option("--time-limit", sc->timeLimit,
                  "Scenes: stop after this many seconds; without --spp the scene's sample cap "
                  "(gi.samples_per_pixel) is lifted, so the time limit decides")
      ->check(CLI::Range(0.0, 1e7))
      ->group(group);
  addSceneBounceOptions(cmd, *sc, group);
  cmd->add_flag("--still", sc->still,
                "Scenes: one image from the scene's camera even when it has a camera path or an "
                "environment sequence (each renders one image per frame, NAME_0000.exr, ...; "
                "a sequence's frame follows each image's time)")
      ->group(group);
  cmd->callback([=, &exitCode]() {
    requireExists(*octree);  // a typo names the near file in its folder
    if (fs::path(*octree).extension() == ".json" && !fs::is_directory(*octree)) {
      if (cmd->count("--width")) sc->width = job->width;
      if (cmd->count("--height")) sc->height = job->height;
      if (cmd->count("--fov")) {
        if (!(job->fovYDegrees >= 0.01 && job->fovYDegrees <= 179))
          throw Error("--fov: expected degrees in [0.01, 179]");
        sc->fov = job->fovYDegrees;
      }
      applySceneMethodOptions(*methodText, *sc);
      applySceneScanOptions(*cmd, *octree, *job, *text, *sc);
      const std::optional<frame::ViewState> state = applyViewStateToScene(
          *octree, *text, [cmd](const char* o) { return cmd->count(o) > 0; }, *sc);
      makeOutputFolder(job->output);
      sc->output = job->output;
      // An explicit --time-limit wins over the scene's sample cap: without --spp the cap is
      // lifted to the most --spp takes, and the time limit (or --target-error) stops the render.
      const bool capLifted = sc->timeLimit && *sc->timeLimit > 0 && !sc->spp;  // 0: no limit
      if (capLifted) sc->spp = 1 << 24;
      const gi::SceneRenderReport rep = gi::renderSceneFile(*octree, *sc);
      if (state) overlaySceneImage(rep, *state);
      // Say when a limit given on the command line did not decide.
      const bool timeLimit = sc->timeLimit && *sc->timeLimit > 0;
      if (rep.result.stopReason == "samples" &&
          (timeLimit || (sc->targetError && *sc->targetError > 0)))
        std::printf("render: the sample cap stopped it at %d spp (%s), before %s did\n",
                    rep.result.samplesPerPixel,
                    capLifted ? "the most --spp takes"
                    : sc->spp
                        ? "--spp"
                        : "the scene's gi.samples_per_pixel, default 256; raise it with --spp",
                    timeLimit ? "--time-limit" : "--target-error");
      exitCode = 0;
      return;
    }
    requireOctreeFolder(*octree, "render");
    if (job->output.empty())
      throw Error("render: -o/--output is required for an octree (a PNG or EXR file)");
    makeOutputFolder(job->output);
    job->octree = *octree;
    applyRenderOptions(*job, *text);
    applyViewStateOptions(*job, *text, [cmd](const char* o) { return cmd->count(o) > 0; });
    if (!path->empty()) job->path = gi::loadCameraPath(*path);
    if (!picks->empty() && job->path) throw Error("--pick: picks in a still, not with --path");
    for (const std::string& p : *picks) {
      const std::vector<double> v = parseNumbers(p, 2, "--pick");
      if (v[0] < 0 || v[1] < 0 || v[0] >= job->width || v[1] >= job->height)
        throw Error("--pick " + p + ": the pixel lies outside the " + std::to_string(job->width) +
                    "x" + std::to_string(job->height) + " image");
      job->picks.push_back({v[0], v[1]});
    }
    auto frames = viewer::renderHeadless(*job);
    if (!frames.empty() && !job->picks.empty()) {
      const OctreeReader reader(job->octree);  // alive while `meta` is read
      const Metadata& meta = reader.metadata();
      const CrsInfo crs = describeCrs(meta.crs);
      const std::string unit = " " + crs.unitSymbol();
      if (crs.known) std::printf("pick: coordinates in %s\n", crs.summary().c_str());
      for (size_t i = 0; i < job->picks.size(); ++i) {
        const auto& pick = frames.front().picks[i];
        std::printf("pick %s: ", (*picks)[i].c_str());
        if (!pick) {
          std::printf("nothing (background within %d px)\n", job->pickRadius);
          continue;
        }
        std::printf("%s%s  (node %s, point %u; %.2f px from the pixel's centre, %.6g%s away)\n",
                    pick->coordinates(meta.scale).c_str(), unit.c_str(), pick->node.name().c_str(),
                    pick->index, pick->pixelDistance, pick->depth, unit.c_str());
        const std::string attrs = frame::describeAttributes(pick->attributes);
        if (!attrs.empty()) std::printf("  %s\n", attrs.c_str());
      }
    }
    bool complete = true;
    for (auto& f : frames) complete = complete && f.complete;
    if (!complete && !job->waitComplete)
      std::printf(
          "render: some frames were drawn before their cut was complete; --wait-complete waits\n");
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
