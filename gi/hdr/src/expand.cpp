// HDR expansion, Algorithm 1 of Sabbadin, Palma, Banterle, Boubekeur and Cignoni, "High Dynamic
// Range Point Clouds for Real-Time Relighting" (2019), section 4 (see expand.h for the stages
// and colour conventions): the public entry points. The stages of one expansion, and the state
// they share, are in expand/ (expansion.h); automaticViews places the cube maps of step 1.
#include "nestlight/gi/hdr/expand.h"

#include <algorithm>
#include <cmath>

#include "expand/expansion.h"
#include "nestlight/gi/hdr/exposure.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/octree/colour_layer.h"

namespace nestlight::gi::hdr {

namespace fs = std::filesystem;
using json = nlohmann::json;

const char* expansionModeName(ExpansionMode m) {
  return m == ExpansionMode::Rgb ? "rgb" : "luminance";
}

json ExpandReport::toJson() const {
  json v = json::array();
  for (const auto& view : views) v.push_back(view.name);
  return {{"log2_exposure", log2Exposure},
          {"exposure_distance", exposureDistance},
          {"views", v},
          {"points", points},
          {"nodes", nodes},
          {"overexposed_points", overexposed},
          {"expanded_points", projected},
          {"unseen_points", unseen},
          {"rejected_match_points", rejectedMatches},
          {"infilled_points", infilled},
          {"islands", islands},
          {"island_points", islandPoints},
          {"infill_chunks", chunks},
          {"infill_chunk_max_points", chunkMaxPoints},
          {"cg_iterations_max", cgIterationsMax},
          {"matched_pixels", matchedPixels},
          {"covered_pixels", coveredPixels},
          {"blind_pixels", blindPixels},
          {"background_pixels", backgroundPixels},
          {"stray_pixels", strayPixels},
          {"max_value", maxValue},
          {"bounded_values", boundedValues},
          {"exposure", checks.toJson()},
          {"warnings", warnings},
          {"clamped_values", clampedValues},
          {"seconds", seconds},
          {"peak_rss_bytes", peakRssBytes}};
}

json ExposureChecks::toJson() const {
  return {
      {"method", method},       {"histogram_log2", histogramLog2},   {"spread_stops", spreadStops},
      {"slope", slope},         {"highlight_slope", highlightSlope}, {"pairs", pairs},
      {"rematches", rematches}, {"range_log2", {rangeLo, rangeHi}},  {"photo_max", photoMax},
      {"bound", bound},         {"matched_share", matchedShare},     {"failed", failed}};
}

glm::vec3 landisExpand(const glm::vec3& ldr, double threshold, double maxLuminance,
                       double exponent) {
  const double y = luminance(ldr);
  if (!(y > threshold) || threshold >= 1) return ldr;
  const double k = std::pow(std::min(1.0, (y - threshold) / (1 - threshold)), exponent);
  const double expanded = (1 - k) * y + k * maxLuminance * y;
  return ldr * float(expanded / y);
}

std::vector<View> automaticViews(const std::vector<glm::dvec3>& positions,
                                 const std::vector<glm::vec3>& normals,
                                 const glm::dvec3& scanCentre, double scanDiagonal, int count,
                                 int faceSize) {
  std::vector<View> views;
  if (count <= 0) return views;
  if (positions.empty()) {
    // Nothing is over-exposed: one cube map at the centre still gives the in-fill its context.
    for (auto& f : cubeMap("auto0", scanCentre, faceSize)) views.push_back(f);
    return views;
  }
  // k-means (Lloyd, 10 rounds) seeded by farthest points: clusters of over-exposed surface.
  std::vector<glm::dvec3> centres{positions[0]};
  while (int(centres.size()) < count && centres.size() < positions.size()) {
    size_t best = 0;
    double bestD = -1;
    for (size_t i = 0; i < positions.size(); ++i) {
      double d = INFINITY;
      for (const auto& c : centres) d = std::min(d, glm::length(positions[i] - c));
      if (d > bestD) bestD = d, best = i;
    }
    if (bestD <= 0) break;
    centres.push_back(positions[best]);
  }
  std::vector<size_t> label(positions.size(), 0);
  for (int round = 0; round < 10; ++round) {
    for (size_t i = 0; i < positions.size(); ++i) {
      double bestD = INFINITY;
      for (size_t c = 0; c < centres.size(); ++c)
        if (const double d = glm::length(positions[i] - centres[c]); d < bestD)
          bestD = d, label[i] = c;
    }
    std::vector<glm::dvec3> sum(centres.size(), glm::dvec3(0));
    std::vector<size_t> n(centres.size(), 0);
    for (size_t i = 0; i < positions.size(); ++i) sum[label[i]] += positions[i], n[label[i]]++;
    for (size_t c = 0; c < centres.size(); ++c)
      if (n[c]) centres[c] = sum[c] / double(n[c]);
  }
  for (size_t c = 0; c < centres.size(); ++c) {
    glm::dvec3 normalSum(0);
    double extent = 0;
    size_t n = 0;
    for (size_t i = 0; i < positions.size(); ++i) {
      if (label[i] != c) continue;
      n++;
      extent = std::max(extent, glm::length(positions[i] - centres[c]));
      if (!normals.empty()) normalSum += glm::dvec3(normals[i]);
    }
    if (n == 0) continue;
    // A 90-degree face sees a disc of radius d at distance d: stand back by the cluster's
    // extent, at least 5% of the scan, at most a quarter of it.
    const double distance = std::clamp(extent * 1.2, 0.05 * scanDiagonal, 0.25 * scanDiagonal);
    glm::dvec3 dir;
    if (glm::length(normalSum) > 0.3 * double(n)) {
      dir = glm::normalize(normalSum);
    } else {
      dir = scanCentre - centres[c];
      dir = glm::length(dir) > 1e-9 ? glm::normalize(dir) : glm::dvec3(0, 0, 1);
    }
    for (auto& f : cubeMap("auto" + std::to_string(c), centres[c] + dir * distance, faceSize))
      views.push_back(f);
  }
  return views;
}

ExpandReport expandHdr(const fs::path& dir, const HdrImage& photo, const ExpandOptions& o) {
  const auto t0 = expand::Clock::now();
  if (o.writeLayer) checkLayerName(o.layerName);  // before hours of work, not after
  return expand::Expansion(dir, photo, o, t0).run();
}

}  // namespace nestlight::gi::hdr
