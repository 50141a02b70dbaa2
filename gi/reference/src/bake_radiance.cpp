// The captured radiance of scan points for differential rendering (Rohmer, Jendersie and Grosch,
// "Natural Environment Illumination: Coherent Interactive Augmented Reality for Mobile and
// Non-Mobile Devices", IEEE TVCG 2017): each point's outgoing radiance in the scene without the
// inserted meshes, path traced by the reference (Veach 1997, chapter 9) from the point's own disc.
#include "nestlight/gi/reference/bake_radiance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/shared/reference_scene.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "seeds.h"

namespace nestlight::gi {
namespace {

// Points per task: large enough that the progress lock is rare, small enough to balance.
constexpr size_t kBakeGrain = 256;

// Point i of cloud ci gets the same paths whatever the threads do.
Rng pointRng(uint64_t seed, size_t ci, size_t i) {
  return Rng(
      splitMix64(splitMix64(seed * 0x9E3779B97F4A7C15ULL + i) ^ (ci * 0xD1B54A32D192ED03ULL)),
      splitMix64(i));
}

struct PointEstimate {
  Rgb mean{0.0f};
  double relativeError = 0;  // NaN: the estimate is 0
};

// `samples` paths from the point's disc; the standard error from the paths' sample variance of
// the channel mean (a scalar per point, so that the report is one number).
PointEstimate estimatePoint(const ReferenceScene& scene, const SurfaceHit& surface, int samples,
                            Rng& rng, const ReferenceOptions& opt, uint64_t* rays,
                            uint64_t* nonFinite) {
  glm::dvec3 sum(0.0);
  double sumY = 0, sumY2 = 0;
  for (int s = 0; s < samples; ++s) {
    Rgb v = traceFromSurface(scene, surface, surface.geometricNormal, rng, opt, rays);
    if (!(std::isfinite(v.r) && std::isfinite(v.g) && std::isfinite(v.b))) {
      ++*nonFinite;
      v = Rgb(0.0f);  // counted and reported, as the reference's renders do
    }
    sum += glm::dvec3(v);
    const double y = (double(v.r) + v.g + v.b) / 3;
    sumY += y;
    sumY2 += y * y;
  }
  PointEstimate e;
  const double n = samples;
  e.mean = Rgb(sum / n);
  const double meanY = sumY / n;
  const double variance = std::max(0.0, (sumY2 - sumY * meanY) / (n - 1));
  e.relativeError = meanY > 0 ? std::sqrt(variance / n) / meanY : NAN;
  return e;
}

void checkScene(const Scene& scene, const RadianceBakeOptions& o) {
  const std::string file = scene.file.string();
  if (scene.octrees.empty())
    throw Error(file, "octrees", "the scene has no scans: there are no points to bake");
  if (scene.gi.mode != RadianceMode::Albedo)
    throw Error(file, "gi.mode",
                "the scene is in the radiance-cache mode: its scan colours are radiance, not "
                "albedos, so they cannot be lit again; bake from the albedo mode (\"mode\": "
                "\"albedo\") and select the baked layer in a radiance-cache scene");
  checkLayerName(o.layer);
  for (size_t i = 0; i < scene.octrees.size(); ++i)
    if (scene.octrees[i].colour == o.layer)
      throw Error(file, "octrees[" + std::to_string(i) + "].colour",
                  "the scan's albedos come from layer '" + o.layer +
                      "', which the bake would replace: bake into another layer");
  if (o.samplesPerPoint < 2)
    throw Error(
        "", "samples per point",
        "at least 2 (the standard error needs two), got " + std::to_string(o.samplesPerPoint));
  if (o.maxBounces < 1)
    throw Error("", "bounces", "at least 1 (direct light), got " + std::to_string(o.maxBounces));
  // Fail before hours of tracing, not after: a writer creates its temporary file (and removes
  // it again), or throws naming it.
  for (const auto& oct : scene.octrees) ColourLayerWriter probe(oct.path, o.layer, 1.0);
}

// The scene the capture saw: without its inserted meshes, and every level of every scan, since
// every point gets a value and traces from its own disc.
Scene capturedScene(const Scene& scene, size_t* leftOut) {
  Scene s = scene;
  s.meshes.clear();
  for (const auto& m : scene.meshes)
    if (!m.inserted) s.meshes.push_back(m);
  *leftOut = scene.meshes.size() - s.meshes.size();
  for (auto& o : s.octrees) o.maxLevel.reset();
  return s;
}

void checkClouds(const Scene& scene, const ReferenceScene& rs) {
  for (size_t i = 0; i < scene.octrees.size(); ++i) {
    const DiscCloudStats& st = rs.cloudStats()[i];
    const std::string field = "octrees[" + std::to_string(i) + "]";
    if (st.limitedByBudget)
      throw Error(scene.file.string(), field + ".memory_budget",
                  "levels " + std::to_string(st.deepestLevel + 1) + "-" +
                      std::to_string(st.octreeDepth) +
                      " of the scan do not fit: every point is baked from its own disc, so the "
                      "whole scan must be loaded; raise the budget");
    if (!rs.clouds()[i].discs.empty() && rs.clouds()[i].normals.empty())
      throw Error(scene.octrees[i].path.string(), "",
                  "the scan has no normals, so its points have no side to send light to: "
                  "convert it with --estimate-normals");
  }
}

// Writes cloud `ci`'s values (3 floats a point, in the cloud's order: the octree's nodes breadth
// first, points in payload order, as loadDiscCloud read them) as the layer of its octree.
uint64_t writeLayer(const std::filesystem::path& dir, const std::vector<float>& rgb,
                    double maxValue, const RadianceBakeOptions& o, const nlohmann::json& build) {
  OctreeReader reader(dir);
  const auto nodes = reader.allNodes();
  std::vector<size_t> first(nodes.size() + 1, 0);
  for (size_t k = 0; k < nodes.size(); ++k) first[k + 1] = first[k] + nodes[k].second.numPoints;
  NL_CHECK_MSG(first.back() * 3 == rgb.size(),
               dir.string() + ": the octree changed while it was baked");
  // Half floats end at 65504: a scale keeps brighter values (a sun's reflection).
  ColourLayerWriter writer(dir, o.layer, std::max(1.0, maxValue / 60000.0));
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t k) {
    writer.writeNode(nodes[k].first, rgb.data() + 3 * first[k], nodes[k].second.numPoints);
  });
  writer.finish(build);
  return writer.clampedValues();
}

}  // namespace

nlohmann::json RadianceBakeReport::toJson() const {
  return {{"points", points},
          {"mean_relative_standard_error", meanRelativeStandardError},
          {"black_points", blackPoints},
          {"non_finite_samples", nonFiniteSamples},
          {"clamped_values", clampedValues},
          {"rays", rays},
          {"inserted_meshes_left_out", meshesLeftOut},
          {"max_value", maxValue},
          {"seconds", seconds}};
}

RadianceBakeReport bakeRadiance(const Scene& scene, const RadianceBakeOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  checkScene(scene, o);
  RadianceBakeReport rep;
  const Scene captured = capturedScene(scene, &rep.meshesLeftOut);
  const auto rs = ReferenceScene::load(captured, o.log);
  checkClouds(captured, *rs);
  ReferenceOptions opt = referenceOptionsFrom(scene.gi);
  opt.mode = RadianceMode::Albedo;
  opt.maxBounces = o.maxBounces;

  uint64_t total = 0;
  for (const auto& c : rs->clouds()) total += c.discs.size();
  std::atomic<uint64_t> done{0}, rays{0}, nonFinite{0};
  std::mutex progressMutex;
  std::vector<std::vector<float>> values(rs->clouds().size());
  std::vector<double> errorSum(rs->clouds().size(), 0), maxValue(rs->clouds().size(), 0);
  std::vector<uint64_t> black(rs->clouds().size(), 0);
  for (size_t ci = 0; ci < rs->clouds().size(); ++ci) {
    const size_t n = rs->clouds()[ci].discs.size();
    std::vector<float>& rgb = values[ci];
    rgb.assign(3 * n, 0.0f);
    std::vector<double> relErr(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kBakeGrain), [&](const auto& r) {
      uint64_t localRays = 0, localBad = 0;
      for (size_t i = r.begin(); i < r.end(); ++i) {
        Rng rng = pointRng(o.seed, ci, i);
        const PointEstimate e = estimatePoint(*rs, rs->discHit(ci, i), o.samplesPerPoint, rng, opt,
                                              &localRays, &localBad);
        rgb[3 * i] = e.mean.r, rgb[3 * i + 1] = e.mean.g, rgb[3 * i + 2] = e.mean.b;
        relErr[i] = e.relativeError;
      }
      rays += localRays;
      nonFinite += localBad;
      const uint64_t d = done += r.size();
      if (o.progress && progressMutex.try_lock()) {
        o.progress(d, total);
        progressMutex.unlock();
      }
    });
    for (size_t i = 0; i < n; ++i) {
      if (std::isnan(relErr[i]))
        ++black[ci];
      else
        errorSum[ci] += relErr[i];
    }
    for (float v : rgb) maxValue[ci] = std::max(maxValue[ci], double(v));
  }
  if (o.progress) o.progress(total, total);

  rep.points = total;
  double sum = 0;
  for (size_t ci = 0; ci < values.size(); ++ci) {
    sum += errorSum[ci];
    rep.blackPoints += black[ci];
    rep.maxValue = std::max(rep.maxValue, maxValue[ci]);
  }
  rep.meanRelativeStandardError =
      rep.blackPoints < total ? sum / double(total - rep.blackPoints) : 0.0;
  rep.rays = rays;
  rep.nonFiniteSamples = nonFinite;
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  nlohmann::json build = rep.toJson();
  build["method"] = "bake-radiance";
  build["samples_per_point"] = o.samplesPerPoint;
  build["max_bounces"] = o.maxBounces;
  build["seed"] = o.seed;
  build["scene"] = scene.file.string();
  if (!o.commandLine.is_null()) build["command"] = o.commandLine;
  for (size_t ci = 0; ci < values.size(); ++ci)
    rep.clampedValues += writeLayer(captured.octrees[ci].path, values[ci], maxValue[ci], o, build);
  return rep;
}

}  // namespace nestlight::gi
