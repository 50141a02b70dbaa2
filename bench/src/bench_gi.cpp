// `nestlight bench gi` (nestlight/bench/bench_gi.h).
#include "nestlight/bench/bench_gi.h"

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>

#include "nestlight/bench/harness.h"
#include "nestlight/gi/environment_sequence.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/plot.h"
#include "nestlight/gi/reference/path_tracer.h"  // kReferenceModelVersion, by reference_scene.h
#include "nestlight/gi/render_scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace gi;

namespace {

std::string fileHash(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return std::to_string(std::hash<std::string>{}(bytes));
}

// What the reference depends on besides the scene file: its octrees (metadata and payload),
// meshes and environment map, by size and modification time, so an edited asset is noticed.
std::string assetStamp(const Scene& s) {
  std::string stamp;
  auto add = [&](const fs::path& p) {
    std::error_code ec;
    auto size = fs::file_size(p, ec);
    auto time = fs::last_write_time(p, ec).time_since_epoch().count();
    stamp += p.string() + "=" + std::to_string(ec ? 0 : size) + "@" +
             std::to_string(ec ? 0 : time) + ";";
  };
  for (const auto& o : s.octrees) {
    add(o.path / "metadata.json");
    add(o.path / "octree.bin");
  }
  for (const auto& m : s.meshes) add(m.path);
  if (s.environment && !s.environment->path.empty()) add(s.environment->path);
  if (s.environment && !s.environment->sequence.empty()) {
    try {
      const EnvironmentSequence seq(sequenceSpec(*s.environment));
      for (size_t i = 0; i < seq.frames(); ++i) add(seq.framePath(i));
    } catch (const Error&) {
      add(s.environment->sequence);  // the render names what is wrong with it
    }
  }
  return std::to_string(std::hash<std::string>{}(stamp));
}

// log-log interpolation of the time at which `rows` (in order of quality) reach `target`.
// `box4`: the error of 4 x 4-pixel block means.
json timeToError(const std::vector<const BenchGiRow*>& rows, double target, bool box4 = false) {
  auto err = [box4](const BenchGiRow& r) { return box4 ? r.relativeL2Box4 : r.relativeL2; };
  for (size_t i = 0; i < rows.size(); ++i) {
    if (err(*rows[i]) <= target) {
      if (i == 0) return {{"ms", rows[0]->medianMs}, {"how", "reached at the lowest setting"}};
      const BenchGiRow &a = *rows[i - 1], &b = *rows[i];
      double t = (std::log(target) - std::log(err(a))) / (std::log(err(b)) - std::log(err(a)));
      return {{"ms",
               std::exp(std::log(a.medianMs) + t * (std::log(b.medianMs) - std::log(a.medianMs)))},
              {"how", "interpolated between " + std::to_string(a.quality) + " and " +
                          std::to_string(b.quality) + " " + a.qualityName}};
    }
  }
  if (rows.empty() || !(err(*rows.back()) > 0)) return {{"ms", nullptr}, {"how", "no data"}};
  const BenchGiRow& b = *rows.back();
  if (b.qualityName != "samples per pixel")
    return {{"ms", nullptr},
            {"how", "not reached (" + std::to_string(err(b)) + " at the best setting)"}};
  // Monte Carlo error falls as 1/sqrt(time): extrapolate from the best setting.
  double ms = b.medianMs * std::pow(err(b) / target, 2);
  return {{"ms", ms},
          {"how", "extrapolated as error ~ time^-1/2 from " + std::to_string(b.quality) + " spp"}};
}

// The scene every measured run starts from, as the options set it: the method asked for, the
// mode and the image size.
struct Setup {
  const BenchGiOptions& o;
  fs::path sceneFile;
  Scene probe;
  int W = 0, H = 0;
  Scene prepared(const std::string& method) const {
    Scene s = probe;
    s.gi.method = method;
    if (o.mode == "albedo") s.gi.mode = RadianceMode::Albedo;
    if (o.mode == "radiance_cache") s.gi.mode = RadianceMode::RadianceCache;
    s.camera.width = W;
    s.camera.height = H;
    return s;
  }
};

// The methods asked for (default: every registered one), the options checked first: a typo must
// not cost a reference render.
std::vector<const MethodInfo*> selectMethods(const BenchGiOptions& o) {
  std::vector<const MethodInfo*> methods;
  if (o.methods.empty())
    for (const auto& m : registeredMethods()) methods.push_back(&m);
  for (const auto& name : o.methods) {
    const MethodInfo* m = findMethod(name);
    if (!m) throw Error("bench gi: unknown method '" + name + "' (" + methodList() + ")");
    methods.push_back(m);
  }
  for (const auto& [name, levels] : o.qualities) {
    if (!findMethod(name))
      throw Error("bench gi: quality levels for unknown method '" + name + "' (" + methodList() +
                  ")");
    if (levels.empty()) throw Error("bench gi: no quality levels for '" + name + "'");
  }
  if (o.runs < 1) throw Error("bench gi: --runs must be at least 1");
  if (!o.mode.empty() && o.mode != "albedo" && o.mode != "radiance_cache")
    throw Error("bench gi: --mode must be albedo or radiance_cache, got '" + o.mode + "'");
  return methods;
}

struct Reference {
  HdrImage image;
  json info;
};

// The reference, cached in refPath under a key of everything that changes it.
Reference loadOrRenderReference(const Setup& setup, const fs::path& refPath, std::FILE* log) {
  const BenchGiOptions& o = setup.o;
  const std::string key = "model" + std::to_string(kReferenceModelVersion) + ":" +
                          fileHash(setup.sceneFile) + ":" + assetStamp(setup.probe) + ":" +
                          std::to_string(setup.W) + "x" + std::to_string(setup.H) + ":" +
                          std::to_string(o.referenceError) + ":" + o.mode;
  Reference ref;
  if (!o.forceReference && fs::exists(refPath)) {
    ImageAttributes attrs;
    HdrImage img = readHdrImage(refPath.string(), &attrs);
    if (attrs["nestlight:cache_key"] == key) {
      ref.image = std::move(img);
      ref.info = {{"cached", true},
                  {"samples", attrs["nestlight:samples"]},
                  {"relative_error_estimate", attrs["nestlight:relative_error_estimate"]},
                  {"seconds", attrs["nestlight:seconds"]}};
      return ref;
    }
  }
  say(log, "bench gi: rendering the reference to %.4g relative error (at most %.0f s, %d spp)...\n",
      o.referenceError, o.referenceTimeLimit, o.referenceSpp);
  Scene s = setup.prepared("reference");
  s.gi.targetRelativeError = o.referenceError;
  s.gi.timeLimitSeconds = o.referenceTimeLimit;
  s.gi.samplesPerPixel = o.referenceSpp;
  s.gi.seed = 0x5eed;  // independent of the measured runs' seed
  MethodFrame r = createMethod(s, {true, false})->render(s.camera);
  ref.image = r.image;
  // One that stopped short of the error target (time or sample limit) is kept for this run
  // but not reused: the next run tries again.
  ImageAttributes attrs{
      {"nestlight:cache_key", r.stopReason == "error target" ? key : "incomplete"},
      {"nestlight:samples", std::to_string(r.samplesPerPixel)},
      {"nestlight:relative_error_estimate", std::to_string(r.relativeError)},
      {"nestlight:seconds", std::to_string(r.seconds)},
      {"nestlight:stop", r.stopReason}};
  writeExr(refPath.string(), ref.image, attrs);
  ref.info = {{"cached", false},
              {"samples", r.samplesPerPixel},
              {"relative_error_estimate", r.relativeError},
              {"seconds", r.seconds},
              {"stop", r.stopReason},
              {"rays_per_second", r.raysPerSecond()},
              {"samples_per_second", r.samplesPerSecond()}};
  say(log, "  reference: %d spp, estimated error %.4f, %.1f s (%s)\n", r.samplesPerPixel,
      r.relativeError, r.seconds, r.stopReason.c_str());
  if (r.stopReason != "error target")
    say(log,
        "  warning: the reference stopped before %.4g error; errors below its own are not "
        "meaningful\n",
        o.referenceError);
  return ref;
}

// One configuration (method, variant, quality level): timed over the runs, its first frame
// written and compared with the reference, its table row printed.
BenchGiRow runConfiguration(const Setup& setup, const MethodInfo& m,
                            const MethodInfo::Variant& variant, int level,
                            const HdrImage& reference, const fs::path& refPath, const fs::path& dir,
                            std::FILE* log) {
  Scene s = setup.prepared(m.name);
  s.gi.seed = 1;
  // The variant first: a quality level may mean different settings under it (ibl's
  // estimators).
  variant.apply(s.gi);
  m.applyQuality(s.gi, level);
  std::unique_ptr<Method> method = createMethod(s, {true, false, true});
  BenchGiRow row;
  row.method = m.name;
  row.variant = variant.name;
  row.qualityName = m.qualityName;
  row.quality = level;
  MethodFrame first;
  for (int run = 0; run < setup.o.runs; ++run) {
    MethodFrame f = method->render(s.camera);
    row.ms.push_back(f.seconds * 1e3);
    if (run == 0) first = std::move(f);
  }
  row.medianMs = median(row.ms);
  row.raysPerSecond = first.raysPerSecond();
  row.samplesPerSecond = first.samplesPerSecond();
  row.passMs = first.passMs;
  row.attributes = first.attributes;
  std::string stem =
      m.name + (variant.name.empty() ? "" : "_" + variant.name) + "_" + std::to_string(level);
  std::replace(stem.begin(), stem.end(), ' ', '_');
  writeExr((dir / (stem + ".exr")).string(), first.image, first.attributes);
  CompareOptions co;
  co.testName = m.name + " " + std::to_string(level);
  co.referenceName = refPath.string();
  co.exposureStops = setup.probe.output.exposure;
  row.cmp = compareImages(first.image, reference, co);
  row.relativeL2 = relativeL2(first.image, reference);
  row.relativeL2Box4 = relativeL2(boxFilter(first.image, 4), boxFilter(reference, 4));
  const std::string label = m.name + (variant.name.empty() ? "" : " (" + variant.name + ")");
  say(log, "%-10s %8d %10.1f %12.3g %10.4f %10.4g %9.2f %7.4f %11.4f\n", label.c_str(), level,
      row.medianMs, row.raysPerSecond, row.relativeL2, row.cmp.linear.rmse, row.cmp.linear.psnr,
      row.cmp.linear.ssim, row.cmp.toneMapped.ssim);
  return row;
}

std::string csvLine(const BenchGiRow& r) {
  auto [lo, hi] = std::minmax_element(r.ms.begin(), r.ms.end());
  char line[640];
  std::snprintf(
      line, sizeof line,
      "%s,%s,%d,%s,%zu,%.3f,%.3f,%.3f,%.6g,%.6g,%.6g,%.6g,%.6g,%.4f,%.6f,%.6g,%.4f,%.6f,%llu\n",
      r.method.c_str(), r.variant.c_str(), r.quality, r.qualityName.c_str(), r.ms.size(),
      r.medianMs, *lo, *hi, r.raysPerSecond, r.samplesPerSecond, r.relativeL2, r.cmp.linear.rmse,
      r.cmp.linear.relativeMse, r.cmp.linear.psnr, r.cmp.linear.ssim, r.cmp.toneMapped.rmse,
      r.cmp.toneMapped.psnr, r.cmp.toneMapped.ssim, (unsigned long long)r.cmp.test.pixels);
  return line;
}

json rowJson(const BenchGiRow& r) {
  json passes = json::object();
  for (const auto& [name, ms] : r.passMs) passes[name] = ms;
  json attrs = json::object();
  for (const auto& [k, v] : r.attributes) attrs[k] = v;
  return {{"method", r.method},
          {"variant", r.variant},
          {"attributes", attrs},
          {"quality", r.quality},
          {"quality_name", r.qualityName},
          {"runs_ms", r.ms},
          {"median_ms", r.medianMs},
          {"rays_per_second", r.raysPerSecond},
          {"samples_per_second", r.samplesPerSecond},
          {"gpu_pass_ms", passes},
          {"relative_l2", r.relativeL2},
          {"relative_l2_box4", r.relativeL2Box4},
          {"comparison", toJson(r.cmp)}};
}

void sayTimesTo(std::FILE* log, const char* what, const json& times) {
  for (const auto& [name, t] : times.items()) {
    say(log, "time to %s, %s: %s ms (%s)\n", what, name.c_str(),
        t["ms"].is_null() ? "-" : std::to_string(int64_t(t["ms"].get<double>())).c_str(),
        t["how"].get<std::string>().c_str());
  }
}

// bench_gi.csv, .json (also report.json) and .svg, and the times to 10% and 1% error.
void writeReport(BenchGiReport& report, const Setup& setup, const json& refInfo, std::FILE* log) {
  const fs::path& dir = report.dir;
  const std::string device =
      (setup.o.device.empty() ? std::string("unknown CPU") : setup.o.device) + ", " +
      std::to_string(tbb::info::default_concurrency()) +
      " threads (CPU methods: Embree 3; GL methods: the context's device)";
  std::ofstream csv(dir / "bench_gi.csv");
  csv << "method,variant,quality,quality_name,runs,median_ms,min_ms,max_ms,rays_per_second,samples_"
         "per_second,relative_l2,"
         "rmse,relative_mse,psnr_db,ssim,rmse_tonemapped,psnr_tonemapped_db,ssim_tonemapped,"
         "nonfinite_pixels\n";
  json jrows = json::array();
  std::vector<PlotSeries> series;
  json timeTo1, timeTo10, timeTo10Box4;
  // One series per method and variant, in the order they ran.
  std::vector<std::pair<std::string, std::string>> keys;
  for (const BenchGiRow& r : report.rows)
    if (std::find(keys.begin(), keys.end(), std::make_pair(r.method, r.variant)) == keys.end())
      keys.emplace_back(r.method, r.variant);
  for (const auto& [methodName, variantName] : keys) {
    PlotSeries ps;
    ps.name = methodName + (variantName.empty() ? "" : " (" + variantName + ")");
    std::vector<const BenchGiRow*> mine;
    for (const BenchGiRow& r : report.rows) {
      if (r.method != methodName || r.variant != variantName) continue;
      mine.push_back(&r);
      csv << csvLine(r);
      jrows.push_back(rowJson(r));
      ps.points.push_back({r.medianMs, r.relativeL2, std::to_string(r.quality)});
    }
    timeTo1[ps.name] = timeToError(mine, 0.01);
    timeTo10[ps.name] = timeToError(mine, 0.1);
    timeTo10Box4[ps.name] = timeToError(mine, 0.1, true);
    series.push_back(std::move(ps));
  }
  report.json = {
      {"scene", setup.sceneFile.string()},
      {"device", device},
      {"mode",
       setup.prepared("reference").gi.mode == RadianceMode::Albedo ? "albedo" : "radiance_cache"},
      {"width", setup.W},
      {"height", setup.H},
      {"runs", setup.o.runs},
      {"reference", refInfo},
      {"rows", jrows},
      {"time_to_1_percent", timeTo1},
      {"time_to_10_percent", timeTo10},
      {"time_to_10_percent_box4", timeTo10Box4},
      {"error_measure", "relative L2: sqrt(sum (t - r)^2 / sum r^2) over pixels and channels"}};
  std::ofstream(dir / "bench_gi.json") << report.json.dump(2) << "\n";
  writeSvgPlot((dir / "bench_gi.svg").string(),
               "GI speed against error: " + setup.sceneFile.parent_path().filename().string(),
               "time per frame (ms, " + device + ")", "relative L2 error against the reference",
               series, true, true);
  sayTimesTo(log, "10% relative error of 4x4-pixel means", timeTo10Box4);
  sayTimesTo(log, "10% relative error", timeTo10);
  sayTimesTo(log, "1% relative error", timeTo1);
  say(log, "bench gi: wrote %s/bench_gi.{csv,json,svg} (device: %s)\n", dir.c_str(),
      device.c_str());
}

}  // namespace

BenchGiReport runBenchGi(const BenchGiOptions& o, std::FILE* log) {
  const std::vector<const MethodInfo*> methods = selectMethods(o);
  Setup setup{o, fs::absolute(o.scene), {}};
  BenchGiReport report;
  report.dir = o.out.empty() ? setup.sceneFile.parent_path() / "bench-gi" : o.out;
  const fs::path& dir = report.dir;
  fs::create_directories(dir);
  setup.probe = loadScene(setup.sceneFile);
  checkSceneMethod(setup.probe);  // the registry names the methods, not the scene parser
  setup.W = o.width ? o.width : setup.probe.camera.width;
  setup.H = o.height ? o.height : setup.probe.camera.height;

  if (!sceneHasLight(setup.prepared("reference"), setup.prepared("reference").gi.mode))
    throw Error(
        setup.sceneFile.string(), "lights",
        "nothing lights this scene in albedo mode (scan colours are reflectances there, and it has "
        "no "
        "lights, no environment and no emissive mesh): every method would render black. Use "
        "--mode radiance_cache, or add a light");

  const fs::path refPath = dir / "reference.exr";
  const Reference reference = loadOrRenderReference(setup, refPath, log);
  writeToneMappedPng((dir / "reference.png").string(), reference.image,
                     setup.probe.output.exposure);

  say(log, "%-10s %8s %10s %12s %10s %10s %9s %7s %11s\n", "method", "quality", "median ms",
      "rays/s", "rel L2", "RMSE", "PSNR dB", "SSIM", "SSIM (tm)");
  for (const MethodInfo* m : methods) {
    if (!m->albedoMode && setup.prepared(m->name).gi.mode == RadianceMode::Albedo) {
      say(log, "%s: skipped (it renders the radiance-cache mode only so far)\n", m->name.c_str());
      continue;
    }
    auto q = o.qualities.find(m->name);
    const std::vector<int>& levels = q != o.qualities.end() ? q->second : m->defaultQualities;
    std::vector<MethodInfo::Variant> variants = {{"", [](GiSettings&) {}}};
    if (o.variants) variants.insert(variants.end(), m->variants.begin(), m->variants.end());
    for (const auto& variant : variants)
      for (int level : levels)
        report.rows.push_back(
            runConfiguration(setup, *m, variant, level, reference.image, refPath, dir, log));
  }
  writeReport(report, setup, reference.info, log);
  return report;
}

}  // namespace nestlight::bench
