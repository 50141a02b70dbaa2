#include "nestlight/gi/hdr/exposure.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nestlight::gi::hdr {

namespace {

void add(Histogram& h, float v) {
  if (!std::isfinite(v)) {
    h.skipped++;
    return;
  }
  const int bin = std::clamp(int(double(v) * kHistogramBins), 0, kHistogramBins - 1);
  h.mass[size_t(bin)] += 1;
  h.counted++;
}

void normalise(Histogram& h) {
  if (h.counted == 0) return;
  for (double& m : h.mass) m /= double(h.counted);
}

}  // namespace

Histogram luminanceHistogram(const std::vector<float>& luminance) {
  Histogram h;
  for (float v : luminance) add(h, v);
  normalise(h);
  return h;
}

Histogram exposedHistogram(const std::vector<float>& hdrLuminance, double exposure) {
  Histogram h;
  for (float v : hdrLuminance)
    add(h, std::isfinite(v) ? float(std::clamp(exposure * double(v), 0.0, 1.0)) : v);
  normalise(h);
  return h;
}

double wasserstein(const Histogram& a, const Histogram& b) {
  if (a.counted == 0 || b.counted == 0) return 1.0;
  double ca = 0, cb = 0, area = 0;
  for (int i = 0; i < kHistogramBins; ++i) {
    ca += a.mass[size_t(i)];
    cb += b.mass[size_t(i)];
    area += std::fabs(ca - cb);
  }
  return area / kHistogramBins;
}

ExposureSearch findBestExposure(const std::vector<float>& hdrLuminance, const Histogram& ldr,
                                const ExposureSearchOptions& options) {
  ExposureSearch r;
  double lo = options.log2Lo, hi = options.log2Hi;
  if (!(lo < hi)) {
    float minPositive = std::numeric_limits<float>::infinity(), max = 0;
    for (float v : hdrLuminance)
      if (std::isfinite(v) && v > 0) minPositive = std::min(minPositive, v), max = std::max(max, v);
    if (!(max > 0)) return r;
    lo = -std::log2(double(max));
    hi = -std::log2(double(minPositive));
    if (!(lo < hi)) lo -= 1, hi += 1;  // a photograph of one luminance
  }
  if (ldr.counted == 0) return r;
  r.log2Lo = lo;
  r.log2Hi = hi;
  r.usable = true;
  r.distance = std::numeric_limits<double>::infinity();
  const int samples = std::max(options.samples, 2);
  for (int it = 0; it < std::max(options.maxIterations, 1); ++it) {
    double best = r.log2Exposure, bestDistance = std::numeric_limits<double>::infinity();
    for (int s = 0; s < samples; ++s) {
      const double x = lo + (hi - lo) * s / (samples - 1);
      const double d = wasserstein(exposedHistogram(hdrLuminance, std::exp2(x)), ldr);
      if (d < bestDistance) bestDistance = d, best = x;
    }
    r.iterations = it + 1;
    if (!(bestDistance < r.distance)) break;  // converged: no better sample in the narrower range
    r.distance = bestDistance;
    r.log2Exposure = best;
    const double half = 0.25 * (hi - lo);  // the range halves, centred on the best
    lo = best - half;
    hi = best + half;
  }
  return r;
}

PairEstimate estimateExposureFromPairs(const std::vector<float>& scanY,
                                       const std::vector<float>& photoY, double minScan,
                                       double maxScan, double photoClip) {
  PairEstimate r;
  r.offered = std::min(scanY.size(), photoY.size());
  std::vector<double> ratio, ls, lp;
  ratio.reserve(r.offered);
  for (size_t i = 0; i < r.offered; ++i) {
    const double s = scanY[i], p = photoY[i];
    if (!(s >= minScan && s <= maxScan) || !(p > 0) || !std::isfinite(p) || !(p < photoClip))
      continue;
    ls.push_back(std::log2(s));
    lp.push_back(std::log2(p));
    ratio.push_back(ls.back() - lp.back());
  }
  r.pairs = ratio.size();
  if (ratio.empty()) return r;
  r.usable = true;
  auto median = [](std::vector<double> v) {
    const size_t m = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(m), v.end());
    return v[m];
  };
  r.log2Exposure = median(ratio);
  std::vector<double> dev(ratio.size());
  for (size_t i = 0; i < ratio.size(); ++i) dev[i] = std::fabs(ratio[i] - r.log2Exposure);
  r.spreadStops = 1.4826 * median(dev);
  auto slope = [&](double above) {
    double n = 0, ms = 0, mp = 0;
    for (size_t i = 0; i < ls.size(); ++i)
      if (ls[i] >= above) ms += ls[i], mp += lp[i], n++;
    if (n < 2) return 1.0;
    ms /= n, mp /= n;
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < ls.size(); ++i)
      if (ls[i] >= above) sxy += (ls[i] - ms) * (lp[i] - mp), sxx += (ls[i] - ms) * (ls[i] - ms);
    return sxx > 0 ? sxy / sxx : 1.0;
  };
  r.slope = slope(-std::numeric_limits<double>::infinity());
  r.highlightSlope = slope(median(ls));
  return r;
}

}  // namespace nestlight::gi::hdr
