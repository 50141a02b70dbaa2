// `reference` and `direct` in the registry: `bench gi` varies their samples per pixel alone.
#include "reference_method.h"

namespace nestlight::gi {

namespace {

MethodInfo pathTracerInfo() {
  MethodInfo m;
  m.gpu = false;
  m.qualityName = "samples per pixel";
  m.defaultQualities = {1, 4, 16, 64};
  m.applyQuality = [](GiSettings& g, int q) {
    g.samplesPerPixel = q;
    g.targetRelativeError = 0;
    g.timeLimitSeconds = 0;
  };
  return m;
}

}  // namespace

MethodInfo referenceMethodInfo() {
  MethodInfo m = pathTracerInfo();
  m.name = "reference";
  m.summary = "path-traced ground truth (Embree, CPU): all bounces";
  m.create = createReferenceMethod;
  return m;
}

MethodInfo directMethodInfo() {
  MethodInfo m = pathTracerInfo();
  m.name = "direct";
  m.summary = "the reference's path tracer stopped after one bounce: direct light (CPU)";
  m.create = createDirectMethod;
  return m;
}

}  // namespace nestlight::gi
