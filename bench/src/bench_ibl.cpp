// `nestlight bench ibl` (nestlight/bench/bench_ibl.h).
#include "nestlight/bench/bench_ibl.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "nestlight/bench/harness.h"
#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/environment_source.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/plot.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/gi/scene.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace gi;

namespace {

constexpr double kPiD = 3.14159265358979323846;

// A UV sphere of radius 1 about the origin with vertex normals.
void writeSphereObj(const fs::path& path, int rings = 32, int segments = 64) {
  std::ofstream f(path);
  for (int r = 0; r <= rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const double th = kPiD * r / rings, ph = 2 * kPiD * s / segments;
      const double x = std::sin(th) * std::cos(ph), y = std::sin(th) * std::sin(ph),
                   z = std::cos(th);
      f << "v " << x << " " << y << " " << z << "\nvn " << x << " " << y << " " << z << "\n";
    }
  auto id = [&](int r, int s) { return r * segments + (s % segments) + 1; };
  for (int r = 0; r < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      const int a = id(r, s), b = id(r + 1, s), c = id(r + 1, s + 1), d = id(r, s + 1);
      if (r > 0)
        f << "f " << a << "//" << a << " " << b << "//" << b << " " << d << "//" << d << "\n";
      if (r < rings - 1)
        f << "f " << d << "//" << d << " " << b << "//" << b << " " << c << "//" << c << "\n";
    }
}

// A sky (0.5 at the zenith to 0.1 at the horizon, 0.05 below) with a sun: a Gaussian of 3 degrees
// peaking at 2,000 (90% of the light), 35 degrees above the horizon, moving 6 degrees in azimuth a
// frame.
HdrImage movingSunFrame(int frame) {
  const int W = 256, H = 128;
  HdrImage img(W, H);
  const double sigma = 3 * kPiD / 180, el = 35 * kPiD / 180, az = (20 + 6.0 * frame) * kPiD / 180;
  const glm::dvec3 sun(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double th = kPiD * (y + 0.5) / H, ph = 2 * kPiD * (x + 0.5) / W;
      const glm::dvec3 d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const double a = std::acos(std::clamp(glm::dot(d, sun), -1.0, 1.0));
      const double sky = d.z > 0 ? 0.1 + 0.4 * d.z : 0.05;
      const double s = 2000 * std::exp(-a * a / (2 * sigma * sigma));
      img.set(x, y,
              Rgb(float(sky * 0.8 + s), float(sky * 0.9 + s * 0.95), float(sky * 1.2 + s * 0.85)));
    }
  return img;
}

// `map` turned about the zenith by `columns` texels.
HdrImage turned(const HdrImage& map, int columns) {
  HdrImage out(map.width, map.height);
  for (int y = 0; y < map.height; ++y)
    for (int x = 0; x < map.width; ++x) out.set((x + columns) % map.width, y, map.get(x, y));
  return out;
}

// Pixels whose centre ray and all 8 neighbours' meet the same surface (a mesh's material, or the
// scan): the shading error without the silhouettes, where a GL method's pixel-centre sample and
// the reference's pixel average differ whatever the estimator.
std::vector<uint8_t> interiorMask(const Scene& s, const ReferenceScene& rs, int W, int H) {
  SceneCamera cam = s.camera;
  cam.width = W, cam.height = H;
  std::vector<int> id(size_t(W) * H, -1);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      glm::vec3 o, d;
      cameraRay(cam, s.origin, x + 0.5f, y + 0.5f, &o, &d);
      SurfaceHit hit;
      if (rs.intersect(o, d, 1e30f, &hit))
        id[size_t(y) * W + x] = hit.kind == SurfaceHit::Kind::Disc ? -2 : int(hit.material);
    }
  std::vector<uint8_t> mask(id.size(), 0);
  for (int y = 1; y + 1 < H; ++y)
    for (int x = 1; x + 1 < W; ++x) {
      const int c = id[size_t(y) * W + x];
      bool same = c != -1;
      for (int dy = -1; dy <= 1 && same; ++dy)
        for (int dx = -1; dx <= 1 && same; ++dx) same = id[size_t(y + dy) * W + x + dx] == c;
      mask[size_t(y) * W + x] = same;
    }
  return mask;
}

struct Sums {
  double err2 = 0, ref2 = 0;
};
Sums maskedSums(const HdrImage& a, const HdrImage& r, const std::vector<uint8_t>& mask) {
  Sums s;
  for (size_t p = 0; p < mask.size(); ++p) {
    if (!mask[p]) continue;
    for (int k = 0; k < 3; ++k) {
      const double e = double(a.rgb[3 * p + k]) - r.rgb[3 * p + k];
      if (std::isfinite(e)) s.err2 += e * e;
      s.ref2 += double(r.rgb[3 * p + k]) * r.rgb[3 * p + k];
    }
  }
  return s;
}

// Over 4 x 4 blocks of pixels: the relative L2 error of the blocks' mean radiance (the masked
// pixels', in blocks at least half masked) and the ratio of the image means. On scanned receivers
// the per-pixel error has a floor whatever the samples: the G-buffer blends the splats' noisy
// colours where the reference's pixel-centre ray meets one disc's; the blocks see shading.
struct BlockStats {
  double relativeL2 = 0, meanRatio = 0;
};
BlockStats blockStats(const HdrImage& a, const HdrImage& r, const std::vector<uint8_t>& mask) {
  double err2 = 0, ref2 = 0, sumA = 0, sumR = 0;
  for (int by = 0; by + 4 <= r.height; by += 4)
    for (int bx = 0; bx + 4 <= r.width; bx += 4) {
      double ba[3] = {0, 0, 0}, br[3] = {0, 0, 0};
      int n = 0;
      for (int y = by; y < by + 4; ++y)
        for (int x = bx; x < bx + 4; ++x) {
          const size_t p = size_t(y) * size_t(r.width) + size_t(x);
          if (!mask[p]) continue;
          ++n;
          for (int k = 0; k < 3; ++k) ba[k] += a.rgb[3 * p + k], br[k] += r.rgb[3 * p + k];
        }
      if (2 * n < 16) continue;
      for (int k = 0; k < 3; ++k) {
        if (std::isfinite(ba[k]))
          err2 += (ba[k] - br[k]) * (ba[k] - br[k]) / (n * n), sumA += ba[k];
        ref2 += br[k] * br[k] / (n * n), sumR += br[k];
      }
    }
  return {ref2 > 0 ? std::sqrt(err2 / ref2) : 0, sumR > 0 ? sumA / sumR : 0};
}

// Time at which the error curve (ms, error) in the order of the sample counts reaches `target`,
// interpolated in log-log; extrapolated (and said so) beyond the largest count.
json timeTo(const std::vector<std::pair<double, double>>& curve, double target) {
  for (size_t i = 0; i < curve.size(); ++i) {
    if (curve[i].second > target) continue;
    if (i == 0) return {{"ms", curve[0].first}, {"how", "reached at the fewest samples"}};
    const auto& a = curve[i - 1];
    const auto& b = curve[i];
    const double t =
        (std::log(target) - std::log(a.second)) / (std::log(b.second) - std::log(a.second));
    return {{"ms", std::exp(std::log(a.first) + t * (std::log(b.first) - std::log(a.first)))},
            {"how", "interpolated"}};
  }
  if (curve.size() >= 2 && curve.back().second < curve[curve.size() - 2].second) {
    const auto& a = curve[curve.size() - 2];
    const auto& b = curve.back();
    const double t =
        (std::log(target) - std::log(a.second)) / (std::log(b.second) - std::log(a.second));
    return {{"ms", std::exp(std::log(a.first) + t * (std::log(b.first) - std::log(a.first)))},
            {"how", "extrapolated beyond the most samples"}};
  }
  return {{"ms", nullptr}, {"how", "not reached"}};
}

std::string probeName(int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "probe_%04d.exr", frame);
  return name;
}

// The scene's probe sequence in dir; false (said so) when a shared map is missing.
bool writeProbeSequence(const BenchIblOptions& o, const std::string& sceneName, const fs::path& dir,
                        std::FILE* log) {
  if (sceneName == "moving-sun" || sceneName == "scanned") {
    for (int f = 0; f < o.frames; ++f) writeExr((dir / probeName(f)).string(), movingSunFrame(f));
  } else if (sceneName == "shared" || sceneName == "outdoor") {
    const fs::path map =
        o.sharedData / "hdr" /
        (sceneName == "shared" ? "stage_env_latlong.exr" : "royal_esplanade_1k.hdr");
    if (!fs::exists(map)) {
      say(log, "bench ibl: %s not found: the shared scene is skipped\n", map.c_str());
      return false;
    }
    const HdrImage base = readHdrImage(map.string());
    for (int f = 0; f < o.frames; ++f)
      writeExr((dir / probeName(f)).string(),
               turned(base, int(std::lround(base.width * 4.0 * f / 360))));
  } else {
    throw Error("--scenes", "",
                "unknown scene '" + sceneName + "' (moving-sun, scanned, shared, outdoor)");
  }
  return true;
}

// The scene file's JSON: the scanned town, or the glossy sphere on its floor.
json sceneDescription(const BenchIblOptions& o, const std::string& sceneName, const fs::path& dir) {
  json sceneJson;
  if (sceneName == "scanned") {
    // Scanned receivers: the object scene's town (make-scene object: ground, walls, columns and
    // a sphere scanned with 2 mm of noise, a gold torus) in the albedo mode, where every scan
    // point is lit, under the moving sun. The scan is made once in town/ and reused.
    TestSceneOptions to;
    to.points = 200000;
    to.width = to.height = o.size;
    to.quiet = true;
    sceneJson = json::parse(std::ifstream(makeTestScene(TestSceneKind::Object, dir / "town", to)));
    for (auto& t : sceneJson["octrees"]) t["path"] = "town/" + t["path"].get<std::string>();
    for (auto& m : sceneJson["meshes"]) m["path"] = "town/" + m["path"].get<std::string>();
    sceneJson.erase("lights");
    sceneJson.erase("output");
    sceneJson["camera"]["width"] = sceneJson["camera"]["height"] = o.size;
    sceneJson["environment"] = {{"sequence", "probe_%04d.exr"}, {"fps", 1}};
    sceneJson["gi"] = {{"method", "direct"}, {"mode", "albedo"}, {"seed", 1}};
    return sceneJson;
  }
  writeSphereObj(dir / "sphere.obj");
  writeBoxObj(dir / "box.obj");
  return {{"version", 1},
          {"materials",
           {{"floor", {{"type", "lambert"}, {"base_color", 0.5}}},
            {"glossy",
             {{"type", "ggx"},
              {"base_color", {0.95, 0.8, 0.5}},
              {"roughness", o.roughness},
              {"metallic", 1.0}}}}},
          {"meshes",
           json::array({json{{"path", "box.obj"},
                             {"transform",
                              {{"translate", {-5.0, -5.0, -0.1}}, {"scale", {10.0, 10.0, 0.1}}}},
                             {"material", "floor"}},
                        json{{"path", "sphere.obj"},
                             {"transform", {{"translate", {0.0, 0.0, 1.0}}}},
                             {"material", "glossy"}}})},
          {"environment", {{"sequence", "probe_%04d.exr"}, {"fps", 1}}},
          {"camera",
           {{"eye", {0.0, -4.2, 2.4}},
            {"target", {0.0, 0.0, 0.8}},
            {"up", {0.0, 0.0, 1.0}},
            {"fov", 42.0},
            {"width", o.size},
            {"height", o.size}}},
          {"gi", {{"method", "direct"}, {"mode", "radiance_cache"}, {"seed", 1}}}};
}

// One scene of the study: its frames' cameras, the mask of interior pixels and the ground truth
// per frame, with everything the measures write to.
struct SceneRun {
  const BenchIblOptions& o;
  std::string name;
  fs::path dir;
  Scene scene;
  std::vector<SceneCamera> cameras;
  std::vector<uint8_t> mask;
  std::vector<HdrImage> refs;
  std::vector<double> refNoise2;  // per frame: the reference's relative squared error
  std::ofstream& csv;
  std::FILE* log;
};

// Ground truth per frame: the reference's direct light, as two halves of the samples with
// different seeds, whose mean is the reference and whose difference measures its own noise
// (the errors are reported with it and with it taken out). Cached by `stamp`.
void renderGroundTruth(SceneRun& run, ReferenceScene& rs, const std::string& stamp) {
  const BenchIblOptions& o = run.o;
  // The reference's first bounce (direct light), its camera rays through pixel centres as the
  // GL methods shade them, lit by each frame's probe as the method is (EnvironmentSource).
  std::unique_ptr<EnvironmentSource> probe;
  ReferenceOptions ro = referenceOptionsFrom(run.scene.gi);
  ro.maxBounces = 1;
  ro.maxSamplesPerPixel = o.referenceSpp;
  ro.targetRelativeError = 0;
  ro.pixelCentres = true;
  for (int f = 0; f < o.frames; ++f) {
    HdrImage half[2];
    for (int k = 0; k < 2; ++k) {
      char name[128];
      std::snprintf(name, sizeof name, "reference_%s_%dspp_%04d_%c.exr", stamp.c_str(),
                    o.referenceSpp, f, "ab"[k]);
      const fs::path file = run.dir / name;
      if (fs::exists(file)) {
        half[k] = readHdrImage(file.string());
        continue;
      }
      if (!probe) probe = std::make_unique<EnvironmentSource>(run.scene.environment);
      rs.setEnvironment(probe->at(run.cameras[size_t(f)].time));
      ro.seed = 2 * uint64_t(f) + uint64_t(k) + 1;
      ro.maxSamplesPerPixel = std::max(o.referenceSpp / 2, 1);
      const ReferenceResult r = renderReference(rs, run.cameras[size_t(f)], ro,
                                                [](const ReferenceProgress&) { return true; });
      writeExr(file.string(), r.image,
               {{"nestlight:method", "direct"},
                {"nestlight:samples", std::to_string(r.samplesPerPixel)},
                {"nestlight:pixel_centres", "1"}});
      half[k] = r.image;
      say(run.log, "bench ibl: %s reference frame %d (%c): %d spp in %.1f s\n", run.name.c_str(), f,
          "ab"[k], r.samplesPerPixel, r.seconds);
    }
    HdrImage mean = half[0];
    for (size_t i = 0; i < mean.rgb.size(); ++i)
      mean.rgb[i] = 0.5f * (half[0].rgb[i] + half[1].rgb[i]);
    // The mean of two halves: its variance is a quarter of E (a - b)^2.
    const Sums d = maskedSums(half[0], half[1], run.mask);
    const Sums m = maskedSums(mean, mean, run.mask);
    run.refNoise2.push_back(m.ref2 > 0 ? d.err2 / 4 / m.ref2 : 0);
    run.refs.push_back(std::move(mean));
  }
  say(run.log,
      "bench ibl: %s reference: %d spp, its own relative error %.4f (median over frames)\n",
      run.name.c_str(), o.referenceSpp, std::sqrt(median(run.refNoise2)));
}

// Cached references are named by what they depend on: the scene (materials, camera, size) and
// every probe frame's bytes.
std::string referenceStamp(const BenchIblOptions& o, const json& sceneJson, const fs::path& dir) {
  std::string stampText = sceneJson.dump();
  for (int f = 0; f < o.frames; ++f) {
    std::ifstream in(dir / probeName(f), std::ios::binary);
    stampText +=
        std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "%016zx", std::hash<std::string>{}(stampText));
  return stamp;
}

// An estimator's curve and plot series as its sample counts run.
struct EstimatorRun {
  std::vector<std::pair<double, double>> curve;  // (median ms, median relative L2) per count
  PlotSeries speed;
  std::vector<PlotSeries>& frameSeries;
};

// One configuration (estimator, samples per pixel): the sequence rendered with two seeds and
// measured frame by frame against the ground truth, and timed at the timing size.
json runLevel(const SceneRun& run, const std::string& est, int q, EstimatorRun& er) {
  const BenchIblOptions& o = run.o;
  Scene s = run.scene;
  s.gi.method = "ibl";
  s.gi.parameters = json{{"estimator", est}};
  findMethod("ibl")->applyQuality(s.gi, q);
  auto runSeed = [&](uint64_t seed, int W) {
    Scene ss = s;
    ss.gi.seed = seed;
    ss.camera.width = ss.camera.height = W;
    auto m = createMethod(ss, {true, false});
    std::vector<MethodFrame> out;
    for (int f = 0; f < (W == o.size ? o.frames : std::min(o.frames, o.timingFrames)); ++f) {
      SceneCamera c = run.cameras[size_t(f)];
      c.width = c.height = W;
      out.push_back(m->render(c));
    }
    return out;
  };
  const std::vector<MethodFrame> a = runSeed(1, o.size);
  std::vector<MethodFrame> b;
  if (o.variance) b = runSeed(2, o.size);
  const std::vector<uint8_t>& mask = run.mask;
  const std::vector<HdrImage>& refs = run.refs;
  std::vector<double> errs, errsNet, vars, flick, ms, blockErrs, meanRatios;
  for (int f = 0; f < o.frames; ++f) {
    const Sums e = maskedSums(a[size_t(f)].image, refs[size_t(f)], mask);
    const double rel = e.ref2 > 0 ? std::sqrt(e.err2 / e.ref2) : 0;
    // The reference's own noise adds to the measured error (independent): taken out.
    errsNet.push_back(std::sqrt(std::max(0.0, rel * rel - run.refNoise2[size_t(f)])));
    double var = 0;
    if (o.variance) {
      const Sums d = maskedSums(a[size_t(f)].image, b[size_t(f)].image, mask);
      var = e.ref2 > 0 ? d.err2 / 2 / e.ref2 : 0;  // E (a - b)^2 = 2 var, relative to mean r^2
    }
    double fl = 0;
    if (f > 0) {
      HdrImage da = a[size_t(f)].image, db = a[size_t(f - 1)].image;
      for (size_t i = 0; i < da.rgb.size(); ++i) da.rgb[i] -= refs[size_t(f)].rgb[i];
      for (size_t i = 0; i < db.rgb.size(); ++i) db.rgb[i] -= refs[size_t(f - 1)].rgb[i];
      const Sums d = maskedSums(da, db, mask);
      fl = e.ref2 > 0 ? std::sqrt(d.err2 / e.ref2) : 0;
      flick.push_back(fl);
    }
    errs.push_back(rel), vars.push_back(var), ms.push_back(a[size_t(f)].seconds * 1e3);
    const BlockStats bs = blockStats(a[size_t(f)].image, refs[size_t(f)], mask);
    blockErrs.push_back(bs.relativeL2), meanRatios.push_back(bs.meanRatio);
    run.csv << run.name << "," << est << "," << q << "," << f << "," << ms.back() << "," << rel
            << "," << errsNet.back() << "," << var << "," << (f > 0 ? std::to_string(fl) : "")
            << "," << bs.relativeL2 << "," << bs.meanRatio << "\n";
  }
  double timingMs = 0;
  if (o.timingSize > 0) {
    std::vector<double> t;
    for (const MethodFrame& fr : runSeed(1, o.timingSize)) t.push_back(fr.seconds * 1e3);
    timingMs = median(t);
  }
  const double medMs = median(ms), medErr = median(errsNet);
  // Equal time at the timing size where it was measured: per-pixel relative error hardly
  // depends on the image's size at a given sample count, frame time does (fixed costs).
  er.curve.push_back({o.timingSize > 0 ? timingMs : medMs, medErr});
  er.speed.points.push_back({er.curve.back().first, medErr, std::to_string(q)});
  if (q == o.samples[o.samples.size() / 2]) {
    PlotSeries fs{est + " (" + std::to_string(q) + " spp)", {}};
    for (int f = 0; f < o.frames; ++f) fs.points.push_back({double(f), errsNet[size_t(f)]});
    er.frameSeries.push_back(fs);
  }
  say(run.log,
      "bench ibl: %-10s %-4s %3d spp: %8.1f ms/frame at %d^2 (%8.1f ms at %d^2), relative L2 "
      "%.4f (%.4f without "
      "the reference's noise; median of %d frames), relative variance %.2e, flicker %.4f; "
      "4x4 blocks: relative L2 "
      "%.4f, mean %.4f of the reference's\n",
      run.name.c_str(), est.c_str(), q, medMs, o.size, timingMs, o.timingSize, median(errs), medErr,
      o.frames, median(vars), median(flick), median(blockErrs), median(meanRatios));
  return {{"samples", q},
          {"median_ms", medMs},
          {"timing_ms", timingMs},
          {"median_relative_l2", median(errs)},
          {"median_relative_l2_net", medErr},
          {"median_relative_l2_4x4", median(blockErrs)},
          {"median_mean_ratio", median(meanRatios)},
          {"relative_l2_4x4_per_frame", blockErrs},
          {"mean_ratio_per_frame", meanRatios},
          {"relative_l2_per_frame", errs},
          {"relative_l2_net_per_frame", errsNet},
          {"relative_variance_per_frame", vars},
          {"flicker_per_frame", flick},
          {"median_flicker", median(flick)},
          {"ms_per_frame", ms},
          {"attributes", a.back().attributes}};
}

// Every estimator at every sample count on one scene, the best one's speed-up over environment
// sampling alone, and the scene's two plots.
json measureScene(const SceneRun& run) {
  const BenchIblOptions& o = run.o;
  std::vector<double> refNoise;
  for (double v : run.refNoise2) refNoise.push_back(std::sqrt(v));
  json sceneOut = {{"scene", run.name},
                   {"reference_relative_error_per_frame", refNoise},
                   {"estimators", json::array()}};
  std::vector<PlotSeries> speedSeries, frameSeries;
  std::map<std::string, json> timeTos;
  for (const std::string& est : o.estimators) {
    EstimatorRun er{{}, PlotSeries{est, {}}, frameSeries};
    json estOut = {{"estimator", est}, {"levels", json::array()}};
    for (int q : o.samples) estOut["levels"].push_back(runLevel(run, est, q, er));
    estOut["time_to_5pct"] = timeTo(er.curve, 0.05);
    estOut["time_to_2pct"] = timeTo(er.curve, 0.02);
    timeTos[est] = estOut["time_to_5pct"];
    speedSeries.push_back(er.speed);
    sceneOut["estimators"].push_back(estOut);
  }
  // The best estimator's time to 5% against environment-map sampling alone.
  if (timeTos.count("env") && timeTos["env"]["ms"].is_number()) {
    std::string best;
    double bestMs = INFINITY;
    for (const auto& [e, t] : timeTos)
      if (e != "env" && t["ms"].is_number() && t["ms"].get<double>() < bestMs)
        bestMs = t["ms"].get<double>(), best = e;
    if (!best.empty()) {
      const double speedup = timeTos["env"]["ms"].get<double>() / bestMs;
      sceneOut["best_to_5pct"] = {{"estimator", best}, {"speedup_over_env", speedup}};
      say(run.log,
          "bench ibl: %s: %s reaches 5%% in %.1f ms a frame (%d^2), %.2fx faster than "
          "environment sampling alone\n",
          run.name.c_str(), best.c_str(), bestMs, o.timingSize > 0 ? o.timingSize : o.size,
          speedup);
    }
  }
  const int timeSize = o.timingSize > 0 ? o.timingSize : o.size;
  writeSvgPlot((o.out / (run.name + "_speed.svg")).string(),
               "ibl on " + run.name + ": time against error",
               "ms per frame (" + std::to_string(timeSize) + "^2)",
               "relative L2 error (median over frames, net)", speedSeries, true, true);
  writeSvgPlot((o.out / (run.name + "_frames.svg")).string(),
               "ibl on " + run.name + ": error per frame", "frame",
               "relative L2 error (the reference's noise taken out)", frameSeries, false, true);
  return sceneOut;
}

}  // namespace

BenchIblReport runBenchIbl(const BenchIblOptions& o, std::FILE* log) {
  if (o.frames < 2)
    throw Error("--frames", "", "give at least 2 frames (flicker compares consecutive frames)");
  NL_CHECK(findMethod("ibl"));
  for (const auto& e : o.estimators)
    if (e != "mis" && e != "bis" && e != "smc" && e != "env" && e != "brdf")
      throw Error("--estimators", "", "unknown estimator '" + e + "' (mis, bis, smc, env, brdf)");
  BenchIblReport report;
  report.dir = o.out;
  fs::create_directories(o.out);
  json all = {{"device", o.device},
              {"frames", o.frames},
              {"size", o.size},
              {"timing_size", o.timingSize},
              {"time_to_error_at", o.timingSize > 0 ? o.timingSize : o.size},
              {"reference_spp", o.referenceSpp},
              {"roughness", o.roughness},
              {"scenes", json::array()}};
  std::ofstream csv(o.out / "bench_ibl.csv");
  csv << "scene,estimator,samples,frame,ms,relative_l2,relative_l2_net,relative_variance,flicker,"
         "relative_l2_4x4,"
         "mean_ratio\n";
  for (const std::string& sceneName : o.scenes) {
    const fs::path dir = o.out / sceneName;
    fs::create_directories(dir);
    if (!writeProbeSequence(o, sceneName, dir, log)) continue;
    const json sceneJson = sceneDescription(o, sceneName, dir);
    std::ofstream(dir / "scene.json") << sceneJson.dump(2);
    SceneRun run{o, sceneName, dir, loadScene(dir / "scene.json"), {}, {}, {}, {}, csv, log};
    const std::string stamp = referenceStamp(o, sceneJson, dir);
    run.cameras = sceneCameras(run.scene);
    NL_CHECK(int(run.cameras.size()) == o.frames);
    // The scene as the reference traces it: the mask's rays, and the references not yet cached.
    const std::unique_ptr<ReferenceScene> rs = ReferenceScene::load(run.scene);
    run.mask = interiorMask(run.scene, *rs, o.size, o.size);
    renderGroundTruth(run, *rs, stamp);
    all["scenes"].push_back(measureScene(run));
  }
  std::ofstream(o.out / "bench_ibl.json") << all.dump(2);
  report.json = std::move(all);
  return report;
}

}  // namespace nestlight::bench
