#pragma once

#include <memory>

#include "nestlight/gi/method.h"
#include "nestlight/gi/method_info.h"

namespace nestlight::gi {

// `reference`: the path tracer with the scene's bounces.
std::unique_ptr<Method> createReferenceMethod(const Scene& scene, const MethodContext& ctx);
// `direct`: the same stopped after one bounce.
std::unique_ptr<Method> createDirectMethod(const Scene& scene, const MethodContext& ctx);

// Their entries in the registry (src/reference_info.cpp). They declare no parameters: the path
// tracer reads none (and ignores any a scene gives, so a scene made for another method renders).
MethodInfo referenceMethodInfo();
MethodInfo directMethodInfo();

}  // namespace nestlight::gi
