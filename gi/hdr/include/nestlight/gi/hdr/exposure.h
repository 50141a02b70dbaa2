// The exposure search of HDR expansion (Sabbadin, Palma, Banterle, Boubekeur and Cignoni, "High
// Dynamic Range Point Clouds for Real-Time Relighting", 2019, section 4.1, eq. 1 and 2): the
// exposure e that makes the HDR photograph, clamped to [0, 1] after scaling by e (eq. 2), look
// most like the scan's LDR colour, judged by the Wasserstein distance between 128-bin luminance
// histograms (CIE XYZ's Y of linear colour). Log2(e) is sampled uniformly (100 samples) over a
// range that halves around the best sample at each iteration, until the distance stops
// decreasing or 10 iterations; the first range is the photograph's own: from the exposure that
// brings its brightest luminance to 1 to the one that brings its darkest to 1.
//
// The histogram search pairs whole distributions: when the photograph's frame holds background
// the scan lacks (sky, a lamp outside the scan), or its tone curve is not a pure exposure change,
// it pairs the scan's mid-tones with that background and lands stops away. So the exposure the
// expansion uses comes from pixel pairs the renderings explain (estimateExposureFromPairs): the
// rendering from the photograph's own camera where the scan covers it, or PatchMatch's matches
// that pass the quality threshold; the histogram search only starts the unregistered case.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

namespace nestlight::gi::hdr {

constexpr int kHistogramBins = 128;

// A normalised histogram of luminances in [0, 1] (values outside are clamped into the end bins;
// non-finite values are skipped). All zeros when no value counts.
struct Histogram {
  std::vector<double> mass = std::vector<double>(kHistogramBins, 0.0);  // sums to 1 (or 0)
  uint64_t counted = 0;
  uint64_t skipped = 0;  // non-finite
};

Histogram luminanceHistogram(const std::vector<float>& luminance);
// The same of clamp(exposure * luminance, 0, 1), eq. 2.
Histogram exposedHistogram(const std::vector<float>& hdrLuminance, double exposure);

// The 1-Wasserstein (earth mover's) distance between two histograms over [0, 1]: the area
// between their cumulative distributions. Histograms that are empty give 1 (the largest).
double wasserstein(const Histogram& a, const Histogram& b);

struct ExposureSearchOptions {
  int samples = 100;  // per iteration, uniform in log2 exposure
  int maxIterations = 10;
  // The first log2 range; when lo >= hi, the photograph's own (see above).
  double log2Lo = 0, log2Hi = 0;
};

struct ExposureSearch {
  double log2Exposure = 0;  // the best found
  double distance = 1;      // its Wasserstein distance
  int iterations = 0;
  double log2Lo = 0, log2Hi = 0;  // the first range searched
  bool usable = false;  // false: the photograph has no positive finite luminance, or the scan's
                        // histogram is empty (nothing to match)
};

// hdrLuminance: the photograph's linear luminances; ldr: the scan's (renderings') histogram.
ExposureSearch findBestExposure(const std::vector<float>& hdrLuminance, const Histogram& ldr,
                                const ExposureSearchOptions& options = {});

// The exposure from pairs of luminances seen at the same place: the scan's (linear LDR, from a
// rendering) and the photograph's (linear HDR). Only pairs the scan recorded well count (its
// luminance in [minScan, maxScan]: above, clipped; below, quantised by 8-bit display values) and
// whose photograph value is positive, finite and under `photoClip` (a photograph's own
// saturation). log2 e is the median of log2(scan / photo): robust to the pairs a rendering
// explains badly (silhouettes, splat gaps), where a mean or a histogram is pulled along.
struct PairEstimate {
  double log2Exposure = 0;
  // 1.4826 times the median absolute deviation of the log2 ratios (a standard deviation, robust
  // to outliers), in stops: near 0 when the photograph is the scan's colour times one exposure;
  // a tone curve other than an exposure change, or pairs of different things, spread it.
  double spreadStops = 0;
  // The least-squares slope of log2 photo against log2 scan over the same pairs: 1 for a pure
  // exposure change, the curve's gamma otherwise.
  double slope = 1;
  // The same over the brighter half of the pairs (scan luminance above their median): how the
  // photograph's tone runs towards the clipping, where the expansion extrapolates it. Above 1 the
  // photograph's highlights grow faster than the scan's, and the values the expansion fetches
  // beyond the clipping overshoot the truth by a power of it.
  double highlightSlope = 1;
  uint64_t pairs = 0;    // pairs that counted
  uint64_t offered = 0;  // pairs given
  bool usable = false;   // false: no pair counted
};
PairEstimate estimateExposureFromPairs(const std::vector<float>& scanLuminance,
                                       const std::vector<float>& photoLuminance,
                                       double minScan = 0.02, double maxScan = 0.9,
                                       double photoClip = std::numeric_limits<double>::infinity());

}  // namespace nestlight::gi::hdr
