// `nestlight render`: headless images of an octree (EGL; llvmpipe on machines without a GPU).
#include <cstdio>
#include <memory>
#include <sstream>

#include "cli.h"
#include "nestlight/octree/error.h"
#include "nestlight/viewer/headless.h"

namespace nestlight::cli {

namespace {
std::vector<double> parseNumbers(const std::string& text, size_t n, const std::string& option) {
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
  if (v.size() != n) throw Error(option + ": expected " + std::to_string(n) + " comma-separated numbers");
  return v;
}
}  // namespace

void addRenderOptions(CLI::App* cmd, viewer::RenderJob& job, std::shared_ptr<RenderOptionText> text) {
  cmd->add_option("--width", job.width, "Image width in pixels (up to 16384; large images render in tiles)")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_option("--height", job.height, "Image height in pixels")->capture_default_str()->check(CLI::Range(1, 16384));
  cmd->add_option("--camera", text->camera,
                  "Camera as EYE_X,EYE_Y,EYE_Z,TARGET_X,TARGET_Y,TARGET_Z in world coordinates (z up); "
                  "default: the whole scan seen from --view");
  cmd->add_option("--view", text->view, "Azimuth,elevation in degrees of the default camera")->capture_default_str();
  cmd->add_option("--fov", job.fovYDegrees, "Vertical field of view, degrees")->capture_default_str();
  cmd->add_option("--rasteriser", text->rasteriser,
                  "points: GL_POINTS splats sized by node spacing; compute: compute-shader rasteriser "
                  "(Schuetz et al. 2021), one pixel per point")
      ->capture_default_str();
  cmd->add_option("--colour", text->colour, "rgb, intensity, classification, elevation or normal (default: rgb "
                                            "when the scan has colour, else elevation)");
  cmd->add_option("--point-size", job.settings.sizeScale, "Splat diameter in node spacings (points rasteriser)")
      ->capture_default_str();
  cmd->add_option("--fixed-point-size", job.settings.fixedPointSize, "Every splat this many pixels (0: by spacing)");
  cmd->add_option("--edl", job.settings.edlStrength, "Eye-dome lighting strength (0: off)")->capture_default_str();
  cmd->add_option("--point-budget", text->pointBudget, "Points in the cut")->capture_default_str();
  cmd->add_option("--gpu-budget", text->gpuBudget, "GPU memory for resident nodes")->capture_default_str();
  cmd->add_option("--upload-budget", text->uploadBudget, "Bytes uploaded per frame")->capture_default_str();
  cmd->add_option("--spacing-pixels", job.budgets.spacingPixels,
                  "Refine until a node's point spacing projects to at most this many pixels")
      ->capture_default_str();
  cmd->add_option("--loaders", job.budgets.loaderThreads, "Loader threads")->capture_default_str();
}

void applyRenderOptions(viewer::RenderJob& job, const RenderOptionText& text) {
  if (!text.camera.empty()) {
    auto v = parseNumbers(text.camera, 6, "--camera");
    viewer::Camera c;
    c.eye = {v[0], v[1], v[2]};
    c.target = {v[3], v[4], v[5]};
    if (glm::length(c.eye - c.target) <= 0) throw Error("--camera: eye and target coincide");
    c.fovYDegrees = job.fovYDegrees;
    job.camera = c;
  }
  auto view = parseNumbers(text.view, 2, "--view");
  job.azimuth = view[0], job.elevation = view[1];
  job.settings.rasteriser = viewer::parseRasteriser(text.rasteriser);
  if (!text.colour.empty()) job.colour = viewer::parseColourMode(text.colour);
  job.budgets.points = parseCount(text.pointBudget, "--point-budget");
  job.budgets.gpuBytes = parseBytes(text.gpuBudget);
  job.budgets.uploadBytesPerFrame = parseBytes(text.uploadBudget);
  if (job.settings.rasteriser == viewer::Rasteriser::Compute) job.settings.fixedPointSize = 1;
}

void addRender(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "render",
      "Render an octree headless to PNG or EXR (EGL: an NVIDIA GPU, or Mesa's llvmpipe on the CPU).\n"
      "A still by default; --path renders a camera path (JSON keyframes) to an image sequence.\n"
      "Example: nestlight render scan.octree -o view.png --width 1920 --height 1080 --wait-complete");
  auto job = std::make_shared<viewer::RenderJob>();
  auto text = std::make_shared<RenderOptionText>();
  auto octree = std::make_shared<std::string>();
  auto path = std::make_shared<std::string>();
  cmd->add_option("octree", *octree, "Octree folder made by `nestlight convert`")->required();
  cmd->add_option("-o,--output", job->output, "Image file (.png or .exr); with --path a pattern with %04d")
      ->required();
  cmd->add_option("--path", *path, "Camera path JSON: {\"fps\": 30, \"fov\": 60, \"keyframes\": "
                                   "[{\"time\": 0, \"eye\": [x,y,z], \"target\": [x,y,z]}, ...]}");
  cmd->add_option("--stats", job->statsCsv, "Per-frame stats CSV (cut, resident bytes, loads, timings)");
  cmd->add_flag("--wait-complete", job->waitComplete,
                "Render each frame only once its cut is fully loaded (deterministic images)");
  cmd->add_option("--timeout", job->timeoutSeconds, "Seconds to wait for a complete cut")->capture_default_str();
  addRenderOptions(cmd, *job, text);
  cmd->callback([=, &exitCode]() {
    job->octree = *octree;
    applyRenderOptions(*job, *text);
    if (!path->empty()) job->path = viewer::CameraPath::load(*path);
    auto frames = viewer::renderHeadless(*job);
    bool complete = true;
    for (auto& f : frames) complete = complete && f.complete;
    if (!complete && !job->waitComplete)
      std::printf("render: some frames were drawn before their cut was complete; --wait-complete waits\n");
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
