// HDR expansion of a scan's colour from one HDR photograph, out of core: Sabbadin, Palma,
// Banterle, Boubekeur and Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting"
// (2019), section 4, Algorithm 1:
//   1. LDR renderings of the scan from views that see its over-exposed points (renderings.h);
//   2. the photograph's exposure that best matches the scan's colour (exposure.h, eq. 1-2);
//   3. generalised PatchMatch from each rendering to the exposed photograph (patchmatch.h), and
//      the HDR mapping: the photograph's HDR values at the matches, times that exposure;
//   4. back-projection onto the points whose LDR luminance exceeds t_l = 0.9: over the views that
//      see a point, the median weighted by match quality (SSD; matches above t_h = 1 rejected),
//      where the paper takes the weighted mean (expand/back_projection.cpp says why);
//   5. gradient-domain in-fill (eq. 3) of the over-exposed points left without a valid value,
//      over the k = 16 nearest-neighbour graph (poisson_infill.h), chunk by chunk;
//   6. the result written as the octree's "hdr" colour layer (colour_layer.h), atomically.
// Colours are linear (gamma 2.2 removed from the scan's colour, as the paper), in the units of
// the scan's LDR colour: 1 is where the scan's camera clipped.
//
// Memory is bounded independently of the scan's size: nodes stream through every pass, per-point
// results go to a scratch file (16 bytes a point), and the in-fill solves one spatial chunk (its
// points plus an overlap margin) at a time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/hdr/views.h"
#include "nestlight/gi/hdr_image.h"

namespace nestlight::gi::hdr {

enum class ExpansionMode { Luminance, Rgb };  // the paper's PMATCHLUM and PMATCHRGB
const char* expansionModeName(ExpansionMode m);

struct ExpandOptions {
  ExpansionMode mode = ExpansionMode::Rgb;
  std::vector<View> views;  // given views; empty: automatic
  // The photograph's own camera, when it is registered with the scan: the scan is also rendered
  // from it, PatchMatch starts that rendering from the identity (PatchMatchOptions::identityStart)
  // and the points it matched take their colour from it alone (the photograph is direct evidence
  // there; other views only reach what it did not match). It is rendered at the size PatchMatch
  // sees the photograph at and must have the photograph's aspect.
  std::optional<View> photoView;
  // The photograph's pixels that show the scanned scene (non-zero) and those that do not (sky,
  // lamps or buildings beyond the scan, people, the tripod): one entry per photograph pixel, row
  // by row; empty: all of them. Masked-out pixels count for nothing: not in the exposure's
  // histogram or pairs, not in its plausible range or the bound, and no match may land on them.
  std::vector<uint8_t> photoMask;
  int photoSearchRadius =
      0;  // pixels: how far the photo view's matches may move from the identity (0: anywhere)
  // Deviation from the paper, measured (docs/HDR.md): a match whose source patch is over-exposed
  // in every pixel says nothing (inside a clipped region every white patch of the photograph
  // matches with SSD 0: a sunlit floor takes a lamp's values), so it is rejected and its points
  // are in-filled from the region's rim instead. The photograph's own view is exempt (its
  // matches start registered). false: the paper's back-projection.
  bool rejectBlindPatches = true;
  // Unregistered: a clipped pixel's matched value above this many times the median of the matched
  // values within localRadius pixels (and above the clipping) is rejected and in-filled instead;
  // 0 keeps every match.
  double maxLocalRatio = 8.0;
  int localRadius = 4;
  int autoViews = 1;         // cube maps placed automatically when `views` is empty
  int faceSize = 384;        // cube-map face size of automatic views (pixels)
  double overexposed = 0.9;  // t_l: LDR luminance (linear) above which a point is expanded
  double maxSsd = 1.0;       // t_h: matches with a larger patch SSD are rejected
  int patchRadius = 3;       // 7 x 7 patches
  int patchIterations = 5;
  int maxPhotoSize = 768;  // the photograph is box-filtered down to at most this (long side)
  int neighbours = 16;     // k of the in-fill graph
  // In-fill chunk budget (points, margin excluded). Memory follows it: at 100 M protocol points
  // (4.6 M in-filled) 1.5 M gave a peak of 1.4 GiB, 500 k gives 394 MiB and runs faster (smaller
  // systems converge in fewer CG iterations).
  uint64_t chunkPoints = 500'000;
  // The photograph's exposure (log2), forced: no estimate; the checks are still measured and
  // recorded but do not stop the expansion (the caller vouches for it).
  std::optional<double> log2Exposure;
  // The checks of the exposure and of the matches (ExposureChecks). When one fails the expansion
  // stops with an error saying which and what to pass, unless `force` (the layer is written and
  // the failures become warnings).
  bool force = false;
  // Spread (robust standard deviation, stops) of the log ratios between the scan and the
  // photograph over the pairs the renderings explain. The protocol's pure exposure change
  // measures about 0.1 (8-bit renderings, splat edges); a gamma of 1.4 on the photograph's tone
  // about 0.6 and sends the clipped points stops beyond the truth (tests/gi/hdr/expand_test.cpp).
  double maxSpreadStops = 0.4;
  // Largest highlight slope (PairEstimate::highlightSlope) accepted: 1 is an exposure change; a
  // photograph whose highlights grow faster than the scan's overshoots beyond the clipping. The
  // margin covers the 8-bit renderings' quantisation (measured 1.0 to 1.05 on pure exposures).
  double maxHighlightSlope = 1.15;
  // The exposed photograph's largest value must reach this many times the scan's clipping: below
  // it the photograph holds nothing the scan did not record (a histogram match that paired the
  // scan's clipping with a bright background lands at 1).
  double minHeadroom = 1.41421356;  // half a stop
  uint64_t minPairs = 100;          // pairs the exposure must rest on
  // Share of the over-exposed points that the renderings see and that took a matched value: below
  // it the in-fill extrapolates the whole clipped range from a handful of matches.
  double minMatchedShare = 0.05;
  std::filesystem::path scratchDir;  // per-point scratch file; empty: the octree folder
  std::string layerName = "hdr";
  bool writeLayer = true;
  // Optional outputs for inspection (empty: none): renderings, matches, expanded renderings.
  std::filesystem::path debugDir;
  nlohmann::json commandLine;
  std::function<void(const std::string& stage, double fraction)> progress;
};

// How the exposure was found and the checks that decide whether the layer is trusted.
struct ExposureChecks {
  // "photo-view": pairs of the photograph's own view where the scan covers it; "matches": pairs
  // at PatchMatch's matches under t_h; "forced": --exposure.
  std::string method;
  // The histogram search's answer (eq. 1-2), unregistered only (NaN, null in JSON: not run)
  double histogramLog2 = std::numeric_limits<double>::quiet_NaN();
  double spreadStops = 0, slope = 1, highlightSlope = 1;
  uint64_t pairs = 0;
  int rematches = 0;  // PatchMatch runs repeated at a corrected exposure
  // Plausible range of log2 e: the exposed photograph must reach the scan's clipping (t_l) with
  // its brightest value and keep its darkest percentile under it (else it is all clipped).
  double rangeLo = 0, rangeHi = 0;
  double photoMax = 0;  // the photograph's largest finite channel
  // The layer's values are clamped to max(1, e * the photograph's largest value; registered,
  // its largest where the scan renders)
  double bound = 0;
  double matchedShare =
      -1;  // of the over-exposed points, the share that took a match (-1: not reached)
  std::vector<std::string> failed;  // the checks that failed, each a sentence with its numbers
  nlohmann::json toJson() const;
};

struct ExpandReport {
  double log2Exposure = 0, exposureDistance = 0;
  bool exposureUsable = false;
  ExposureChecks checks;
  uint64_t boundedValues = 0;         // channels clamped to checks.bound
  std::vector<std::string> warnings;  // failed checks written anyway (force)
  std::vector<View> views;
  uint64_t points = 0, nodes = 0;
  uint64_t overexposed = 0;                // LDR luminance above t_l
  uint64_t projected = 0;                  // of those, given a matched HDR value
  uint64_t unseen = 0;                     // over-exposed, seen by no view
  uint64_t rejectedMatches = 0;            // over-exposed, seen, but every match above t_h
  uint64_t infilled = 0;                   // solved by the in-fill
  uint64_t islands = 0, islandPoints = 0;  // in-fill components with no valid neighbour: LDR kept
  uint64_t chunks = 0, chunkMaxPoints = 0;
  uint64_t cgIterationsMax = 0;
  uint64_t matchedPixels = 0, coveredPixels = 0;
  uint64_t blindPixels = 0;  // matches rejected because their whole patch was over-exposed
  // Registered: matches rejected because they landed where the scan does not render in the
  // photograph's own view (background the scan lacks)
  uint64_t backgroundPixels = 0;
  // Unregistered: matches rejected because their value was more than maxLocalRatio times the
  // median of the matched values around them (a light the scan lacks)
  uint64_t strayPixels = 0;
  double maxValue = 0;  // largest channel written
  uint64_t clampedValues = 0;
  nlohmann::json seconds;  // per stage
  uint64_t peakRssBytes = 0;
  nlohmann::json toJson() const;
};

// Expands the scan at `octree` with `photo` (linear HDR). Throws nestlight::Error for unusable
// input (no rgb, a black photograph, views that see nothing).
ExpandReport expandHdr(const std::filesystem::path& octree, const HdrImage& photo,
                       const ExpandOptions& options);

// Views placed automatically: `count` cube maps looking at clusters of the given over-exposed
// positions (k-means), each moved off its cluster along the cluster's mean normal (or towards
// the scan's centre when normals are missing or disagree) so that the cluster fills a face.
std::vector<View> automaticViews(const std::vector<glm::dvec3>& positions,
                                 const std::vector<glm::vec3>& normals,
                                 const glm::dvec3& scanCentre, double scanDiagonal, int count,
                                 int faceSize);

// Global inverse tone mapping of one linear LDR colour (Landis, "Production-ready global
// illumination", 2002, as the paper's LANDIS-PC baseline): luminances above `threshold` are
// pushed towards `maxLuminance` with an exponent-2 blend; chromaticity kept.
glm::vec3 landisExpand(const glm::vec3& ldr, double threshold, double maxLuminance,
                       double exponent = 2.0);

}  // namespace nestlight::gi::hdr
