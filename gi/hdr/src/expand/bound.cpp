// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4: the bound of the
// layer's values, which the paper does not have: the in-fill's gradients (section 4.2) can carry
// a few matched values far beyond anything the photograph recorded.
#include <algorithm>
#include <cmath>

#include "expand/expansion.h"

namespace nestlight::gi::hdr::expand {

// The bound of the layer's values: the photograph's largest value times the exposure; where it
// is registered, its largest where the scan renders (what lies beyond, a lamp the scan lacks,
// is no point's value).
void Expansion::bound() {
  double explainedMax = photoMax;
  if (!photoCoverage.empty()) {
    explainedMax = 0;
    for (size_t i = 0; i < small.pixels(); ++i)
      if (photoCoverage[i])
        for (int k = 0; k < 3; ++k)
          if (const float v = small.rgb[3 * i + size_t(k)]; std::isfinite(v))
            explainedMax = std::max(explainedMax, double(v));
  }
  checks.bound = std::max(1.0, double(exposure) * explainedMax);
}

}  // namespace nestlight::gi::hdr::expand
