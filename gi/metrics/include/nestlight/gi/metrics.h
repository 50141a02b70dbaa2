// How wrong a rendered image is against a reference (normally gi/reference's path tracer), on
// linear HDR pixels and on the same pixels after the shared tone map (tone_map.h).
//
// References:
//   SSIM: Z. Wang, A. C. Bovik, H. R. Sheikh, E. P. Simoncelli, "Image quality assessment: from
//     error visibility to structural similarity", IEEE Trans. Image Processing 13(4), 2004.
//   relative MSE: F. Rousselle, C. Knaus, M. Zwicker, "Adaptive sampling and reconstruction using
//     greedy error minimization", ACM Trans. Graphics 30(6) (SIGGRAPH Asia), 2011.
//   RMSE as OpenImageIO's `oiiotool --diff` prints it.
//
// Conventions (every number below is over "compared" pixels: those whose three channels are
// finite in both images; the others are counted in NonFiniteCount and never enter a number):
//   MSE    = mean over pixels and channels of (t - r)^2, RMSE = sqrt(MSE)         (t test, r ref)
//   mean absolute error = mean |t - r|, max absolute error = max |t - r|
//   relMSE = mean of (t - r)^2 / (r^2 + eps), eps = 1e-2 (Rousselle et al. 2011): eps keeps black
//            reference pixels from dividing by zero and de-emphasises errors in the dark
//   mean relative error = mean of |t - r| / (|r| + eps), the same eps
//   PSNR   = 10 log10(peak^2 / MSE) dB; +inf when MSE is 0
//   SSIM   = Wang et al. 2004: Gaussian window 11x11, sigma 1.5; K1 = 0.01, K2 = 0.03;
//            C1 = (K1 L)^2, C2 = (K2 L)^2; SSIM per channel, averaged over R, G, B and pixels
//   peak (PSNR) and L (SSIM): 1 for tone-mapped images (display range), the reference's largest
//            compared channel value for linear HDR (there is no fixed white); 1 when that is <= 0.
// SSIM at the border: Wang et al.'s code keeps only pixels whose whole window is inside the
// image. Here every pixel counts and the window is truncated at the border (and around non-finite
// pixels) and renormalised, so the two agree on interior pixels and images narrower than 11
// pixels still get a value.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "nestlight/gi/hdr_image.h"

namespace nestlight::gi {

inline constexpr double kRelativeEpsilon = 1e-2;  // Rousselle et al. 2011
inline constexpr int kSsimWindow = 11;            // Wang et al. 2004
inline constexpr double kSsimSigma = 1.5;
inline constexpr double kSsimK1 = 0.01, kSsimK2 = 0.03;

struct CompareOptions {
  double exposureStops = 0;  // before the tone map, for the tone-mapped metrics
  double relativeEpsilon = kRelativeEpsilon;
  std::string testName, referenceName;  // files, for error messages
};

// One image domain (linear HDR or tone-mapped). NaN when no pixel could be compared.
struct ErrorStats {
  double mse = 0, rmse = 0, meanAbsolute = 0, maxAbsolute = 0;
  double relativeMse = 0, meanRelative = 0;
  double psnr = 0;  // dB
  double ssim = 0;
  double peak = 1;  // PSNR's peak and SSIM's dynamic range L, as used
};

struct NonFiniteCount {
  uint64_t pixels = 0;        // pixels with at least one non-finite channel
  uint64_t nan = 0, inf = 0;  // channel values
};

struct ImageComparison {
  int width = 0, height = 0;
  uint64_t pixels = 0;    // width * height
  uint64_t compared = 0;  // pixels finite in both images
  NonFiniteCount test, reference;
  double exposureStops = 0, relativeEpsilon = kRelativeEpsilon;
  ErrorStats linear, toneMapped;
};

// Throws nestlight::Error naming both files (options' names) when the sizes differ.
ImageComparison compareImages(const HdrImage& test, const HdrImage& reference,
                              const CompareOptions& options = {});

// Mean SSIM with dynamic range L over pixels finite in both images (NaN when none is);
// compareImages says how many were left out. Symmetric in its two images.
double ssim(const HdrImage& a, const HdrImage& b, double dynamicRange);

// Means of k x k blocks (edge blocks of what is there; non-finite values skipped): comparing two
// images box-filtered separates their shading's error from pixel-scale sampling (one sample
// at each pixel's centre against the area average of a path tracer, over noisy recorded colours
// and edges).
HdrImage boxFilter(const HdrImage& img, int k);

// sqrt(sum (t - r)^2 / sum r^2) over all pixels and channels (non-finite differences skipped):
// the relative L2 error the reference's stop rule estimates.
double relativeL2(const HdrImage& test, const HdrImage& reference);

// Throws nestlight::Error("test: is WxH pixels but reference ref is W'xH' pixels").
void checkSameSize(const HdrImage& test, const HdrImage& reference, const std::string& testName,
                   const std::string& referenceName);

// False-colour error image: per pixel the relative error e = mean over channels of
// |t - r| / (|r| + eps), mapped on a log10 scale from minRelative (darkest) to maxRelative
// (brightest) through viridis (van der Walt and Smith, matplotlib 1.5, 2015; perceptually uniform
// and readable in grey and by colour-blind viewers). Errors outside the range clamp to its ends;
// pixels non-finite in either image are magenta, which viridis never produces. Fixed defaults
// rather than the image's own range, so maps of different methods can be compared side by side.
struct ErrorImageOptions {
  double minRelative = 1e-3, maxRelative = 1.0;
  double epsilon = kRelativeEpsilon;
};
struct ErrorImageLegend {
  double minRelative = 1e-3, maxRelative = 1.0, epsilon = kRelativeEpsilon;
  std::string describe() const;  // one line for reports
};
// Display-referred colours in [0, 1], the size of the inputs.
HdrImage errorFalseColour(const HdrImage& test, const HdrImage& reference,
                          const ErrorImageOptions& options = {}, const CompareOptions& names = {});
// Writes errorFalseColour as PNG; returns the legend to write into the report.
ErrorImageLegend writeErrorImage(const std::string& pngPath, const HdrImage& test,
                                 const HdrImage& reference, const ErrorImageOptions& options = {},
                                 const CompareOptions& names = {});
// viridis at t in [0, 1] (clamped): sRGB-encoded display values in [0, 1], piecewise linear
// through ten evenly spaced samples of the map.
Rgb viridis(double t);

// JSON for reports. Non-finite numbers (PSNR of identical images, metrics with nothing compared)
// are the strings "inf", "-inf" and "nan": JSON has no such numbers and null would read as
// "missing".
nlohmann::json toJson(const ErrorStats& s);
nlohmann::json toJson(const ImageComparison& c);
nlohmann::json toJson(const ErrorImageLegend& l);
nlohmann::json jsonNumber(double v);

}  // namespace nestlight::gi
