// HDR expansion out of core, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni,
// "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 4.1, eq. 1-2: the
// photograph's range (the exposures that could be right) and the exposure the paper's histogram
// search finds, the starting point when nothing registers the photograph and on record otherwise.
#include <algorithm>
#include <cmath>

#include "expand/expansion.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::hdr::expand {

void Expansion::photographExposure() {
  const auto t = Clock::now();
  // Pixels of exactly zero carry no measurement (a rendered photograph's background, a masked
  // area): counted, they would pull the histogram, and so the exposure, towards black.
  photoY.reserve(photo.pixels());
  for (size_t i = 0; i < photo.pixels(); ++i) {
    // Masked out: what the photograph shows there is not the scanned scene (sky, a lamp beyond
    // the scan, people), so it is no evidence of the exposure and bounds no value.
    if (!maskedIn(i)) continue;
    const Rgb c(photo.rgb[3 * i], photo.rgb[3 * i + 1], photo.rgb[3 * i + 2]);
    for (int k = 0; k < 3; ++k)
      if (std::isfinite(c[k])) photoMax = std::max(photoMax, double(c[k]));
    if (const float y = luminance(c); y != 0.0f) photoY.push_back(y);
  }
  for (float y : photoY)
    if (std::isfinite(y) && y > 0) positiveY.push_back(y);
  if (positiveY.empty())
    throw Error("", "",
                o.photoMask.empty()
                    ? "the photograph has no positive finite luminance (black or broken): "
                      "nothing to match"
                    : "the photograph has no positive finite luminance where its mask lets it "
                      "count: nothing to match");
  checks.photoMax = photoMax;
  {
    // The exposed photograph must bring its brightest luminance beyond the scan's clipping (by
    // minHeadroom), or it says nothing about the clipped points, and must leave its darkest
    // percentile under 1, or it is clipped almost everywhere and nothing matches.
    const size_t p1 = positiveY.size() / 100;
    std::nth_element(positiveY.begin(), positiveY.begin() + std::ptrdiff_t(p1), positiveY.end());
    const double dark = positiveY[p1];
    const double bright = *std::max_element(positiveY.begin(), positiveY.end());
    checks.rangeLo = std::log2(o.minHeadroom / bright);
    checks.rangeHi = std::max(checks.rangeLo, std::log2(1.0 / dark));
  }
  rep.exposureUsable = true;
  if (o.log2Exposure) {
    checks.method = "forced";
    rep.log2Exposure = *o.log2Exposure;
  } else if (o.photoView) {
    checks.method = "photo-view";  // estimated from the photograph's own view, after the renderings
  } else {
    checks.method = "matches";
    const ExposureSearch ex = findBestExposure(photoY, scanHistogram);
    if (!ex.usable)
      throw Error(
          "", "",
          "the photograph has no positive finite luminance (black or broken): nothing to match");
    rep.log2Exposure = checks.histogramLog2 = ex.log2Exposure;
    rep.exposureDistance = ex.distance;
  }
  rep.seconds["exposure"] = seconds(t);
}

}  // namespace nestlight::gi::hdr::expand
