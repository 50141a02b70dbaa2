// The exposure search of HDR expansion (Sabbadin, Palma, Banterle, Boubekeur and Cignoni, "High
// Dynamic Range Point Clouds for Real-Time Relighting", 2019, section 4.1, eq. 1 and 2): the
// exposure e that makes the HDR photograph, clamped to [0, 1] after scaling by e (eq. 2), look
// most like the scan's LDR colour, judged by the Wasserstein distance between 128-bin luminance
// histograms (CIE XYZ's Y of linear colour). Log2(e) is sampled uniformly (100 samples) over a
// range that halves around the best sample at each iteration, until the distance stops
// decreasing or 10 iterations; the first range is the photograph's own: from the exposure that
// brings its brightest luminance to 1 to the one that brings its darkest to 1.
#pragma once

#include <cstdint>
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
  int samples = 100;     // per iteration, uniform in log2 exposure
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

}  // namespace nestlight::gi::hdr
