// `nestlight render scene.json`: load, override, render each frame, write EXR (and PNG).
#include "nestlight/gi/render_scene.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "nestlight/gi/methods.h"
#include "nestlight/gi/scene_overrides.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {

namespace fs = std::filesystem;

SceneRenderReport renderSceneFile(const fs::path& file, const SceneRenderOverrides& ov) {
  auto t0 = std::chrono::steady_clock::now();
  Scene scene = loadScene(file);
  // The file's own method must exist even when --method replaces it, as any field of the file.
  checkSceneMethod(scene);
  applySceneOverrides(scene, ov);
  if (!ov.output.empty()) scene.output.exr = ov.output;
  if (scene.output.exr.empty())
    scene.output.exr = file.parent_path() / (file.stem().string() + ".exr");
  if (scene.output.exr.extension() != ".exr")
    throw Error(scene.output.exr.string(), "",
                "the scene renderer writes linear HDR: give a .exr file");
  if (!ov.quiet) std::fprintf(stderr, "render: loading %s\n", file.c_str());
  if (!sceneHasLight(scene, scene.gi.mode))
    std::fprintf(
        stderr,
        "render: warning: %s: nothing lights this scene in albedo mode (no lights, environment or "
        "emissive mesh; scan colours are reflectances there): the image will be black\n",
        file.c_str());
  MethodContext mc;
  mc.quiet = ov.quiet;
  std::unique_ptr<Method> method = createMethod(scene, mc);
  const double loadSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!ov.quiet)
    std::fprintf(stderr, "render: %s, %s mode, %dx%d (loaded in %.1f s)\n", scene.gi.method.c_str(),
                 scene.gi.mode == RadianceMode::Albedo ? "albedo" : "radiance-cache",
                 scene.camera.width, scene.camera.height, loadSeconds);
  // A camera path renders one image per frame, named base_0000.exr, base_0001.exr, ...
  const std::vector<SceneCamera> cameras = sceneCameras(scene, ov.still);
  // With -o the PNG (when the scene asks for one) goes beside the EXR under the same name.
  if (!scene.output.png.empty() && !ov.output.empty())
    scene.output.png = fs::path(ov.output).replace_extension(".png");
  auto numbered = [&](const fs::path& p, size_t f) {
    if (cameras.size() == 1 || p.empty()) return p;
    char suffix[16];
    std::snprintf(suffix, sizeof suffix, "_%04zu", f);
    return p.parent_path() / (p.stem().string() + suffix + p.extension().string());
  };
  fs::create_directories(fs::absolute(scene.output.exr).parent_path());
  MethodFrame r;
  fs::path exr;
  // The PNG's exposure: --exposure, else the scene's output.exposure, else automatic from the
  // first frame, kept for the rest so that a camera path's images do not flicker. The EXR is the
  // method's linear image as it is, whatever the exposure.
  std::optional<PngExposure> pngExposure;
  for (size_t f = 0; f < cameras.size(); ++f) {
    if (!ov.quiet && cameras.size() > 1)
      std::fprintf(stderr, "render: frame %zu of %zu\n", f + 1, cameras.size());
    r = method->render(cameras[f]);
    ImageAttributes attrs = r.attributes;
    attrs["nestlight:method"] = scene.gi.method;
    attrs["nestlight:mode"] = scene.gi.mode == RadianceMode::Albedo ? "albedo" : "radiance_cache";
    attrs["nestlight:frame"] = std::to_string(f);
    attrs["nestlight:scene"] = fs::absolute(file).string();
    exr = numbered(scene.output.exr, f);
    writeExr(exr.string(), r.image, attrs);
    if (!scene.output.png.empty()) {
      if (!pngExposure) {
        pngExposure = choosePngExposure(
            r.image, ov.exposure,
            scene.output.exposureSet ? std::optional<double>(scene.output.exposure) : std::nullopt);
        if (!ov.quiet)
          std::printf("render: PNG exposure %s%s\n", pngExposure->description.c_str(),
                      cameras.size() > 1 ? ", every frame" : "");
      }
      writeToneMappedPng(numbered(scene.output.png, f).string(), r.image, pngExposure->stops);
    }
  }
  SceneRenderReport rep;
  rep.exr = exr;
  rep.frames = int(cameras.size());
  rep.result = std::move(r);
  rep.loadSeconds = loadSeconds;
  if (pngExposure) rep.pngExposure = pngExposure->stops;
  rep.scene = std::move(scene);
  if (!ov.quiet) std::printf("render: wrote %s: %s\n", rep.exr.c_str(), rep.result.summary.c_str());
  return rep;
}

}  // namespace nestlight::gi
