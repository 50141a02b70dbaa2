// The GI methods by name: one registry (pbrt-v4's Integrator::Create is the model) from which
// `nestlight render`, `nestlight view`, `bench gi` and the tests make every method, each from a
// scene and its gi.parameters.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"

namespace nestlight::gi {

const std::vector<MethodInfo>& registeredMethods();
// Nullptr for an unknown name.
const MethodInfo* findMethod(const std::string& name);
// The registered methods' names, in the registry's order.
std::vector<std::string> registeredMethodNames();
// "reference, direct, raster"
std::string methodList();
// Throws nestlight::Error naming the scene file and scene.gi.method, with the registered names,
// when none has the scene's gi.method. The registry is the one list of names: scene files are
// checked against it here, not by the scene parser.
void checkSceneMethod(const Scene& scene);
// Makes scene.gi.method for `scene`. Throws nestlight::Error as checkSceneMethod for an unknown
// method, or the method's own errors (its parameters, its inputs).
std::unique_ptr<Method> createMethod(const Scene& scene, const MethodContext& ctx = {});
// Why `bench gi` does not measure `method` (with `variant`; nullptr: as the scene sets it) on
// `scene`, whose gi.mode is the one it would render: "" when it applies, else the reason. Asks
// the method's declaration: the mode it renders (MethodInfo::albedoMode), then its own and the
// variant's whyNotApplicable.
std::string whyNotApplicable(const MethodInfo& method, const Scene& scene,
                             const MethodInfo::Variant* variant = nullptr);

}  // namespace nestlight::gi
