// `nestlight render scene.json`: load, override, render each frame, write EXR (and PNG).
#include "nestlight/gi/reference/render_scene.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace fs = std::filesystem;

namespace {
void logLine(const std::string& line) { std::fprintf(stderr, "  %s\n", line.c_str()); }
}  // namespace

SceneRenderReport renderSceneFile(const fs::path& file, const SceneRenderOverrides& ov) {
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = loadScene(file);
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
  auto rs = ReferenceScene::load(scene, logFn);
  double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ReferenceOptions opt = referenceOptionsFrom(scene.gi);
  if (!ov.quiet)
    std::fprintf(stderr, "render: %s, %s mode, %dx%d, up to %d samples/pixel%s%s (loaded in %.1f s)\n",
                 scene.gi.method.c_str(), scene.gi.mode == RadianceMode::Albedo ? "albedo" : "radiance-cache",
                 scene.camera.width, scene.camera.height, opt.maxSamplesPerPixel,
                 opt.targetRelativeError > 0 ? (", error target " + std::to_string(opt.targetRelativeError)).c_str() : "",
                 opt.timeLimitSeconds > 0 ? (", time limit " + std::to_string(opt.timeLimitSeconds) + " s").c_str() : "",
                 loadSeconds);
  int lastReported = 0;
  auto progress = [&](const ReferenceProgress& p) {
    if (!ov.quiet && (p.samplesPerPixel >= 2 * lastReported || p.samplesPerPixel == opt.maxSamplesPerPixel)) {
      lastReported = p.samplesPerPixel;
      std::fprintf(stderr, "  %5d spp  %7.2f s  estimated error %.4f\n", p.samplesPerPixel, p.seconds, p.relativeError);
    }
    return true;
  };
  // A camera path renders one image per frame, named base_0000.exr, base_0001.exr, ...
  const std::vector<SceneCamera> cameras = sceneCameras(scene, ov.still);
  // With -o the PNG (when the scene asks for one) goes beside the EXR under the same name.
  if (!scene.output.png.empty() && !ov.output.empty()) scene.output.png = fs::path(ov.output).replace_extension(".png");
  auto numbered = [&](const fs::path& p, size_t f) {
    if (cameras.size() == 1 || p.empty()) return p;
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "_%04zu", f);
    return p.parent_path() / (p.stem().string() + suffix + p.extension().string());
  };
  fs::create_directories(fs::absolute(scene.output.exr).parent_path());
  ReferenceResult r;
  fs::path exr;
  for (size_t f = 0; f < cameras.size(); ++f) {
    if (!ov.quiet && cameras.size() > 1) std::fprintf(stderr, "render: frame %zu of %zu\n", f + 1, cameras.size());
    lastReported = 0;
    r = renderReference(*rs, cameras[f], opt, progress);
    ImageAttributes attrs{{"nestlight:samples", std::to_string(r.samplesPerPixel)},
                              {"nestlight:relative_error_estimate", std::to_string(r.relativeError)},
                              {"nestlight:seconds", std::to_string(r.seconds)},
                              {"nestlight:rays", std::to_string(r.rays)},
                              {"nestlight:method", scene.gi.method},
                              {"nestlight:mode", scene.gi.mode == RadianceMode::Albedo ? "albedo" : "radiance_cache"},
                              {"nestlight:max_bounces", std::to_string(opt.maxBounces)},
                              {"nestlight:stop", r.stopReason},
                              {"nestlight:frame", std::to_string(f)},
                              {"nestlight:scene", fs::absolute(file).string()}};
    exr = numbered(scene.output.exr, f);
    writeExr(exr.string(), r.image, attrs);
    if (!scene.output.png.empty())
      writeToneMappedPng(numbered(scene.output.png, f).string(), r.image, scene.output.exposure);
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

}  // namespace nestlight::gi
