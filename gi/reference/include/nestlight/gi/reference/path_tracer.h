// The path-traced reference (ground truth for every GI method): unidirectional path tracing
// with next-event estimation towards the lights and the environment, multiple importance
// sampling (power heuristic) between environment and BSDF sampling, Russian roulette after
// three bounces. Progressive: samples are split into two independent halves whose difference
// estimates the remaining error, and rendering stops on an error target, a time limit or a
// sample budget.
//
// Radiance modes (issue 4; paper 000 section 5): in the radiance cache mode a ray that reaches
// a scan disc takes the disc's recorded colour as emitted radiance and ends there, as PBGI
// treats the scan; in the albedo mode discs are Lambert reflectors with the recorded colour as
// albedo, lit by the lights and the environment like everything else.
#pragma once

#include <functional>
#include <string>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/shared/reference_scene.h"

namespace nestlight::gi {

struct ReferenceOptions {
  RadianceMode mode = RadianceMode::RadianceCache;
  int maxBounces = 4;  // scattering events; 1 = direct lighting only
  int maxSamplesPerPixel = 256;
  double targetRelativeError = 0;  // relative L2 error estimate to stop at (0: off)
  double timeLimitSeconds = 0;     // 0: off
  uint64_t seed = 1;
  int minSamplesPerPixel = 4;  // before the error estimate is trusted
  // Camera rays through pixel centres only (no anti-aliasing): the ground truth of a method that
  // shades pixel centres (the GL methods), so that an error measures shading, not the spread of
  // radiance across a pixel (a sharp highlight's pixel mean differs from its centre's value).
  bool pixelCentres = false;
};

struct ReferenceProgress {
  int samplesPerPixel = 0;
  double relativeError = 0;  // NaN until both halves have samples
  double seconds = 0;
  uint64_t rays = 0;
};

struct ReferenceResult {
  HdrImage image;
  int samplesPerPixel = 0;
  double relativeError = 0;  // the half-buffer estimate at the end
  double seconds = 0;
  uint64_t rays = 0;              // camera, extension and shadow rays
  uint64_t nonFiniteSamples = 0;  // samples dropped as NaN/Inf (should stay 0)
  std::string stopReason;         // "error target", "time limit", "samples", "cancelled"
  double raysPerSecond() const { return seconds > 0 ? rays / seconds : 0; }
  double samplesPerSecond() const {
    return seconds > 0 ? double(samplesPerPixel) * image.pixels() / seconds : 0;
  }
};

// The estimate of ||mean - truth|| / ||mean|| from two independent half-sample images: the
// difference of the halves has twice the variance of one half, the mean of both half of it, so
// ||A - B|| / 2 estimates the mean's error (over all pixels and channels).
double halfBufferRelativeError(const HdrImage& a, const HdrImage& b);

// `progress` is called after every pass; returning false stops the render ("cancelled").
ReferenceResult renderReference(const ReferenceScene& scene, const SceneCamera& camera,
                                const ReferenceOptions& options,
                                const std::function<bool(const ReferenceProgress&)>& progress = {});

// One path's radiance along a ray (local frame). For tests and other integrators.
Rgb traceRadiance(const ReferenceScene& scene, const glm::vec3& origin, const glm::vec3& direction,
                  Rng& rng, const ReferenceOptions& options, uint64_t* rays = nullptr);

// One path's radiance leaving `surface` towards `wo` (unit, on the side it is seen from), as
// traceRadiance would return it for a ray that reached `surface` from there: the surface's
// emission, if any, plus up to maxBounces scattering events, the first at `surface`. `surface`
// is a hit as ReferenceScene::intersect fills it (kind, position, normals, colour, radius and
// thickness, which set the offset its rays leave from). For the radiance of given scan points.
Rgb traceFromSurface(const ReferenceScene& scene, const SurfaceHit& surface, const glm::vec3& wo,
                     Rng& rng, const ReferenceOptions& options, uint64_t* rays = nullptr);

// The camera ray through image position (x, y) in pixels (top row first, x to the right).
void cameraRay(const SceneCamera& camera, const glm::dvec3& origin, float x, float y,
               glm::vec3* rayOrigin, glm::vec3* rayDirection);

ReferenceOptions referenceOptionsFrom(const GiSettings& gi);

}  // namespace nestlight::gi
