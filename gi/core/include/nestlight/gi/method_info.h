// What a GI method declares about itself: its name, its parameters, what `bench gi` varies and
// how it is made. Each method's library fills its own (nestlight/gi/<method>/...: e.g.
// pbgiMethodInfo()); the registry (nestlight/gi/methods.h) lists them, so a method's name and
// parameters are written once, beside the method.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_parameters.h"

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
  // Why the method cannot apply to a scene (its gi.mode as it will render): "" when it can, else
  // the reason, which `bench gi` prints and records instead of a row that would only repeat
  // another (ibl without an environment renders raster's direct light). Unset: it always can.
  using Applicability = std::function<std::string(const Scene&)>;
  Applicability whyNotApplicable;
  // Settings `bench gi` also measures, each at every quality level (vpl: fewer bounces; exact
  // visibility, the ablation that separates the ISMs' error from the VPLs'); each may say, as the
  // method does, why it cannot apply to a scene (its image would equal the method's own).
  struct Variant {
    Variant(std::string n, std::function<void(GiSettings&)> a, Applicability why = {})
        : name(std::move(n)), apply(std::move(a)), whyNotApplicable(std::move(why)) {}
    std::string name;
    std::function<void(GiSettings&)> apply;
    Applicability whyNotApplicable;
  };
  std::vector<Variant> variants;
  // Whether it renders the albedo mode (scan points lit by the scene's lights); `bench gi`
  // skips, and says so, a method that does not.
  bool albedoMode = true;
  // Every member of scene.gi.parameters the method reads (a method on the raster frame: raster's
  // and its own). Empty: the method reads none (and, as the path tracer, ignores any given).
  ParameterSpecs parameters;
};

// Sets `name` in the settings' gi.parameters (making them an object first): quality levels and
// variants.
void setParameter(GiSettings& g, const std::string& name, const nlohmann::json& value);

}  // namespace nestlight::gi
