// The path-traced reference as `bench gi` and `bench diffrender` measure against it: the scene
// prepared for one method (the scene's gi.parameters kept only where that method declares them,
// the mode and image size as the options set them), and the reference rendered once to an error
// target and cached in an EXR whose header holds a key of everything that changes it. Private to
// bench/src.
#pragma once

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"

namespace nestlight::bench::reference {

// `probe` (the scene as loaded) for `method`: gi.parameters of the scene's own method are kept
// only where `method` declares them (diffrender's capture is no parameter of pbgi, which would
// refuse it); `mode` "albedo" or "radiance_cache" overrides the scene's ("" keeps it); the
// camera is width x height.
gi::Scene sceneFor(const gi::Scene& probe, const std::string& method, const std::string& mode,
                   int width, int height);

// What a cached reference depends on and how it is rendered.
struct Request {
  std::filesystem::path sceneFile;  // its bytes are hashed into the key
  gi::Scene probe;                  // the scene as loaded: its assets are stamped into the key
  std::string mode;                 // as sceneFor takes it
  int width = 0, height = 0;
  double error = 0.004;          // the relative error the reference is rendered to
  double timeLimit = 1800;       // seconds at most
  int spp = 1 << 16;             // samples per pixel at most
  bool force = false;            // render again even when the cache matches
  std::string who = "bench gi";  // the progress lines' prefix
};

struct Image {
  gi::HdrImage image;
  nlohmann::json info;  // cached, samples, relative_error_estimate, seconds (, stop, rates)
};

// The reference, cached in `path`; `withoutInserted`: R0, the scene as it was captured (the
// meshes marked inserted left out), under its own key. One that stopped short of the error target
// is used but not cached (the next run tries again).
Image loadOrRender(const Request& request, const std::filesystem::path& path, std::FILE* log,
                   bool withoutInserted = false);

}  // namespace nestlight::bench::reference
