// The captured radiance of a generated scene's scan points, the ground truth of differential
// rendering (Rohmer, Jendersie and Grosch, "Natural Environment Illumination: Coherent
// Interactive Augmented Reality for Mobile and Non-Mobile Devices", IEEE TVCG 2017): in a scene
// whose scan colours are albedos (the albedo mode), the radiance each point sends out when the
// inserted meshes are absent is what a scanner would have recorded there. Estimated with the
// path-traced reference (traceFromSurface) and written as a colour layer, so that a scene that
// selects the layer in the radiance-cache mode shows it as the capture.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "nestlight/gi/scene.h"

namespace nestlight::gi {

struct RadianceBakeOptions {
  std::string layer;           // the colour layer written into each scan's octree
  int samplesPerPoint = 64;    // paths per point (at least 2: the standard error needs two)
  int maxBounces = 4;          // scattering events, the point's own the first (1: direct only)
  uint64_t seed = 1;           // the same seed gives the same layer, whatever the threads
  nlohmann::json commandLine;  // recorded in the layer's build notes
  // Points done of the total, from one thread at a time, every few hundred points.
  std::function<void(uint64_t done, uint64_t total)> progress;
  void (*log)(const std::string&) = nullptr;  // the reference scene's loading, line by line
};

struct RadianceBakeReport {
  uint64_t points = 0;
  // Mean over points of the estimate's standard error over its value, on the mean of the three
  // channels (sample variance of the paths / samples, square-rooted); points whose estimate is 0
  // (no light reaches them, or black albedo) have no relative error and are left out.
  double meanRelativeStandardError = 0;
  uint64_t blackPoints = 0;       // points left out of the mean for a zero estimate
  uint64_t nonFiniteSamples = 0;  // paths dropped as NaN/Inf (should stay 0)
  uint64_t clampedValues = 0;     // channels beyond the layer's range (ColourLayerWriter)
  uint64_t rays = 0;
  size_t meshesLeftOut = 0;  // the inserted meshes
  double maxValue = 0;       // the brightest channel written
  double seconds = 0;
  nlohmann::json toJson() const;
};

// For every point of every scan of `scene` (every level, whatever octrees[].max_level says), the
// Lambertian radiance it sends towards its normal's side, lit by the scene's lights, environment
// and emissive meshes, with the meshes marked `inserted` left out; albedo = the point's colour as
// the reference reads it in the albedo mode. Written as colour layer `options.layer` of each
// scan's octree (atomically), the report as the layer's build notes. Throws nestlight::Error
// naming the scene file and field when the scene has no scans, is not in the albedo mode, a
// scan has no normals or does not fit its memory budget whole, the layer name is reserved or is
// the scan's albedo source; naming the octree when it cannot be written.
RadianceBakeReport bakeRadiance(const Scene& scene, const RadianceBakeOptions& options);

}  // namespace nestlight::gi
