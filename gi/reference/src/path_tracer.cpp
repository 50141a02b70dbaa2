// Unidirectional path tracing with next-event estimation and multiple importance sampling
// (Veach 1997, chapter 9; pbrt-v4 section 13.4), over discs and triangles. The radiance-cache
// mode follows paper 000 section 5: the scan's recorded colour is the radiance that leaves it.
#include "nestlight/gi/reference/path_tracer.h"

#include <tbb/blocked_range2d.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "nestlight/octree/error.h"
#include "seeds.h"

namespace nestlight::gi {
namespace {

constexpr int kTile = 16;

bool finite(const Rgb& c) {
  return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b);
}
float maxComponent(const Rgb& c) {
  return std::max({c.r, c.g, c.b});
}

// Offsets a ray origin off the surface it leaves, on the side it leaves towards. Relative to
// the scene's coordinate scale (float spacing there) and, for discs, to the disc's size and to
// the scanned surface's thickness there (its neighbours' discs, offset by the scan's noise, would
// shadow it otherwise).
glm::vec3 offsetOrigin(const SurfaceHit& h, const glm::vec3& dir, float sceneExtent) {
  float eps = 1e-5f * sceneExtent + std::max(1e-3f * h.radius, h.thickness);
  glm::vec3 n = h.geometricNormal;
  return h.position + (glm::dot(dir, n) >= 0 ? n : -n) * eps;
}

// Spot falloff: 1 inside the inner cone, 0 outside the outer one, smoothstep between.
float spotFalloff(const Light& l, const glm::vec3& fromLight) {
  float cosTheta = glm::dot(fromLight, glm::normalize(l.direction));
  float cosInner = std::cos(glm::radians(l.innerAngleDegrees)),
        cosOuter = std::cos(glm::radians(l.outerAngleDegrees));
  if (cosTheta >= cosInner) return 1;
  if (cosTheta <= cosOuter) return 0;
  float t = (cosTheta - cosOuter) / std::max(cosInner - cosOuter, 1e-6f);
  return t * t * (3 - 2 * t);
}

}  // namespace

void cameraRay(const SceneCamera& c, const glm::dvec3& origin, float x, float y, glm::vec3* ro,
               glm::vec3* rd) {
  glm::dvec3 f = glm::normalize(c.target - c.eye);
  glm::dvec3 r = glm::normalize(glm::cross(f, c.up));
  glm::dvec3 u = glm::cross(r, f);
  double tanHalf = std::tan(glm::radians(c.fovYDegrees) / 2);
  double aspect = double(c.width) / c.height;
  double sx = (2.0 * x / c.width - 1.0) * tanHalf * aspect;
  double sy = (1.0 - 2.0 * y / c.height) * tanHalf;
  *ro = glm::vec3(c.eye - origin);
  *rd = glm::vec3(glm::normalize(f + sx * r + sy * u));
}

namespace {

// One path along the ray (origin, direction), or, with `start`, from that surface point as if
// the ray had just reached it: the same vertex code serves the camera's paths and the radiance
// leaving a given point (the baked capture).
Rgb tracePath(const ReferenceScene& scene, const SurfaceHit* start, const glm::vec3& origin,
              const glm::vec3& direction, Rng& rng, const ReferenceOptions& opt,
              uint64_t* raysOut) {
  Rgb L(0.0f), beta(1.0f);
  glm::vec3 o = origin, d = direction;
  float prevBsdfPdf = 0;  // 0: the previous vertex was the camera (no MIS weight)
  uint64_t rays = 0;
  const EnvironmentMap& env = scene.environment();
  const bool hasEnv = scene.hasEnvironment();
  const float inf = std::numeric_limits<float>::infinity();
  Material discMaterial;  // albedo mode: Lambert with the disc's colour
  for (int depth = 0;; ++depth) {
    SurfaceHit hit;
    if (depth == 0 && start) {
      hit = *start;
    } else if (++rays; !scene.intersect(o, d, inf, &hit)) {
      if (hasEnv) {
        Rgb Le = env.eval(d);
        float w = prevBsdfPdf > 0 ? powerHeuristic(prevBsdfPdf, env.pdf(d)) : 1.0f;
        L += beta * Le * w;
      }
      break;
    }
    const glm::vec3 wo = -d;
    const Material* mat;
    if (hit.kind == SurfaceHit::Kind::Disc) {
      if (opt.mode == RadianceMode::RadianceCache) {
        // The scan's colour is the radiance leaving it (both sides: scans see surfaces from
        // wherever the scanner stood, and normals of thin parts may face either way).
        L += beta * hit.colour;
        break;
      }
      discMaterial.baseColor = glm::min(hit.colour, Rgb(1.0f));
      mat = &discMaterial;
    } else {
      mat = &scene.materials()[hit.material];
      // Emitters are found by BSDF sampling only (no NEE to emissive meshes): weight 1.
      if (maxComponent(mat->emission) > 0 && glm::dot(hit.geometricNormal, wo) > 0)
        L += beta * mat->emission;
    }
    if (depth >= opt.maxBounces) break;

    // Two-sided shading: the frame faces the outgoing direction.
    glm::vec3 ng = hit.geometricNormal, ns = hit.shadingNormal;
    if (glm::dot(ng, wo) < 0) ng = -ng;
    if (glm::dot(ns, ng) < 0) ns = -ns;
    Material tinted;
    if (hit.kind == SurfaceHit::Kind::Triangle && hit.colour != Rgb(1.0f)) {
      tinted = *mat;
      tinted.baseColor *= hit.colour;
      mat = &tinted;
    }
    const Frame frame = Frame::fromNormal(ns);
    const glm::vec3 woLocal = frame.toLocal(wo);
    if (woLocal.z <= 0) break;  // shading normal turned away from the viewer: no reflection

    // Next-event estimation: every delta light (a handful), then one environment sample.
    for (size_t li = 0; li < scene.lights().size(); ++li) {
      const Light& light = scene.lights()[li];
      glm::vec3 wi;
      Rgb Li;
      float dist;
      if (light.type == LightType::Directional) {
        wi = -glm::normalize(light.direction);
        Li = light.intensity;
        dist = inf;
      } else {
        glm::vec3 toLight = scene.lightPosition(li) - hit.position;
        float d2 = glm::dot(toLight, toLight);
        if (!(d2 > 0)) continue;
        dist = std::sqrt(d2);
        wi = toLight / dist;
        Li = light.intensity / d2;
        if (light.type == LightType::Spot) Li *= spotFalloff(light, -wi);
      }
      if (maxComponent(Li) <= 0) continue;
      glm::vec3 wiLocal = frame.toLocal(wi);
      if (wiLocal.z <= 0 || glm::dot(wi, ng) <= 0) continue;
      Rgb f = evalBsdf(*mat, woLocal, wiLocal);
      if (maxComponent(f) <= 0) continue;
      glm::vec3 so = offsetOrigin(hit, wi, scene.extent());
      ++rays;
      float tMax = std::isinf(dist) ? inf : dist * (1 - 1e-4f);
      if (!scene.occluded(so, wi, tMax)) L += beta * f * Li * wiLocal.z;
    }
    if (hasEnv) {
      EnvironmentMap::Sample s = env.sample(rng.uniform2());
      glm::vec3 wiLocal = frame.toLocal(s.direction);
      if (s.pdf > 0 && wiLocal.z > 0 && glm::dot(s.direction, ng) > 0) {
        Rgb f = evalBsdf(*mat, woLocal, wiLocal);
        if (maxComponent(f) > 0) {
          ++rays;
          if (!scene.occluded(offsetOrigin(hit, s.direction, scene.extent()), s.direction, inf)) {
            float w = powerHeuristic(s.pdf, pdfBsdf(*mat, woLocal, wiLocal));
            L += beta * f * s.radiance * (wiLocal.z * w / s.pdf);
          }
        }
      }
    }

    // Continue the path by BSDF sampling.
    auto bs = sampleBsdf(*mat, woLocal, rng.uniform2(), rng.uniform());
    if (!bs || !(bs->pdf > 0)) break;
    glm::vec3 wi = frame.toWorld(bs->wi);
    if (glm::dot(wi, ng) <= 0)
      break;  // below the geometric surface: light leak through shading normals
    beta *= bs->f * (bs->wi.z / bs->pdf);
    if (!finite(beta) || maxComponent(beta) <= 0) break;
    prevBsdfPdf = bs->pdf;
    o = offsetOrigin(hit, wi, scene.extent());
    d = wi;
    if (depth >= 3) {
      // Russian roulette: unbiased, keeps long paths only where they still carry energy.
      float q = std::max(0.05f, 1 - maxComponent(beta));
      if (rng.uniform() < q) break;
      beta /= 1 - q;
    }
  }
  if (raysOut) *raysOut += rays;
  return L;
}

}  // namespace

Rgb traceRadiance(const ReferenceScene& scene, const glm::vec3& origin, const glm::vec3& direction,
                  Rng& rng, const ReferenceOptions& opt, uint64_t* rays) {
  return tracePath(scene, nullptr, origin, direction, rng, opt, rays);
}

Rgb traceFromSurface(const ReferenceScene& scene, const SurfaceHit& surface, const glm::vec3& wo,
                     Rng& rng, const ReferenceOptions& opt, uint64_t* rays) {
  return tracePath(scene, &surface, surface.position, -wo, rng, opt, rays);
}

double halfBufferRelativeError(const HdrImage& a, const HdrImage& b) {
  NL_CHECK(a.rgb.size() == b.rgb.size());
  double diff = 0, norm = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    double m = 0.5 * (double(a.rgb[i]) + b.rgb[i]);
    double dd = double(a.rgb[i]) - b.rgb[i];
    diff += dd * dd;
    norm += m * m;
  }
  if (norm <= 0) return diff > 0 ? INFINITY : 0;
  return 0.5 * std::sqrt(diff / norm);
}

ReferenceOptions referenceOptionsFrom(const GiSettings& gi) {
  ReferenceOptions o;
  o.mode = gi.mode;
  o.maxBounces = gi.maxBounces;
  o.maxSamplesPerPixel = gi.samplesPerPixel;
  o.targetRelativeError = gi.targetRelativeError;
  o.timeLimitSeconds = gi.timeLimitSeconds;
  o.seed = gi.seed;
  return o;
}

ReferenceResult renderReference(const ReferenceScene& scene, const SceneCamera& camera,
                                const ReferenceOptions& opt,
                                const std::function<bool(const ReferenceProgress&)>& progress) {
  NL_CHECK(camera.width > 0 && camera.height > 0 && opt.maxSamplesPerPixel > 0);
  const int W = camera.width, H = camera.height;
  // Two half-sample sums: even passes go to A, odd passes to B.
  HdrImage sumA(W, H), sumB(W, H);
  int nA = 0, nB = 0;
  ReferenceResult res;
  std::atomic<uint64_t> rays{0}, nonFinite{0};
  auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  HdrImage meanA(W, H), meanB(W, H);
  double relErr = NAN;
  res.stopReason = "samples";
  for (int pass = 0; pass < opt.maxSamplesPerPixel; ++pass) {
    HdrImage& target = (pass % 2 == 0) ? sumA : sumB;
    tbb::parallel_for(tbb::blocked_range2d<int>(0, H, kTile, 0, W, kTile),
                      [&](const tbb::blocked_range2d<int>& r) {
                        uint64_t localRays = 0, localBad = 0;
                        for (int y = r.rows().begin(); y < r.rows().end(); ++y)
                          for (int x = r.cols().begin(); x < r.cols().end(); ++x) {
                            // The sample of pixel (x, y) in pass p is the same whatever the threads
                            // do. Pass and pixel both enter the seed: PCG streams that differ only
                            // in their increment are correlated, and the two half images must be
                            // independent for the error estimate.
                            const uint64_t pixel = uint64_t(y) * W + x;
                            Rng rng(
                                splitMix64(splitMix64(opt.seed * 0x9E3779B97F4A7C15ULL + pixel) ^
                                           (uint64_t(pass) * 0xD1B54A32D192ED03ULL)),
                                splitMix64(pixel));
                            const glm::vec2 j = opt.pixelCentres ? glm::vec2(0.5f) : rng.uniform2();
                            glm::vec3 ro, rd;
                            cameraRay(camera, scene.origin(), x + j.x, y + j.y, &ro, &rd);
                            Rgb c = traceRadiance(scene, ro, rd, rng, opt, &localRays);
                            if (!finite(c)) {
                              ++localBad;
                              c = Rgb(0.0f);  // counted, reported; a NaN must not poison the pixel
                            }
                            float* p = &target.rgb[3 * (size_t(y) * W + x)];
                            p[0] += c.r, p[1] += c.g, p[2] += c.b;
                          }
                        rays += localRays;
                        nonFinite += localBad;
                      });
    (pass % 2 == 0 ? nA : nB)++;
    ReferenceProgress pr;
    pr.samplesPerPixel = nA + nB;
    pr.seconds = elapsed();
    pr.rays = rays;
    if (nA == nB) {
      for (size_t i = 0; i < sumA.rgb.size(); ++i) {
        meanA.rgb[i] = sumA.rgb[i] / nA;
        meanB.rgb[i] = sumB.rgb[i] / nB;
      }
      relErr = halfBufferRelativeError(meanA, meanB);
    }
    pr.relativeError = relErr;
    if (progress && !progress(pr)) {
      res.stopReason = "cancelled";
      break;
    }
    if (opt.targetRelativeError > 0 && nA == nB && pr.samplesPerPixel >= opt.minSamplesPerPixel &&
        relErr <= opt.targetRelativeError) {
      res.stopReason = "error target";
      break;
    }
    if (opt.timeLimitSeconds > 0 && pr.seconds >= opt.timeLimitSeconds && nA == nB) {
      res.stopReason = "time limit";
      break;
    }
  }
  res.samplesPerPixel = nA + nB;
  res.image = HdrImage(W, H);
  for (size_t i = 0; i < sumA.rgb.size(); ++i)
    res.image.rgb[i] = (sumA.rgb[i] + sumB.rgb[i]) / float(res.samplesPerPixel);
  res.relativeError = relErr;
  res.seconds = elapsed();
  res.rays = rays;
  res.nonFiniteSamples = nonFinite;
  return res;
}

}  // namespace nestlight::gi
