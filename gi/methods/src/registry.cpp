#include "nestlight/gi/diffrender/diffrender_method.h"
#include "nestlight/gi/ibl/ibl_method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/pbgi/pbgi_method.h"
#include "nestlight/gi/projection/projection_method.h"
#include "nestlight/gi/raster/raster_method.h"
#include "nestlight/gi/vpl/vpl_method.h"
#include "nestlight/octree/error.h"
#include "reference_method.h"

namespace nestlight::gi {

// The one list of methods; each declares itself (name, parameters, quality levels, variants) in
// its own library.
const std::vector<MethodInfo>& registeredMethods() {
  static const std::vector<MethodInfo> methods = {
      referenceMethodInfo(), directMethodInfo(), rasterMethodInfo(),     vplMethodInfo(),
      pbgiMethodInfo(),      iblMethodInfo(),    diffrenderMethodInfo(), projectionMethodInfo()};
  return methods;
}

const MethodInfo* findMethod(const std::string& name) {
  for (const auto& m : registeredMethods())
    if (m.name == name) return &m;
  return nullptr;
}

std::vector<std::string> registeredMethodNames() {
  std::vector<std::string> names;
  for (const auto& m : registeredMethods()) names.push_back(m.name);
  return names;
}

std::string methodList() {
  std::string s;
  for (const auto& m : registeredMethods()) s += (s.empty() ? "" : ", ") + m.name;
  return s;
}

void checkSceneMethod(const Scene& scene) {
  if (!findMethod(scene.gi.method))
    throw Error(scene.file.string(), "scene.gi.method",
                "'" + scene.gi.method + "' is not one of: " + methodList());
}

std::unique_ptr<Method> createMethod(const Scene& scene, const MethodContext& ctx) {
  checkSceneMethod(scene);
  return findMethod(scene.gi.method)->create(scene, ctx);
}

std::string whyNotApplicable(const MethodInfo& method, const Scene& scene,
                             const MethodInfo::Variant* variant) {
  if (!method.albedoMode && scene.gi.mode == RadianceMode::Albedo)
    return "it renders the radiance-cache mode only so far";
  if (method.whyNotApplicable)
    if (std::string why = method.whyNotApplicable(scene); !why.empty()) return why;
  if (variant && variant->whyNotApplicable) return variant->whyNotApplicable(scene);
  return "";
}

}  // namespace nestlight::gi
