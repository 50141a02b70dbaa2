// Image error metrics. References: Wang, Bovik, Sheikh and Simoncelli, "Image quality assessment:
// from error visibility to structural similarity", IEEE TIP 13(4), 2004 (SSIM); Rousselle, Knaus
// and Zwicker, "Adaptive sampling and reconstruction using greedy error minimization", ACM TOG
// 30(6), 2011 (relative MSE); viridis by van der Walt and Smith (matplotlib, 2015, CC0) for the
// false-colour map. Conventions are in metrics.h.
//
// Sums run in double: squared differences of HDR values above half-float range (and of floats
// near FLT_MAX) stay finite there. Rows are reduced in parallel into per-row partials that are
// added in row order afterwards, so the numbers do not depend on how TBB split the work.
#include "nestlight/gi/metrics.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool finitePixel(const float* p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

// Runs f(y) for every row in parallel.
template <typename F>
void forRows(int height, F f) {
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& r) {
    for (int y = r.begin(); y != r.end(); ++y) f(y);
  });
}

NonFiniteCount countNonFinite(const HdrImage& img) {
  std::vector<NonFiniteCount> rows(size_t(img.height));
  forRows(img.height, [&](int y) {
    NonFiniteCount& n = rows[size_t(y)];
    for (int x = 0; x < img.width; ++x) {
      const float* p = &img.rgb[3 * (size_t(y) * img.width + x)];
      bool bad = false;
      for (int k = 0; k < 3; ++k) {
        if (std::isnan(p[k]))
          ++n.nan, bad = true;
        else if (std::isinf(p[k]))
          ++n.inf, bad = true;
      }
      n.pixels += bad;
    }
  });
  NonFiniteCount total;
  for (const auto& r : rows) total.pixels += r.pixels, total.nan += r.nan, total.inf += r.inf;
  return total;
}

// 1 where both images are finite: the pixels every metric is taken over.
std::vector<uint8_t> comparedMask(const HdrImage& a, const HdrImage& b) {
  std::vector<uint8_t> mask(a.pixels());
  forRows(a.height, [&](int y) {
    for (int x = 0; x < a.width; ++x) {
      size_t i = size_t(y) * a.width + x;
      mask[i] = finitePixel(&a.rgb[3 * i]) && finitePixel(&b.rgb[3 * i]);
    }
  });
  return mask;
}

double maxCompared(const HdrImage& img, const std::vector<uint8_t>& mask) {
  std::vector<double> rows(size_t(img.height), -std::numeric_limits<double>::infinity());
  forRows(img.height, [&](int y) {
    for (int x = 0; x < img.width; ++x) {
      size_t i = size_t(y) * img.width + x;
      if (!mask[i]) continue;
      for (int k = 0; k < 3; ++k)
        rows[size_t(y)] = std::max(rows[size_t(y)], double(img.rgb[3 * i + k]));
    }
  });
  double m = -std::numeric_limits<double>::infinity();
  for (double r : rows) m = std::max(m, r);
  return m;
}

// A peak of 0 (a black reference) would make PSNR -inf for any error and SSIM's constants 0;
// the display range is the only other scale there is.
double peakOrOne(double peak) {
  return peak > 0 ? peak : 1.0;
}

ErrorStats pixelStats(const HdrImage& t, const HdrImage& r, const std::vector<uint8_t>& mask,
                      double eps, double peak) {
  struct Sums {
    double sq = 0, abs = 0, max = 0, relSq = 0, rel = 0;
    uint64_t n = 0;
  };
  std::vector<Sums> rows(size_t(t.height));
  forRows(t.height, [&](int y) {
    Sums& s = rows[size_t(y)];
    for (int x = 0; x < t.width; ++x) {
      size_t i = size_t(y) * t.width + x;
      if (!mask[i]) continue;
      ++s.n;
      for (int k = 0; k < 3; ++k) {
        const double a = t.rgb[3 * i + k], b = r.rgb[3 * i + k];
        const double d = a - b, ad = std::abs(d);
        s.sq += d * d;
        s.abs += ad;
        s.max = std::max(s.max, ad);
        s.relSq += d * d / (b * b + eps);
        s.rel += ad / (std::abs(b) + eps);
      }
    }
  });
  Sums total;
  for (const auto& s : rows) {
    total.sq += s.sq, total.abs += s.abs, total.relSq += s.relSq, total.rel += s.rel,
        total.n += s.n;
    total.max = std::max(total.max, s.max);
  }
  ErrorStats e;
  e.peak = peak;
  if (total.n == 0) {
    e.mse = e.rmse = e.meanAbsolute = e.maxAbsolute = e.relativeMse = e.meanRelative = e.psnr =
        e.ssim = kNaN;
    return e;
  }
  const double samples = 3.0 * double(total.n);
  e.mse = total.sq / samples;
  e.rmse = std::sqrt(e.mse);
  e.meanAbsolute = total.abs / samples;
  e.maxAbsolute = total.max;
  e.relativeMse = total.relSq / samples;
  e.meanRelative = total.rel / samples;
  e.psnr =
      e.mse == 0 ? std::numeric_limits<double>::infinity() : 10.0 * std::log10(peak * peak / e.mse);
  return e;
}

// SSIM of Wang et al. 2004 as a normalised convolution: each window's moments are weighted sums
// over the compared pixels it covers, divided by the weight it covered. Excluded pixels (outside
// the image or non-finite) thus drop out of every neighbour's statistics instead of entering
// them as zeros. The 2D Gaussian is separable, and so are the weighted sums: one horizontal pass
// into a strip of rows (with the window's radius of halo), then one vertical pass.
double maskedSsim(const HdrImage& a, const HdrImage& b, const std::vector<uint8_t>& mask,
                  double L) {
  constexpr int R = kSsimWindow / 2;
  std::array<double, kSsimWindow> kernel{};
  double ksum = 0;
  for (int i = 0; i < kSsimWindow; ++i)
    ksum += kernel[size_t(i)] =
        std::exp(-double((i - R) * (i - R)) / (2 * kSsimSigma * kSsimSigma));
  for (double& k : kernel) k /= ksum;
  const double c1 = (kSsimK1 * L) * (kSsimK1 * L), c2 = (kSsimK2 * L) * (kSsimK2 * L);

  // Per pixel: the covered weight, then per channel sums of a, b, a^2, b^2, ab.
  constexpr int kPlanes = 1 + 3 * 5;
  constexpr int kBlock = 16;  // output rows per task: the halo costs 2R/kBlock extra work
  const int w = a.width, h = a.height;
  const int blocks = (h + kBlock - 1) / kBlock;
  std::vector<double> rowSum(size_t(h), 0.0);
  std::vector<uint64_t> rowCount(size_t(h), 0);
  tbb::parallel_for(0, blocks, [&](int block) {
    const int y0 = block * kBlock, y1 = std::min(h, y0 + kBlock);
    const int r0 = std::max(0, y0 - R), r1 = std::min(h, y1 + R);
    std::vector<double> strip(size_t(r1 - r0) * w * kPlanes, 0.0);
    for (int y = r0; y < r1; ++y)
      for (int x = 0; x < w; ++x) {
        double* acc = &strip[(size_t(y - r0) * w + x) * kPlanes];
        for (int dx = -R; dx <= R; ++dx) {
          const int xx = x + dx;
          if (xx < 0 || xx >= w) continue;
          const size_t i = size_t(y) * w + xx;
          if (!mask[i]) continue;
          const double k = kernel[size_t(dx + R)];
          acc[0] += k;
          for (int c = 0; c < 3; ++c) {
            const double va = a.rgb[3 * i + c], vb = b.rgb[3 * i + c];
            double* m = acc + 1 + 5 * c;
            // k * (va * vb), not (k * va) * vb: swapping the images must not change the rounding.
            m[0] += k * va, m[1] += k * vb, m[2] += k * (va * va), m[3] += k * (vb * vb),
                m[4] += k * (va * vb);
          }
        }
      }
    std::array<double, kPlanes> acc;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        if (!mask[size_t(y) * w + x]) continue;
        acc.fill(0.0);
        for (int dy = -R; dy <= R; ++dy) {
          const int yy = y + dy;
          if (yy < r0 || yy >= r1) continue;
          const double k = kernel[size_t(dy + R)];
          const double* s = &strip[(size_t(yy - r0) * w + x) * kPlanes];
          for (int p = 0; p < kPlanes; ++p) acc[size_t(p)] += k * s[p];
        }
        const double wsum = acc[0];  // > 0: the centre pixel itself is compared
        double s = 0;
        for (int c = 0; c < 3; ++c) {
          const double* m = &acc[size_t(1 + 5 * c)];
          const double ma = m[0] / wsum, mb = m[1] / wsum;
          const double va = m[2] / wsum - ma * ma, vb = m[3] / wsum - mb * mb,
                       cov = m[4] / wsum - ma * mb;
          s += ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
        }
        rowSum[size_t(y)] += s / 3.0;
        ++rowCount[size_t(y)];
      }
  });
  double sum = 0;
  uint64_t n = 0;
  for (int y = 0; y < h; ++y) sum += rowSum[size_t(y)], n += rowCount[size_t(y)];
  return n ? sum / double(n) : kNaN;
}

void checkLayout(const HdrImage& img) {
  NL_CHECK(img.width >= 0 && img.height >= 0 && img.rgb.size() == img.pixels() * 3);
}

std::string nameOr(const std::string& name, const char* fallback) {
  return name.empty() ? fallback : name;
}

std::string shortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

}  // namespace

void checkSameSize(const HdrImage& test, const HdrImage& reference, const std::string& testName,
                   const std::string& referenceName) {
  if (test.width == reference.width && test.height == reference.height) return;
  throw Error(nameOr(testName, "test image"), "",
              "is " + std::to_string(test.width) + "x" + std::to_string(test.height) +
                  " pixels but the reference " + nameOr(referenceName, "image") + " is " +
                  std::to_string(reference.width) + "x" + std::to_string(reference.height) +
                  " pixels; images must be the same size to compare");
}

double ssim(const HdrImage& a, const HdrImage& b, double dynamicRange) {
  checkLayout(a);
  checkLayout(b);
  checkSameSize(a, b, "", "");
  return maskedSsim(a, b, comparedMask(a, b), dynamicRange);
}

ImageComparison compareImages(const HdrImage& test, const HdrImage& reference,
                              const CompareOptions& options) {
  checkLayout(test);
  checkLayout(reference);
  checkSameSize(test, reference, options.testName, options.referenceName);
  ImageComparison c;
  c.width = test.width;
  c.height = test.height;
  c.pixels = test.pixels();
  c.exposureStops = options.exposureStops;
  c.relativeEpsilon = options.relativeEpsilon;
  c.test = countNonFinite(test);
  c.reference = countNonFinite(reference);
  const std::vector<uint8_t> mask = comparedMask(test, reference);
  for (uint8_t m : mask) c.compared += m;

  const double peak = peakOrOne(maxCompared(reference, mask));
  c.linear = pixelStats(test, reference, mask, options.relativeEpsilon, peak);
  c.linear.ssim = maskedSsim(test, reference, mask, peak);

  // Same mask: tone mapping clips Inf to a finite 1, which must not bring the pixel back.
  const HdrImage tt = toneMap(test, options.exposureStops),
                 tr = toneMap(reference, options.exposureStops);
  c.toneMapped = pixelStats(tt, tr, mask, options.relativeEpsilon, 1.0);
  c.toneMapped.ssim = maskedSsim(tt, tr, mask, 1.0);
  return c;
}

Rgb viridis(double t) {
  // viridis sampled at i/9, i = 0..9 (sRGB, 8 bit).
  static constexpr std::array<std::array<int, 3>, 10> kStops = {{{68, 1, 84},
                                                                 {72, 40, 120},
                                                                 {62, 74, 137},
                                                                 {49, 104, 142},
                                                                 {38, 130, 142},
                                                                 {31, 158, 137},
                                                                 {53, 183, 121},
                                                                 {109, 205, 89},
                                                                 {180, 222, 44},
                                                                 {253, 231, 37}}};
  if (!(t > 0)) t = 0;  // also NaN
  if (t > 1) t = 1;
  const double f = t * double(kStops.size() - 1);
  const size_t i = std::min(size_t(f), kStops.size() - 2);
  const double u = f - double(i);
  Rgb c;
  for (int k = 0; k < 3; ++k)
    c[k] = float(((1 - u) * kStops[i][size_t(k)] + u * kStops[i + 1][size_t(k)]) / 255.0);
  return c;
}

HdrImage errorFalseColour(const HdrImage& test, const HdrImage& reference,
                          const ErrorImageOptions& o, const CompareOptions& names) {
  checkLayout(test);
  checkLayout(reference);
  checkSameSize(test, reference, names.testName, names.referenceName);
  if (!(o.minRelative > 0) || !(o.maxRelative > o.minRelative) || !std::isfinite(o.maxRelative))
    throw Error("", "error image range",
                "needs 0 < min < max, got " + shortNumber(o.minRelative) + " .. " +
                    shortNumber(o.maxRelative));
  if (!(o.epsilon > 0) || !std::isfinite(o.epsilon))
    throw Error("", "error image epsilon", "must be positive, got " + shortNumber(o.epsilon));
  const double lo = std::log10(o.minRelative), span = std::log10(o.maxRelative) - lo;
  HdrImage out(test.width, test.height);
  forRows(test.height, [&](int y) {
    for (int x = 0; x < test.width; ++x) {
      const size_t i = size_t(y) * test.width + x;
      const float* a = &test.rgb[3 * i];
      const float* b = &reference.rgb[3 * i];
      if (!finitePixel(a) || !finitePixel(b)) {
        out.set(x, y, Rgb(1, 0, 1));
        continue;
      }
      double e = 0;
      for (int k = 0; k < 3; ++k)
        e += std::abs(double(a[k]) - b[k]) / (std::abs(double(b[k])) + o.epsilon);
      e /= 3;
      // log10(0) is -inf, which viridis clamps to the bottom of the scale as it should.
      out.set(x, y, viridis((std::log10(e) - lo) / span));
    }
  });
  return out;
}

ErrorImageLegend writeErrorImage(const std::string& pngPath, const HdrImage& test,
                                 const HdrImage& reference, const ErrorImageOptions& options,
                                 const CompareOptions& names) {
  writePng(pngPath, errorFalseColour(test, reference, options, names));
  return ErrorImageLegend{options.minRelative, options.maxRelative, options.epsilon};
}

std::string ErrorImageLegend::describe() const {
  return "per-pixel relative error |t-r|/(|r|+" + shortNumber(epsilon) +
         "), mean of R,G,B, log scale from " + shortNumber(minRelative) + " (dark purple) to " +
         shortNumber(maxRelative) +
         " (yellow), viridis; values beyond clamp; magenta = non-finite pixel";
}

nlohmann::json jsonNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return v;
}

nlohmann::json toJson(const ErrorStats& s) {
  return {{"mse", jsonNumber(s.mse)},
          {"rmse", jsonNumber(s.rmse)},
          {"mean_absolute", jsonNumber(s.meanAbsolute)},
          {"max_absolute", jsonNumber(s.maxAbsolute)},
          {"relative_mse", jsonNumber(s.relativeMse)},
          {"mean_relative", jsonNumber(s.meanRelative)},
          {"psnr_db", jsonNumber(s.psnr)},
          {"ssim", jsonNumber(s.ssim)},
          {"peak", jsonNumber(s.peak)}};
}

nlohmann::json toJson(const ImageComparison& c) {
  auto nonFinite = [](const NonFiniteCount& n) {
    return nlohmann::json{{"pixels", n.pixels}, {"nan", n.nan}, {"inf", n.inf}};
  };
  return {{"width", c.width},
          {"height", c.height},
          {"pixels", c.pixels},
          {"compared_pixels", c.compared},
          {"non_finite", {{"test", nonFinite(c.test)}, {"reference", nonFinite(c.reference)}}},
          {"relative_epsilon", jsonNumber(c.relativeEpsilon)},
          {"exposure_stops", jsonNumber(c.exposureStops)},
          {"tone_map", "2^exposure, clamp to [0,1], sRGB OETF"},
          {"linear", toJson(c.linear)},
          {"tone_mapped", toJson(c.toneMapped)}};
}

nlohmann::json toJson(const ErrorImageLegend& l) {
  return {{"min_relative", jsonNumber(l.minRelative)},
          {"max_relative", jsonNumber(l.maxRelative)},
          {"epsilon", jsonNumber(l.epsilon)},
          {"scale", "log10"},
          {"colour_map", "viridis"},
          {"non_finite_colour", "magenta"},
          {"description", l.describe()}};
}

double relativeL2(const HdrImage& t, const HdrImage& r) {
  NL_CHECK(t.rgb.size() == r.rgb.size());
  double d = 0, n = 0;
  for (size_t i = 0; i < t.rgb.size(); ++i) {
    double e = double(t.rgb[i]) - r.rgb[i];
    if (std::isfinite(e)) d += e * e, n += double(r.rgb[i]) * r.rgb[i];
  }
  return n > 0 ? std::sqrt(d / n) : (d > 0 ? INFINITY : 0);
}

HdrImage boxFilter(const HdrImage& img, int k) {
  NL_CHECK(k >= 1);
  const int w = (img.width + k - 1) / k, h = (img.height + k - 1) / k;
  HdrImage out(w, h);
  for (int by = 0; by < h; ++by)
    for (int bx = 0; bx < w; ++bx) {
      double sum[3] = {0, 0, 0};
      int n[3] = {0, 0, 0};
      for (int y = by * k; y < std::min(img.height, by * k + k); ++y)
        for (int x = bx * k; x < std::min(img.width, bx * k + k); ++x)
          for (int c = 0; c < 3; ++c) {
            const float v = img.rgb[3 * (size_t(y) * img.width + x) + c];
            if (std::isfinite(v)) sum[c] += v, ++n[c];
          }
      for (int c = 0; c < 3; ++c)
        out.rgb[3 * (size_t(by) * w + bx) + c] =
            n[c] ? float(sum[c] / n[c]) : std::numeric_limits<float>::quiet_NaN();
    }
  return out;
}

}  // namespace nestlight::gi
