// The GI methods by name: one registry (pbrt-v4's Integrator::Create is the model) from which
// `nestlight render`, `nestlight view`, `bench gi` and the tests make every method, each from a
// scene and its gi.parameters.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"

namespace nestlight::gi {

struct MethodInfo {
  std::string name;
  std::string summary;  // one line for --help
  bool gpu = false;     // needs an OpenGL 4.5 context
  // What `bench gi` varies to trade speed for error, and the values it tries by default.
  std::string qualityName;  // "samples per pixel", "shadow-map texels"
  std::vector<int> defaultQualities;
  // Sets one quality level in a scene's settings before the method is made.
  std::function<void(GiSettings&, int quality)> applyQuality;
  std::function<std::unique_ptr<Method>(const Scene&, const MethodContext&)> create;
  // Settings `bench gi` also measures, each at every quality level (vpl: fewer bounces; exact
  // visibility, the ablation that separates the ISMs' error from the VPLs').
  struct Variant {
    std::string name;
    std::function<void(GiSettings&)> apply;
  };
  std::vector<Variant> variants;
  // Whether it renders the albedo mode (scan points lit by the scene's lights); `bench gi`
  // skips, and says so, a method that does not.
  bool albedoMode = true;
};

const std::vector<MethodInfo>& registeredMethods();
// Nullptr for an unknown name.
const MethodInfo* findMethod(const std::string& name);
// "reference, direct, raster"
std::string methodList();
// Makes scene.gi.method for `scene`. Throws nestlight::Error naming the scene file and
// "gi.method" for an unknown method, or the method's own errors (its parameters, its inputs).
std::unique_ptr<Method> createMethod(const Scene& scene, const MethodContext& ctx = {});

}  // namespace nestlight::gi
