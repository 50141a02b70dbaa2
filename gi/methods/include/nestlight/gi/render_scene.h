// Rendering a scene file with the method it names (or --method): the whole job of
// `nestlight render scene.json`, shared with `bench gi` and the demo.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "nestlight/gi/method.h"
#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct SceneRenderOverrides {
  std::optional<int> width, height;
  std::optional<double> fov;
  std::optional<std::string> method;
  std::optional<RadianceMode> mode;
  std::optional<int> bounces, spp;
  std::optional<double> targetError, timeLimit;
  std::optional<uint64_t> seed;
  std::optional<double> exposure;  // the PNG's stops (--exposure): wins over the scene file's
  nlohmann::json parameters;       // merged into the scene's gi.parameters (method options)
  // A view state's camera (render/view --state): its eye, target and up replace the scene's
  // camera's (a camera path still moves it; the field of view is `fov`'s).
  struct Pose {
    glm::dvec3 eye{0.0}, target{0, 0, -1}, up{0, 0, 1};
  };
  std::optional<Pose> camera;
  // Added to every scan's octrees[].clipping (--clip, a view state's volumes).
  ClipSet clipping;
  std::filesystem::path output;  // .exr; empty: the scene's output
  bool quiet = false;
  bool still = false;  // ignore the scene's camera path: one image from its camera
};

struct SceneRenderReport {
  Scene scene;
  MethodFrame result;         // the last frame's
  std::filesystem::path exr;  // the last frame's
  int frames = 1;
  double loadSeconds = 0;             // reading the scene and making the method
  std::optional<double> pngExposure;  // the stops the PNG was written with (none: no PNG)
};

// Loads `file`, applies `overrides`, renders every frame (the camera, or each frame of the
// camera path) with the method the scene names and writes linear EXR (plus the scene's PNG).
// Progress and load lines go to stderr unless overrides.quiet. Throws nestlight::Error naming
// the file and the field at fault.
SceneRenderReport renderSceneFile(const std::filesystem::path& file,
                                  const SceneRenderOverrides& overrides);

}  // namespace nestlight::gi
