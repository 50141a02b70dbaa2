// The `raster` method: the GI frame (nestlight/gi/frame/scene_frame.h) with no extension, direct
// light only.
#include "nestlight/gi/raster/raster_method.h"

#include "nestlight/gi/frame/scene_frame.h"

namespace nestlight::gi {

std::unique_ptr<Method> createRasterMethod(const Scene& scene, const MethodContext& ctx) {
  return createRasterMethod(scene, ctx, nullptr);
}

}  // namespace nestlight::gi
