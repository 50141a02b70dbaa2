// HDR expansion of a scan's colour from one HDR photograph, out of core: Sabbadin, Palma,
// Banterle, Boubekeur and Cignoni, "High Dynamic Range Point Clouds for Real-Time Relighting"
// (2019), section 4, Algorithm 1:
//   1. LDR renderings of the scan from views that see its over-exposed points (renderings.h);
//   2. the photograph's exposure that best matches the scan's colour (exposure.h, eq. 1-2);
//   3. generalised PatchMatch from each rendering to the exposed photograph (patchmatch.h), and
//      the HDR mapping: the photograph's HDR values at the matches, times that exposure;
//   4. back-projection onto the points whose LDR luminance exceeds t_l = 0.9: over the views that
//      see a point, the median weighted by match quality (SSD; matches above t_h = 1 rejected),
//      where the paper takes the weighted mean (expand.cpp says why);
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
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/gi/hdr/views.h"
#include "nestlight/gi/hdr_image.h"

namespace nestlight::gi::hdr {

enum class ExpansionMode { Luminance, Rgb };  // the paper's PMATCHLUM and PMATCHRGB
const char* expansionModeName(ExpansionMode m);

struct ExpandOptions {
  ExpansionMode mode = ExpansionMode::Rgb;
  std::vector<View> views;   // given views; empty: automatic
  // The photograph's own camera, when it is registered with the scan: the scan is also rendered
  // from it, PatchMatch starts that rendering from the identity (PatchMatchOptions::identityStart)
  // and the points it matched take their colour from it alone (the photograph is direct evidence
  // there; other views only reach what it did not match). It is rendered at the size PatchMatch
  // sees the photograph at and must have the photograph's aspect.
  std::optional<View> photoView;
  int photoSearchRadius = 0;  // pixels: how far the photo view's matches may move from the identity (0: anywhere)
  // Deviation from the paper, measured (docs/HDR.md): a match whose source patch is over-exposed
  // in every pixel says nothing (inside a clipped region every white patch of the photograph
  // matches with SSD 0: a sunlit floor takes a lamp's values), so it is rejected and its points
  // are in-filled from the region's rim instead. The photograph's own view is exempt (its
  // matches start registered). false: the paper's back-projection.
  bool rejectBlindPatches = true;
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
  std::filesystem::path scratchDir;  // per-point scratch file; empty: the octree folder
  std::string layerName = "hdr";
  bool writeLayer = true;
  // Optional outputs for inspection (empty: none): renderings, matches, expanded renderings.
  std::filesystem::path debugDir;
  nlohmann::json commandLine;
  std::function<void(const std::string& stage, double fraction)> progress;
};

struct ExpandReport {
  double log2Exposure = 0, exposureDistance = 0;
  bool exposureUsable = false;
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
