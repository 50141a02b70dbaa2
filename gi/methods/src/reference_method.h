#pragma once

#include <memory>

#include "nestlight/gi/method.h"

namespace nestlight::gi {

// `reference` (all bounces) or `direct` (one), as scene.gi.method names it.
std::unique_ptr<Method> createReferenceMethod(const Scene& scene, const MethodContext& ctx);

}  // namespace nestlight::gi
