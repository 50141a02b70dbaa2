#pragma once

#include <memory>

#include "nestlight/gi/method.h"

namespace nestlight::gi {

// `reference`: the path tracer with the scene's bounces.
std::unique_ptr<Method> createReferenceMethod(const Scene& scene, const MethodContext& ctx);
// `direct`: the same stopped after one bounce.
std::unique_ptr<Method> createDirectMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
