// `raster`'s entry in the registry; its parameters are the GI frame's
// (nestlight/gi/frame/frame_parameters.h).
#include "nestlight/gi/method_info.h"
#include "nestlight/gi/raster/raster_method.h"

namespace nestlight::gi {

FrameParameters rasterParameters(const Scene& scene) {
  return parseFrameParameters(scene, {});
}

MethodInfo rasterMethodInfo() {
  MethodInfo m;
  m.name = "raster";
  m.summary = "real-time direct light through the GI frame: G-buffer, shadow maps (GL)";
  m.gpu = true;
  m.qualityName = "shadow-map texels";
  m.defaultQualities = {256, 512, 1024, 2048};
  m.applyQuality = [](GiSettings& g, int q) { setParameter(g, "shadow_map_size", q); };
  m.create = [](const Scene& s, const MethodContext& c) { return createRasterMethod(s, c); };
  m.parameters = rasterParameterSpecs();
  return m;
}

}  // namespace nestlight::gi
