// Expansion options small enough for the unit tests: two automatic views, 96-pixel cube faces,
// four PatchMatch iterations and the photograph scaled to 200 pixels, so one expansion takes
// seconds on llvmpipe and under the sanitizers.
#pragma once

#include "nestlight/gi/hdr/expand.h"

namespace nestlight::gi::hdr {

inline ExpandOptions smallExpandOptions() {
  ExpandOptions o;
  o.autoViews = 2;
  o.faceSize = 96;
  o.patchIterations = 4;
  o.maxPhotoSize = 200;
  return o;
}

}  // namespace nestlight::gi::hdr
