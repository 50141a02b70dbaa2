// Rendering scene files (the path-traced reference and direct lighting), shared by `render`
// and `bench gi`.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"

namespace nestlight::cli {

struct SceneRenderOverrides {
  std::optional<int> width, height;
  std::optional<double> fov;
  std::optional<std::string> method;
  std::optional<gi::RadianceMode> mode;
  std::optional<int> bounces, spp;
  std::optional<double> targetError, timeLimit;
  std::optional<uint64_t> seed;
  std::filesystem::path output;  // .exr; empty: the scene's output
  bool quiet = false;
  bool still = false;            // ignore the scene's camera path: one image from its camera
};

struct SceneRenderReport {
  gi::Scene scene;
  gi::ReferenceResult result;
  std::filesystem::path exr;    // the last frame's
  int frames = 1;
  double loadSeconds = 0;
  uint64_t discs = 0, triangles = 0;
};

SceneRenderReport renderSceneFile(const std::filesystem::path& file, const SceneRenderOverrides& overrides);

}  // namespace nestlight::cli
