// `nestlight bench diffrender` (nestlight/bench/bench_diffrender.h): the configurations measured
// (one set-up, the timed runs, one frame with AOVs) and the ground truth they are measured against.
// The tables are made in bench_diffrender_tables.cpp.
#include "nestlight/bench/bench_diffrender.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <fstream>

#include "bench_diffrender_internal.h"
#include "bench_gi_reference.h"
#include "nestlight/bench/harness.h"
#include "nestlight/gi/diffrender/diffrender_method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/reference/path_tracer.h"  // cameraRay
#include "nestlight/gi/shared/reference_scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace drbench {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

const std::vector<std::string> kQueries = {"em", "dit", "vct", "exact"};
const std::vector<std::string> kPresets = {"low", "med", "high"};

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

void checkNames(const std::string& option, const std::vector<std::string>& given,
                const std::vector<std::string>& known, const std::string& what) {
  if (given.empty()) throw Error(option, "", "give at least one " + what);
  for (const std::string& g : given)
    if (std::find(known.begin(), known.end(), g) == known.end())
      throw Error(option, "", "unknown " + what + " '" + g + "' (" + joined(known) + ")");
}

void checkCounts(const std::string& option, const std::vector<int>& given) {
  if (given.empty()) throw Error(option, "", "give at least one value");
  for (int v : given)
    if (v < 1 || v > 1024)
      throw Error(option, "", std::to_string(v) + " is not 1 to 1024 (diffrender's range)");
}

double msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// A file name of a label: "dit N=32 cache=16" -> "dit_N32_cache16".
std::string slug(const std::string& label) {
  std::string s;
  for (char c : label) {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.')
      s += c;
    else if (c == ' ' && !s.empty() && s.back() != '_')
      s += '_';
  }
  return s;
}

long long counter(const gi::MethodFrame& f, const std::string& name) {
  auto it = f.attributes.find("nestlight:diffrender_" + name);
  if (it == f.attributes.end()) return -1;
  try {
    return std::stoll(it->second);
  } catch (const std::exception&) {
    return -1;
  }
}

std::map<std::string, double> wallTimes(const gi::MethodFrame& f) {
  std::map<std::string, double> wall;
  for (const auto& [name, ms] : f.passMs) {
    (void)ms;
    auto it = f.attributes.find("nestlight:pass_wall_ms:" + name);
    wall[name] = it == f.attributes.end() ? 0.0 : std::atof(it->second.c_str());
  }
  return wall;
}

// The set-up frame (untimed) and the timed runs of one configuration: frame and pass medians.
void timeRuns(Bench& b, const gi::Scene& s, DiffrenderRun& r) {
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<gi::Method> m = gi::createMethod(s, {true, false, true});
  const gi::MethodFrame first = m->render(s.camera);
  r.setupMs = msSince(start);
  r.setupPassWallMs = wallTimes(first);
  std::map<std::string, std::vector<double>> gpu, wall;
  for (int run = 0; run < b.o.runs; ++run) {
    const gi::MethodFrame f = m->render(s.camera);
    r.frameMs.push_back(f.seconds * 1e3);
    const std::map<std::string, double> w = wallTimes(f);
    for (const auto& [name, ms] : f.passMs) {
      if (std::find(r.passes.begin(), r.passes.end(), name) == r.passes.end())
        r.passes.push_back(name);
      gpu[name].push_back(ms);
      wall[name].push_back(w.at(name));
    }
  }
  r.medianMs = median(r.frameMs);
  for (const std::string& name : r.passes) {
    r.passGpuMs[name] = median(gpu[name]);
    r.passWallMs[name] = median(wall[name]);
  }
}

// The mean over the floor's blocks of an image at 1 / scale (mean of the channels).
double floorMean(const gi::HdrImage& low, const Bench& b) {
  double sum = 0;
  size_t n = 0;
  for (int y = 0; y < low.height; ++y)
    for (int x = 0; x < low.width; ++x) {
      if (!b.floorBlocks[size_t(y) * size_t(low.width) + size_t(x)]) continue;
      const gi::Rgb c = low.get(x, y);
      const double v = (double(c.r) + double(c.g) + double(c.b)) / 3;
      if (std::isfinite(v)) sum += v, ++n;
    }
  return n ? sum / double(n) : 0.0;
}

// The errors of one more frame, made with the AOVs (reading them back costs what the timed frames
// must not pay): dL, object and material errors against the truth, the floor's mean rho.
void measureAovFrame(Bench& b, gi::Scene s, DiffrenderRun& r) {
  r.aovs = b.dir / "aovs" / slug(r.label);
  differential::setGiParameter(s, "aovs", r.aovs.string());
  const gi::MethodFrame a = gi::createMethod(s, {true, false, true})->render(s.camera);
  gi::writeExr((r.aovs / "composite.exr").string(), a.image, a.attributes);
  const gi::HdrImage delta = gi::readHdrImage((r.aovs / "diffrender_delta.exr").string());
  const gi::HdrImage rho = gi::readHdrImage((r.aovs / "diffrender_rho.exr").string());
  const differential::Metrics m = differential::measure(a.image, delta, &rho, b.truth);
  r.deltaL2 = m.deltaL2, r.objectL2 = m.objectL2, r.rhoL2 = m.rhoL2.value_or(0.0);
  r.compositeL2 = gi::relativeL2(a.image, b.truth.r1);
  r.compositeL2Box4 = gi::relativeL2(gi::boxFilter(a.image, 4), gi::boxFilter(b.truth.r1, 4));
  const gi::HdrImage rhoLow = rho.width == b.lowWidth ? rho : gi::boxFilter(rho, b.truth.scale);
  r.floorRho = floorMean(rhoLow, b);
  r.floorAlbedo = b.floorAlbedo;
  r.floorRhoError = r.floorAlbedo > 0 ? std::abs(r.floorRho - r.floorAlbedo) / r.floorAlbedo : 0;
  r.rhoClamped = counter(a, "rho_clamped");
  r.ditUnconverged = counter(a, "dit_unconverged");
  r.ditHidden = counter(a, "dit_hidden");
  r.scanSamples = counter(a, "scan_pixels");
}

// Scan pixels whose centre ray meets a scan disc facing the camera's up (within 25 degrees) at
// the lowest height such discs are seen at (within 5% of the viewing distance): the floor.
std::vector<bool> floorPixels(const gi::Scene& s, const differential::Truth& t) {
  const std::unique_ptr<gi::ReferenceScene> rs = gi::ReferenceScene::load(s);
  const glm::vec3 up = glm::normalize(glm::vec3(s.camera.up));
  const int W = t.mask.width, H = t.mask.height;
  std::vector<float> height(size_t(W) * size_t(H), NAN);
  float lowest = INFINITY;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      if (t.mask.get(x, y)[0] != 1.0f) continue;
      glm::vec3 o, d;
      gi::cameraRay(s.camera, s.origin, float(x) + 0.5f, float(y) + 0.5f, &o, &d);
      gi::SurfaceHit hit;
      if (!rs->intersect(o, d, 1e30f, &hit) || hit.kind != gi::SurfaceHit::Kind::Disc ||
          !hit.orientedDisc || std::abs(glm::dot(hit.geometricNormal, up)) < 0.906f)
        continue;
      const float h = glm::dot(hit.position, up);
      height[size_t(y) * size_t(W) + size_t(x)] = h;
      lowest = std::min(lowest, h);
    }
  const float tolerance = 0.05f * float(glm::length(s.camera.eye - s.camera.target));
  std::vector<bool> floor(height.size(), false);
  for (size_t i = 0; i < height.size(); ++i)
    floor[i] = std::isfinite(height[i]) && height[i] <= lowest + tolerance;
  return floor;
}

// The floor's blocks at dL's resolution (every pixel floor), or every whole scan block where
// fewer than 8 are: rho's mean is taken over them.
void chooseFloorBlocks(Bench& b, const gi::Scene& s) {
  const differential::Truth& t = b.truth;
  const int sc = t.scale;
  b.lowWidth = (t.mask.width + sc - 1) / sc;
  const int lowHeight = (t.mask.height + sc - 1) / sc;
  const std::vector<bool> floor = floorPixels(s, t);
  std::vector<bool> blocks(size_t(b.lowWidth) * size_t(lowHeight), true), scan = blocks;
  for (int y = 0; y < t.mask.height; ++y)
    for (int x = 0; x < t.mask.width; ++x) {
      const size_t i = size_t(y / sc) * size_t(b.lowWidth) + size_t(x / sc);
      const bool isScan = t.mask.get(x, y)[0] == 1.0f;
      if (!isScan) scan[i] = false;
      if (!isScan || !floor[size_t(y) * size_t(t.mask.width) + size_t(x)]) blocks[i] = false;
    }
  b.floorCount = size_t(std::count(blocks.begin(), blocks.end(), true));
  b.floorRule =
      "the floor's blocks (every pixel a scan pixel whose centre ray meets a disc facing "
      "up, at the lowest height seen, within 5% of the viewing distance)";
  if (b.floorCount < 8) {
    blocks = scan;
    b.floorCount = size_t(std::count(blocks.begin(), blocks.end(), true));
    b.floorRule = "every whole scan block (the floor is not separable in this view)";
  }
  b.floorBlocks = std::move(blocks);
  b.floorAlbedo = floorMean(gi::boxFilter(t.albedo, sc), b);
}

}  // namespace

void checkOptions(const BenchDiffrenderOptions& o) {
  checkNames("--queries", o.queries, kQueries, "query");
  checkNames("--presets", o.presets, kPresets, "preset");
  checkNames("--tables", o.tables, tableNames(), "table");
  if (!o.sweepQueries.empty()) checkNames("--sweep-queries", o.sweepQueries, kQueries, "query");
  checkCounts("--samples", o.samples);
  checkCounts("--cache", o.caches);
  checkCounts("--sweep-cache", {o.sweepCache});
  if (o.runs < 1) throw Error("--runs", "", "give at least 1 timed run");
  if (o.equalTimeMs && !(*o.equalTimeMs > 0 && std::isfinite(*o.equalTimeMs)))
    throw Error("--equal-time-ms", "", "the budget must be a positive number of milliseconds");
  if (!(o.referenceError > 0 && o.referenceError <= 0.5))
    throw Error("--reference-error", "", "give a relative error above 0 and at most 0.5");
  if (o.width < 0 || o.height < 0) throw Error("--width/--height", "", "give a positive size");
}

std::vector<std::string> sweepQueries(const BenchDiffrenderOptions& o) {
  if (!o.sweepQueries.empty()) return o.sweepQueries;
  std::vector<std::string> q;
  for (const std::string& name : o.queries)
    if (name != "exact") q.push_back(name);
  return q;
}

gi::Scene Bench::scene(const json& overrides) const {
  gi::Scene s = reference::sceneFor(probe, "diffrender", "", W, H);
  s.gi.seed = 1;
  for (const auto& [key, value] : overrides.items()) differential::setGiParameter(s, key, value);
  return s;
}

DiffrenderRun Bench::run(const json& overrides, const std::string& label) {
  const gi::Scene s = scene(overrides);
  const gi::DiffrenderParameters p = gi::diffrenderParameters(s);  // names a bad value
  // Configurations that resolve to the same parameters are measured once (DIT med is the cache
  // table's N = 16, cache = 8 with self-shadow).
  const std::string key = std::string(gi::queryName(p.query)) + "/" + std::to_string(p.samples) +
                          "/" + std::to_string(p.cache) + "/" + std::to_string(p.objectSamples) +
                          "/" + std::to_string(p.objectVoxels.x) + "x" +
                          std::to_string(p.objectVoxels.y) + "x" +
                          std::to_string(p.objectVoxels.z) + "/" + (p.selfShadow ? "s" : "-") +
                          (p.secondaryBounce ? "b" : "-");
  if (auto it = memo.find(key); it != memo.end()) return runs[it->second];
  DiffrenderRun r;
  r.label = label;
  r.overrides = overrides;
  r.query = gi::queryName(p.query), r.preset = gi::qualityName(p.quality);
  r.samples = p.samples, r.cache = p.cache, r.objectSamples = p.objectSamples;
  r.selfShadow = p.selfShadow, r.secondaryBounce = p.secondaryBounce;
  timeRuns(*this, s, r);
  measureAovFrame(*this, s, r);
  say(log,
      "  %-28s median %8.1f ms (set-up %6.0f ms); composite %.4f, dL %.4f, object %.4f, rho "
      "%.4f, floor rho %.3f (albedo %.3f)\n",
      r.label.c_str(), r.medianMs, r.setupMs, r.compositeL2, r.deltaL2, r.objectL2, r.rhoL2,
      r.floorRho, r.floorAlbedo);
  memo[key] = runs.size();
  runs.push_back(r);
  return r;
}

// R1 and R0 (cached as bench gi caches them), the truth's images and the floor's blocks.
void Bench::prepareTruth() {
  reference::Request q;
  q.sceneFile = sceneFile;
  q.probe = probe;
  q.width = W, q.height = H;
  q.error = o.referenceError, q.timeLimit = o.referenceTimeLimit, q.spp = o.referenceSpp;
  q.force = o.forceReference;
  q.who = "bench diffrender";
  reference::Image r1 = reference::loadOrRender(q, dir / "reference.exr", log);
  reference::Image r0 = reference::loadOrRender(q, dir / "reference_without.exr", log, true);
  exposure =
      gi::choosePngExposure(
          r1.image, std::nullopt,
          probe.output.exposureSet ? std::optional<double>(probe.output.exposure) : std::nullopt)
          .stops;
  gi::writeToneMappedPng((dir / "reference.png").string(), r1.image, exposure);
  gi::writeToneMappedPng((dir / "reference_without.png").string(), r0.image, exposure);
  truth = differential::makeTruth(scene(json::object()), r1.image, std::move(r0.image),
                                  dir / "aovs" / "truth");
  truth.info["r1"] = r1.info;
  truth.info["r0"] = r0.info;
  chooseFloorBlocks(*this, reference::sceneFor(probe, "reference", "", W, H));
  say(log,
      "bench diffrender: R0 against R1 (nothing inserted): relative L2 %.4f, object pixels %.4f; "
      "the capture against R0 on scan pixels %.4f; rho's floor: %zu blocks, mean albedo %.4f "
      "(%s)\n",
      truth.r0Error, truth.r0ObjectError, truth.captureError, floorCount, floorAlbedo,
      floorRule.c_str());
}

}  // namespace drbench

std::optional<size_t> equalTimePick(const std::vector<std::pair<int, double>>& sweep,
                                    double budgetMs) {
  std::optional<size_t> pick;
  for (size_t i = 0; i < sweep.size(); ++i)
    if (sweep[i].second <= budgetMs && (!pick || sweep[i].first > sweep[*pick].first)) pick = i;
  return pick;
}

BenchDiffrenderReport runBenchDiffrender(const BenchDiffrenderOptions& o, std::FILE* log) {
  namespace fs = std::filesystem;
  drbench::checkOptions(o);
  drbench::Bench b(o);
  b.log = log;
  b.sceneFile = fs::absolute(o.scene);
  b.dir = o.out.empty() ? b.sceneFile.parent_path() / "bench-diffrender" : fs::absolute(o.out);
  std::filesystem::create_directories(b.dir);
  b.probe = gi::loadScene(b.sceneFile);
  if (!differential::applies(b.probe))
    throw Error(b.sceneFile.string(), "scene.gi.parameters.capture",
                "bench diffrender needs inserted meshes (meshes[].inserted) and a capture layer "
                "(gi.parameters.capture; nestlight make-scene diffrender makes such a scene)");
  b.W = o.width ? o.width : b.probe.camera.width;
  b.H = o.height ? o.height : b.probe.camera.height;
  // Every configuration resolves before anything is rendered: a bad value costs no reference.
  for (const nlohmann::json& overrides : drbench::plannedOverrides(o))
    gi::diffrenderParameters(b.scene(overrides));
  b.glDevice = gl::createHeadlessContext()->description();  // the methods make their own
  b.prepareTruth();
  say(log, "bench diffrender: %d timed runs per configuration after the set-up frame\n", o.runs);
  return drbench::makeTables(b);
}

}  // namespace nestlight::bench
