// `nestlight make-scene` (the project's GI test scenes) and `nestlight render scene.json` (the
// path-traced reference, or direct lighting, of a scene file).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "cli_scene.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;

namespace {
void logLine(const std::string& line) { std::fprintf(stderr, "  %s\n", line.c_str()); }
}  // namespace

void addMakeScene(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "make-scene",
      "Generate a GI test scene: a synthetic scan converted into DIR/scan.octree, inserted meshes\n"
      "(OBJ) and DIR/scene.json for `nestlight render` and `nestlight bench gi`.\n"
      "  cornell  a closed 4 m room of coloured walls (a Cornell-box-like scan) with a glossy sphere\n"
      "  nave     a 40 m nave with two colonnades and a marble statue on a pedestal\n"
      "  object   the synthetic town scan with a gold torus, under a sky and a sun (albedo mode)\n"
      "Example: nestlight make-scene cornell -o cornell && nestlight render cornell/scene.json");
  auto kind = std::make_shared<std::string>();
  auto dir = std::make_shared<std::string>();
  auto opt = std::make_shared<TestSceneOptions>();
  auto points = std::make_shared<std::string>("1M");
  cmd->add_option("kind", *kind, "cornell, nave or object")->required()->check(CLI::IsMember({"cornell", "nave", "object"}));
  cmd->add_option("-o,--output", *dir, "Folder to write (created)")->required();
  cmd->add_option("-n,--points", *points, "Points in the scan (e.g. 200k, 2M)")->capture_default_str();
  cmd->add_option("--seed", opt->seed, "Seed of the synthetic scan")->capture_default_str();
  cmd->add_option("--width", opt->width, "Image width in the scene's camera")->capture_default_str()->check(CLI::Range(1, 16384));
  cmd->add_option("--height", opt->height, "Image height")->capture_default_str()->check(CLI::Range(1, 16384));
  cmd->add_flag("--overwrite", opt->overwrite, "Rebuild the octree even when one is there");
  cmd->add_flag("-q,--quiet", opt->quiet, "No progress output");
  cmd->callback([=, &exitCode]() {
    opt->points = parseCount(*points, "--points");
    fs::path file = makeTestScene(*parseTestSceneKind(*kind), *dir, *opt);
    std::printf("make-scene: wrote %s\n", file.c_str());
    exitCode = 0;
  });
}

SceneRenderReport renderSceneFile(const fs::path& file, const SceneRenderOverrides& ov) {
  auto t0 = std::chrono::steady_clock::now();
  gi::Scene scene = gi::loadScene(file);
  if (ov.width) scene.camera.width = *ov.width;
  if (ov.height) scene.camera.height = *ov.height;
  if (ov.fov) scene.camera.fovYDegrees = *ov.fov;
  if (ov.method) scene.gi.method = *ov.method;
  if (ov.mode) scene.gi.mode = *ov.mode;
  if (ov.bounces) scene.gi.maxBounces = *ov.bounces;
  if (ov.spp) scene.gi.samplesPerPixel = *ov.spp;
  if (ov.targetError) scene.gi.targetRelativeError = *ov.targetError;
  if (ov.timeLimit) scene.gi.timeLimitSeconds = *ov.timeLimit;
  if (ov.seed) scene.gi.seed = *ov.seed;
  if (!ov.output.empty()) scene.output.exr = ov.output;
  if (scene.output.exr.empty()) scene.output.exr = file.parent_path() / (file.stem().string() + ".exr");
  if (scene.output.exr.extension() != ".exr")
    throw Error(scene.output.exr.string(), "", "the scene renderer writes linear HDR: give a .exr file");
  void (*logFn)(const std::string&) = ov.quiet ? nullptr : &logLine;
  if (!ov.quiet) std::fprintf(stderr, "render: loading %s\n", file.c_str());
  auto rs = gi::ReferenceScene::load(scene, logFn);
  double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  gi::ReferenceOptions opt = gi::referenceOptionsFrom(scene.gi);
  if (!ov.quiet)
    std::fprintf(stderr, "render: %s, %s mode, %dx%d, up to %d samples/pixel%s%s (loaded in %.1f s)\n",
                 scene.gi.method.c_str(), scene.gi.mode == gi::RadianceMode::Albedo ? "albedo" : "radiance-cache",
                 scene.camera.width, scene.camera.height, opt.maxSamplesPerPixel,
                 opt.targetRelativeError > 0 ? (", error target " + std::to_string(opt.targetRelativeError)).c_str() : "",
                 opt.timeLimitSeconds > 0 ? (", time limit " + std::to_string(opt.timeLimitSeconds) + " s").c_str() : "",
                 loadSeconds);
  int lastReported = 0;
  auto progress = [&](const gi::ReferenceProgress& p) {
    if (!ov.quiet && (p.samplesPerPixel >= 2 * lastReported || p.samplesPerPixel == opt.maxSamplesPerPixel)) {
      lastReported = p.samplesPerPixel;
      std::fprintf(stderr, "  %5d spp  %7.2f s  estimated error %.4f\n", p.samplesPerPixel, p.seconds, p.relativeError);
    }
    return true;
  };
  // A camera path renders one image per frame (eye and target interpolated linearly between
  // keyframes at the path's fps), named base_0000.exr, base_0001.exr, ...
  std::vector<gi::SceneCamera> cameras;
  if (!scene.cameraPath.empty() && !ov.still) {
    const auto& keys = scene.cameraPath;
    const double frameCount = std::floor(keys.back().time * scene.cameraPathFps + 1e-9) + 1;
    constexpr double kMaxFrames = 1e6;
    if (frameCount > kMaxFrames)
      throw Error(file.string(), "scene.camera_path", "asks for " + std::to_string(frameCount) + " frames (at most " +
                                                          std::to_string(int(kMaxFrames)) + ")");
    const int frames = int(frameCount);
    for (int f = 0; f < frames; ++f) {
      double t = f / scene.cameraPathFps;
      size_t k = 0;
      while (k + 1 < keys.size() && keys[k + 1].time <= t) ++k;
      gi::SceneCamera c = scene.camera;
      if (k + 1 < keys.size() && t >= keys[k].time) {
        double a = (t - keys[k].time) / (keys[k + 1].time - keys[k].time);
        c.eye = glm::mix(keys[k].eye, keys[k + 1].eye, a);
        c.target = glm::mix(keys[k].target, keys[k + 1].target, a);
      } else {
        c.eye = keys[k].eye;
        c.target = keys[k].target;
      }
      if (!gi::viewIsValid(c.eye, c.target, c.up))
        throw Error(file.string(), "scene.camera_path", "frame " + std::to_string(f) +
                                                           ": eye meets target or looks along \"up\" between keyframes");
      cameras.push_back(c);
    }
  } else {
    if (!scene.cameraSet) throw Error(file.string(), "scene.camera", "missing: a render needs a camera (or a camera_path)");
    cameras.push_back(scene.camera);
  }
  // With -o the PNG (when the scene asks for one) goes beside the EXR under the same name.
  if (!scene.output.png.empty() && !ov.output.empty()) scene.output.png = fs::path(ov.output).replace_extension(".png");
  auto numbered = [&](const fs::path& p, size_t f) {
    if (cameras.size() == 1 || p.empty()) return p;
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "_%04zu", f);
    return p.parent_path() / (p.stem().string() + suffix + p.extension().string());
  };
  fs::create_directories(fs::absolute(scene.output.exr).parent_path());
  gi::ReferenceResult r;
  fs::path exr;
  for (size_t f = 0; f < cameras.size(); ++f) {
    if (!ov.quiet && cameras.size() > 1) std::fprintf(stderr, "render: frame %zu of %zu\n", f + 1, cameras.size());
    lastReported = 0;
    r = gi::renderReference(*rs, cameras[f], opt, progress);
    gi::ImageAttributes attrs{{"nestlight:samples", std::to_string(r.samplesPerPixel)},
                              {"nestlight:relative_error_estimate", std::to_string(r.relativeError)},
                              {"nestlight:seconds", std::to_string(r.seconds)},
                              {"nestlight:rays", std::to_string(r.rays)},
                              {"nestlight:method", scene.gi.method},
                              {"nestlight:mode", scene.gi.mode == gi::RadianceMode::Albedo ? "albedo" : "radiance_cache"},
                              {"nestlight:max_bounces", std::to_string(opt.maxBounces)},
                              {"nestlight:stop", r.stopReason},
                              {"nestlight:frame", std::to_string(f)},
                              {"nestlight:scene", fs::absolute(file).string()}};
    exr = numbered(scene.output.exr, f);
    gi::writeExr(exr.string(), r.image, attrs);
    if (!scene.output.png.empty())
      gi::writeToneMappedPng(numbered(scene.output.png, f).string(), r.image, scene.output.exposure);
  }
  SceneRenderReport rep;
  rep.exr = exr;
  rep.frames = int(cameras.size());
  rep.result = std::move(r);
  rep.loadSeconds = loadSeconds;
  rep.discs = rs->discs();
  rep.triangles = rs->triangles();
  rep.scene = std::move(scene);
  if (!ov.quiet) {
    const auto& res = rep.result;
    std::printf("render: wrote %s: %d samples/pixel in %.2f s (%s), estimated relative error %.4f, %.2f M rays/s, %.0f k samples/s%s\n",
                rep.exr.c_str(), res.samplesPerPixel, res.seconds, res.stopReason.c_str(), res.relativeError,
                res.raysPerSecond() / 1e6, res.samplesPerSecond() / 1e3,
                res.nonFiniteSamples ? (", " + std::to_string(res.nonFiniteSamples) + " non-finite samples dropped").c_str() : "");
  }
  return rep;
}

}  // namespace nestlight::cli
