// `nestlight bench gi` (nestlight/bench/bench_gi.h).
#include "nestlight/bench/bench_gi.h"

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <optional>

#include "bench_gi_differential.h"
#include "bench_gi_reference.h"
#include "nestlight/bench/harness.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/plot.h"
#include "nestlight/gi/render_scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace gi;

namespace {

std::string shortNumber(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

json timeJson(const TimeToError& t) {
  json j = {{"ms", t.ms ? json(*t.ms) : json(nullptr)}, {"how", t.how}};
  if (t.slope) j["log_log_slope"] = *t.slope;
  return j;
}

// The scene every measured run starts from, as the options set it: the method asked for, the
// mode and the image size.
struct Setup {
  const BenchGiOptions& o;
  fs::path sceneFile;
  Scene probe;
  int W = 0, H = 0;
  // reference.png's exposure (the scene's output.exposure, else automatic from the reference), and
  // the one the tone-mapped metrics use: they judge the pixels a reader of the PNGs sees.
  double exposure = 0;
  Scene prepared(const std::string& method) const {
    return reference::sceneFor(probe, method, o.mode, W, H);
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

using Reference = reference::Image;

// The reference, cached in refPath under a key of everything that changes it; `withoutInserted`:
// R0, the scene as it was captured (the meshes marked inserted left out).
Reference loadOrRenderReference(const Setup& setup, const fs::path& refPath, std::FILE* log,
                                bool withoutInserted = false) {
  const BenchGiOptions& o = setup.o;
  reference::Request r;
  r.sceneFile = setup.sceneFile;
  r.probe = setup.probe;
  r.mode = o.mode;
  r.width = setup.W, r.height = setup.H;
  r.error = o.referenceError, r.timeLimit = o.referenceTimeLimit, r.spp = o.referenceSpp;
  r.force = o.forceReference;
  return reference::loadOrRender(r, refPath, log, withoutInserted);
}

// A quality level's short unit, for the plot's labels and the table.
std::string qualityUnit(const MethodInfo& m) {
  if (m.qualityName == "samples per pixel") return "spp";
  if (m.qualityName == "shadow-map texels") return "texels";
  if (m.qualityName == "micro-buffer m-pixels per side") return "m-px";
  return m.qualityName;
}

double msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

std::string fixed(double v, int digits) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

BenchGiRow newRow(const MethodInfo& m, const std::string& variant, int level) {
  BenchGiRow row;
  row.method = m.name;
  row.variant = variant;
  row.qualityName = m.qualityName;
  row.qualityUnit = qualityUnit(m);
  row.quality = level;
  return row;
}

std::string rowStem(const BenchGiRow& row) {
  std::string stem = row.method + (row.variant.empty() ? "" : "_" + row.variant) + "_" +
                     std::to_string(row.quality);
  std::replace(stem.begin(), stem.end(), ' ', '_');
  return stem;
}

// The timed runs' summary and the last frame, written and compared with the reference.
void finishRow(BenchGiRow& row, const Setup& setup, const MethodFrame& last,
               const HdrImage& reference, const fs::path& refPath, const fs::path& dir) {
  row.medianMs = median(row.ms);
  row.raysPerSecond = last.raysPerSecond();
  row.samplesPerSecond = last.samplesPerSecond();
  row.passMs = last.passMs;
  row.attributes = last.attributes;
  writeExr((dir / (rowStem(row) + ".exr")).string(), last.image, last.attributes);
  CompareOptions co;
  co.testName = row.method + " " + std::to_string(row.quality);
  co.referenceName = refPath.string();
  co.exposureStops = setup.exposure;
  row.cmp = compareImages(last.image, reference, co);
  row.relativeL2 = relativeL2(last.image, reference);
  row.relativeL2Box4 = relativeL2(boxFilter(last.image, 4), boxFilter(reference, 4));
}

void sayRow(std::FILE* log, const BenchGiRow& row) {
  std::string extra;
  if (row.deltaL2) extra += ", dL L2 " + fixed(*row.deltaL2, 4);
  if (row.objectL2) extra += ", object L2 " + fixed(*row.objectL2, 4);
  if (row.rhoL2) extra += ", rho L2 " + fixed(*row.rhoL2, 4);
  say(log, "  %s%s, %d %s: set-up %.0f ms, median %.1f ms, relative L2 %.4f%s\n",
      row.method.c_str(), row.variant.empty() ? "" : (" (" + row.variant + ")").c_str(),
      row.quality, row.qualityUnit.c_str(), row.setupMs, row.medianMs, row.relativeL2,
      extra.c_str());
}

// diffrender's dL and material estimate, from one more frame with its AOVs, untimed: reading
// them back costs what the timed frames must not pay.
void diffrenderMetrics(BenchGiRow& row, Scene s, const HdrImage& composite,
                       const differential::Truth& truth, const fs::path& dir) {
  const fs::path aovs = dir / "differential" / rowStem(row);
  differential::setGiParameter(s, "aovs", aovs.string());
  createMethod(s, {true, false, true})->render(s.camera);
  const HdrImage delta = readHdrImage((aovs / "diffrender_delta.exr").string());
  const HdrImage rho = readHdrImage((aovs / "diffrender_rho.exr").string());
  const differential::Metrics m = differential::measure(composite, delta, &rho, truth);
  row.deltaL2 = m.deltaL2, row.objectL2 = m.objectL2, row.rhoL2 = m.rhoL2;
}

// One configuration (method, variant, quality level): set up (the method made, and a GL
// method's first frame, which compiles its shaders and fills its caches, rendered untimed), then
// timed over the runs; the last timed frame is written and compared with the reference.
BenchGiRow runConfiguration(const Setup& setup, const MethodInfo& m,
                            const MethodInfo::Variant& variant, int level,
                            const HdrImage& reference, const fs::path& refPath, const fs::path& dir,
                            const differential::Truth* truth, std::FILE* log) {
  Scene s = setup.prepared(m.name);
  s.gi.seed = 1;
  // The variant first: a quality level may mean different settings under it (ibl's
  // estimators).
  variant.apply(s.gi);
  m.applyQuality(s.gi, level);
  BenchGiRow row = newRow(m, variant.name, level);
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<Method> method = createMethod(s, {true, false, true});
  // A CPU method's first frame costs what any other does (its scene is built when it is made).
  if (m.gpu) method->render(s.camera);
  row.setupMs = msSince(start);
  MethodFrame last;
  for (int run = 0; run < setup.o.runs; ++run) {
    last = method->render(s.camera);
    row.ms.push_back(last.seconds * 1e3);
  }
  method.reset();
  finishRow(row, setup, last, reference, refPath, dir);
  if (truth && m.name == "diffrender") diffrenderMetrics(row, s, last.image, *truth, dir);
  sayRow(log, row);
  return row;
}

// Two-simulation differential rendering, the baseline of a method that renders a whole scene
// (pbgi, vpl): the method with the inserted meshes and without them, the difference added to the
// capture on the scan's pixels, the meshes' pixels as rendered with them. A run's time is the
// two frames'.
BenchGiRow runTwoSimulation(const Setup& setup, const MethodInfo& m, int level,
                            const HdrImage& reference, const fs::path& refPath, const fs::path& dir,
                            const differential::Truth& truth, std::FILE* log) {
  Scene with = setup.prepared(m.name);
  with.gi.seed = 1;
  m.applyQuality(with.gi, level);
  const Scene without = differential::withoutInserted(with);
  BenchGiRow row = newRow(m, "two-simulation", level);
  // One method at a time: a GL method's context is its own while it lives.
  auto timed = [&](const Scene& s, std::vector<double>& ms) {
    const auto start = std::chrono::steady_clock::now();
    std::unique_ptr<Method> method = createMethod(s, {true, false, true});
    if (m.gpu) method->render(s.camera);
    row.setupMs += msSince(start);
    MethodFrame f;
    for (int run = 0; run < setup.o.runs; ++run) {
      f = method->render(s.camera);
      ms.push_back(f.seconds * 1e3);
    }
    return f;
  };
  std::vector<double> msWith, msWithout;
  const MethodFrame fa = timed(with, msWith), fb = timed(without, msWithout);
  for (size_t run = 0; run < msWith.size(); ++run) row.ms.push_back(msWith[run] + msWithout[run]);
  HdrImage delta;
  MethodFrame last = fa;
  last.image = differential::twoSimulation(fa.image, fb.image, truth, delta);
  last.seconds = fa.seconds + fb.seconds;
  last.rays = fa.rays + fb.rays;
  last.passMs.clear();
  finishRow(row, setup, last, reference, refPath, dir);
  const differential::Metrics dm = differential::measure(last.image, delta, nullptr, truth);
  row.deltaL2 = dm.deltaL2, row.objectL2 = dm.objectL2;
  sayRow(log, row);
  return row;
}

std::string seriesName(const std::string& method, const std::string& variant) {
  return method + (variant.empty() ? "" : " (" + variant + ")");
}

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string optionalNumber(const std::optional<double>& v) {
  char buf[32] = "";
  if (v) std::snprintf(buf, sizeof buf, "%.6g", *v);
  return buf;
}

json optionalJson(const std::optional<double>& v) {
  return v ? json(*v) : json(nullptr);
}

std::string csvLine(const BenchGiRow& r) {
  auto [lo, hi] = std::minmax_element(r.ms.begin(), r.ms.end());
  char rays[40] = "";
  if (r.raysPerSecond > 0) std::snprintf(rays, sizeof rays, "%.6g", r.raysPerSecond);
  char line[640];
  std::snprintf(line, sizeof line,
                "%s,%s,%d,%s,%zu,%.3f,%.3f,%.3f,%.3f,%s,%.6g,%.6g,%.6g,%.6g,%.4f,%.6f,%.6g,%.4f,"
                "%.6f,%llu,%s,%s,%s,\n",
                r.method.c_str(), csvField(r.variant).c_str(), r.quality, r.qualityName.c_str(),
                r.ms.size(), r.setupMs, r.medianMs, *lo, *hi, rays, r.samplesPerSecond,
                r.relativeL2, r.cmp.linear.rmse, r.cmp.linear.relativeMse, r.cmp.linear.psnr,
                r.cmp.linear.ssim, r.cmp.toneMapped.rmse, r.cmp.toneMapped.psnr,
                r.cmp.toneMapped.ssim, (unsigned long long)r.cmp.test.pixels,
                optionalNumber(r.deltaL2).c_str(), optionalNumber(r.objectL2).c_str(),
                optionalNumber(r.rhoL2).c_str());
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
          {"setup_ms", r.setupMs},
          {"runs_ms", r.ms},
          {"median_ms", r.medianMs},
          // A method that traces no rays (GL rasterisation) has none to count.
          {"rays_per_second", r.raysPerSecond > 0 ? json(r.raysPerSecond) : json(nullptr)},
          {"samples_per_second", r.samplesPerSecond},
          {"gpu_pass_ms", passes},
          {"relative_l2", r.relativeL2},
          {"relative_l2_box4", r.relativeL2Box4},
          {"delta_l2", optionalJson(r.deltaL2)},
          {"object_l2", optionalJson(r.objectL2)},
          {"rho_l2", optionalJson(r.rhoL2)},
          {"comparison", toJson(r.cmp)}};
}

// The text table, its columns as wide as their cells; then the skipped rows with their reasons.
void sayTable(std::FILE* log, const BenchGiReport& report) {
  std::vector<std::vector<std::string>> t = {{"method", "variant", "quality", "set-up ms",
                                              "median ms", "runs", "rays/s", "rel L2", "RMSE",
                                              "PSNR dB", "SSIM", "SSIM (tm)"}};
  for (const BenchGiRow& r : report.rows)
    t.push_back({r.method, r.variant.empty() ? "—" : r.variant,
                 std::to_string(r.quality) + " " + r.qualityUnit, fixed(r.setupMs, 0),
                 fixed(r.medianMs, 1), std::to_string(r.ms.size()),
                 r.raysPerSecond > 0 ? humanCount(r.raysPerSecond) : "—", fixed(r.relativeL2, 4),
                 shortNumber(r.cmp.linear.rmse), fixed(r.cmp.linear.psnr, 2),
                 fixed(r.cmp.linear.ssim, 4), fixed(r.cmp.toneMapped.ssim, 4)});
  std::vector<bool> right = {false, false, true, true, true, true,
                             true,  true,  true, true, true, true};
  // Differential rendering's columns, where a row has them.
  if (std::any_of(report.rows.begin(), report.rows.end(),
                  [](const BenchGiRow& r) { return r.deltaL2.has_value(); })) {
    t[0].insert(t[0].end(), {"dL L2", "object L2", "rho L2"});
    for (size_t i = 1; i < t.size(); ++i) {
      const BenchGiRow& r = report.rows[i - 1];
      for (const auto& v : {r.deltaL2, r.objectL2, r.rhoL2}) t[i].push_back(v ? fixed(*v, 4) : "—");
    }
    right.insert(right.end(), {true, true, true});
  }
  say(log, "%s", alignedTable(t, right).c_str());
  if (report.r0RelativeL2)
    say(log,
        "R0 (the reference without the inserted meshes: no differential rendering): rel L2 %.4f\n",
        *report.r0RelativeL2);
  if (report.skipped.empty()) return;
  say(log, "skipped:\n");
  std::vector<std::vector<std::string>> k = {{"method", "variant", "why"}};
  for (const BenchGiSkip& sk : report.skipped)
    k.push_back({sk.method, sk.variant.empty() ? "(all)" : sk.variant, sk.reason});
  say(log, "%s", alignedTable(k).c_str());
}

void sayTimesTo(std::FILE* log, const char* what, const json& times) {
  for (const auto& [name, t] : times.items()) {
    say(log, "time to %s, %s: %s ms (%s)\n", what, name.c_str(),
        t["ms"].is_null() ? "-" : std::to_string(int64_t(t["ms"].get<double>())).c_str(),
        t["how"].get<std::string>().c_str());
  }
}

// The plot's series, one per method and variant in the order they ran: one colour a method, one
// marker a variant, points labelled with their quality and its unit.
std::vector<PlotSeries> plotSeries(const BenchGiReport& report) {
  std::vector<PlotSeries> series;
  for (const BenchGiRow& r : report.rows) {
    const std::string name = seriesName(r.method, r.variant);
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const PlotSeries& ps) { return ps.name == name; });
    if (it == series.end()) it = series.insert(series.end(), {name, {}, r.method});
    it->points.push_back(
        {r.medianMs, r.relativeL2, std::to_string(r.quality) + " " + r.qualityUnit});
  }
  return series;
}

// bench_gi.csv, .json (also report.json), .svg and .png, and the times to 10% and 1% error.
void writeReport(BenchGiReport& report, const Setup& setup, const json& refInfo,
                 const json& differentialInfo, std::FILE* log) {
  const fs::path& dir = report.dir;
  const std::string device =
      (setup.o.device.empty() ? std::string("unknown CPU") : setup.o.device) + ", " +
      std::to_string(tbb::info::default_concurrency()) +
      " threads (CPU methods: Embree 3; GL methods: the context's device)";
  std::ofstream csv(dir / "bench_gi.csv");
  csv << "method,variant,quality,quality_name,runs,setup_ms,median_ms,min_ms,max_ms,rays_per_"
         "second,samples_per_second,relative_l2,rmse,relative_mse,psnr_db,ssim,rmse_tonemapped,"
         "psnr_tonemapped_db,ssim_tonemapped,nonfinite_pixels,delta_l2_scan,object_l2,rho_l2,"
         "skipped\n";
  json jrows = json::array(), jskipped = json::array();
  json timeTo1, timeTo10, timeTo10Box4;
  for (const PlotSeries& ps : plotSeries(report)) {
    std::vector<ErrorPoint> curve, box4;
    for (const BenchGiRow& r : report.rows) {
      if (seriesName(r.method, r.variant) != ps.name) continue;
      csv << csvLine(r);
      jrows.push_back(rowJson(r));
      const std::string label = std::to_string(r.quality) + " " + r.qualityUnit;
      curve.push_back({r.medianMs, r.relativeL2, label});
      box4.push_back({r.medianMs, r.relativeL2Box4, label});
    }
    timeTo1[ps.name] = timeJson(timeToError(curve, 0.01));
    timeTo10[ps.name] = timeJson(timeToError(curve, 0.1));
    timeTo10Box4[ps.name] = timeJson(timeToError(box4, 0.1));
  }
  for (const BenchGiSkip& sk : report.skipped) {
    csv << sk.method << "," << csvField(sk.variant) << ",,,0,,,,,,,,,,,,,,,,,,,"
        << csvField(sk.reason) << "\n";
    jskipped.push_back({{"method", sk.method}, {"variant", sk.variant}, {"reason", sk.reason}});
  }
  report.json = {
      {"scene", setup.sceneFile.string()},
      {"device", device},
      {"mode",
       setup.prepared("reference").gi.mode == RadianceMode::Albedo ? "albedo" : "radiance_cache"},
      {"width", setup.W},
      {"height", setup.H},
      {"runs", setup.o.runs},
      {"timing",
       "median of the runs' frame times, after the set-up (making the method and, for a GL "
       "method, one untimed frame that compiles its shaders), reported apart as setup_ms"},
      {"reference", refInfo},
      {"differential", differentialInfo},
      {"exposure_stops", setup.exposure},
      {"rows", jrows},
      {"skipped", jskipped},
      {"time_to_1_percent", timeTo1},
      {"time_to_10_percent", timeTo10},
      {"time_to_10_percent_box4", timeTo10Box4},
      {"time_to_error_rule",
       "first point at or below the target, log-log interpolated; else extrapolated along the "
       "least-squares line of log error on log time over the last " +
           std::to_string(kTimeFitPoints) + " points, only where its slope is at most " +
           shortNumber(kTimeFitSlope) + " and the time it gives at most " +
           shortNumber(kTimeFitReach) + "x the longest measured and the points span at least " +
           shortNumber(kTimeFitSpan) + "x in time; else not reached"},
      {"error_measure", "relative L2: sqrt(sum (t - r)^2 / sum r^2) over pixels and channels"}};
  std::ofstream(dir / "bench_gi.json") << report.json.dump(2) << "\n";
  const std::string title =
      "GI speed against error: " + setup.sceneFile.parent_path().filename().string();
  const std::string xLabel =
      "time per frame, ms (median of " + std::to_string(setup.o.runs) + " runs after set-up; " +
      (setup.o.device.empty() ? std::string("unknown CPU") : setup.o.device) + ", " +
      std::to_string(tbb::info::default_concurrency()) + " threads)";
  const std::vector<PlotSeries> series = plotSeries(report);
  writeSvgPlot((dir / "bench_gi.svg").string(), title, xLabel,
               "relative L2 error against the reference", series, true, true);
  writePngPlot((dir / "bench_gi.png").string(), title, xLabel,
               "relative L2 error against the reference", series, true, true);
  sayTable(log, report);
  sayTimesTo(log, "10% relative error of 4x4-pixel means", timeTo10Box4);
  sayTimesTo(log, "10% relative error", timeTo10);
  sayTimesTo(log, "1% relative error", timeTo1);
  say(log, "bench gi: wrote %s/bench_gi.{csv,json,svg,png} (device: %s)\n", dir.c_str(),
      device.c_str());
}

// R0 (cached as the reference is) and the images diffrender's metrics and the two-simulation
// baselines need (bench_gi_differential.h).
differential::Truth makeDifferentialTruth(const Setup& setup, const HdrImage& r1,
                                          const fs::path& dir, std::FILE* log) {
  const fs::path r0Path = dir / "reference_without.exr";
  Reference r0 = loadOrRenderReference(setup, r0Path, log, true);
  writeToneMappedPng((dir / "reference_without.png").string(), r0.image, setup.exposure);
  differential::Truth t = differential::makeTruth(
      setup.prepared("diffrender"), r1, std::move(r0.image), dir / "differential" / "truth");
  t.info["r0"] = r0.info;
  say(log,
      "  R0 against R1 (no differential rendering): relative L2 %.4f (of 4x4 block means %.4f), "
      "on the inserted meshes' pixels %.4f, dL on scan blocks %.4f (%s scan blocks of %dx%d "
      "pixels); the capture "
      "against R0 on scan pixels %.4f (what adding to it cannot remove)\n",
      t.r0Error, t.info["r0_relative_l2_box4"].get<double>(), t.r0ObjectError, t.r0ChangeError,
      std::to_string(t.info["scan_blocks"].get<size_t>()).c_str(), t.scale, t.scale,
      t.captureError);
  return t;
}

}  // namespace

TimeToError timeToError(const std::vector<ErrorPoint>& curve, double target) {
  std::vector<ErrorPoint> c;
  for (const ErrorPoint& p : curve)
    if (p.ms > 0 && p.error > 0 && std::isfinite(p.ms) && std::isfinite(p.error)) c.push_back(p);
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i].error > target) continue;
    if (i == 0) return {c[0].ms, "reached at the lowest setting (" + c[0].label + ")", {}};
    const ErrorPoint &a = c[i - 1], &b = c[i];
    const double t =
        (std::log(target) - std::log(a.error)) / (std::log(b.error) - std::log(a.error));
    return {std::exp(std::log(a.ms) + t * (std::log(b.ms) - std::log(a.ms))),
            "interpolated between " + a.label + " and " + b.label,
            {}};
  }
  if (c.empty()) return {{}, "no data", {}};
  const std::string best = "not reached (" + shortNumber(c.back().error) + " at " + c.back().label;
  if (c.size() < 2) return {{}, best + "; one point, no trend)", {}};
  // Least squares of log error on log time over the last points.
  const size_t first = c.size() > size_t(kTimeFitPoints) ? c.size() - kTimeFitPoints : 0;
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, longest = 0, lo = c[first].ms, hi = lo;
  for (size_t i = first; i < c.size(); ++i) {
    const double x = std::log(c[i].ms), y = std::log(c[i].error);
    n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
    lo = std::min(lo, c[i].ms), hi = std::max(hi, c[i].ms);
  }
  for (const ErrorPoint& p : c) longest = std::max(longest, p.ms);
  // Over a narrow span of times a slope is mostly the times' noise (llvmpipe's per-frame
  // overhead can hide a quality's cost): no trend to extend.
  if (!(hi >= kTimeFitSpan * lo))
    return {{},
            best + "; times over the last points within " + shortNumber(kTimeFitSpan) +
                "x of each other: no trend in time)",
            {}};
  const double var = sxx - sx * sx / n;
  const double slope = (sxy - sx * sy / n) / var;
  if (!(slope <= kTimeFitSlope))
    return {{},
            best + "; error against time not falling: log-log slope " + shortNumber(slope) + ")",
            slope};
  const ErrorPoint& last = c.back();
  const double ms = last.ms * std::pow(target / last.error, 1 / slope);
  if (!(ms <= kTimeFitReach * longest))
    return {{},
            best + "; the fit, slope " + shortNumber(slope) + ", would need " + shortNumber(ms) +
                " ms, beyond " + shortNumber(kTimeFitReach) + "x the longest measured)",
            slope};
  return {ms,
          "extrapolated from " + last.label + " along the log-log fit of the last " +
              std::to_string(c.size() - first) + " points (slope " + shortNumber(slope) + ")",
          slope};
}

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
  const PngExposure exposure = choosePngExposure(
      reference.image, std::nullopt,
      setup.probe.output.exposureSet ? std::optional<double>(setup.probe.output.exposure)
                                     : std::nullopt);
  setup.exposure = exposure.stops;
  writeToneMappedPng((dir / "reference.png").string(), reference.image, exposure.stops);
  say(log, "  reference.png and the tone-mapped metrics: exposure %s\n",
      exposure.description.c_str());

  // Differential rendering's ground truth, where a method it measures is asked for.
  std::optional<differential::Truth> truth;
  json differentialInfo = nullptr;
  if (differential::applies(setup.probe) &&
      std::any_of(methods.begin(), methods.end(), [](const MethodInfo* m) {
        return m->name == "diffrender" || m->name == "pbgi" || m->name == "vpl";
      })) {
    truth = makeDifferentialTruth(setup, reference.image, dir, log);
    report.r0RelativeL2 = truth->r0Error;
    differentialInfo = truth->info;
  }

  say(log, "bench gi: %d timed runs per setting after the set-up\n", o.runs);
  for (const MethodInfo* m : methods) {
    const Scene scene = setup.prepared(m->name);
    if (std::string why = whyNotApplicable(*m, scene); !why.empty()) {
      say(log, "%s: skipped (%s)\n", m->name.c_str(), why.c_str());
      report.skipped.push_back({m->name, "", why});
      continue;
    }
    auto q = o.qualities.find(m->name);
    const std::vector<int>& levels = q != o.qualities.end() ? q->second : m->defaultQualities;
    std::vector<MethodInfo::Variant> variants = {{"", [](GiSettings&) {}}};
    if (o.variants) variants.insert(variants.end(), m->variants.begin(), m->variants.end());
    for (const auto& variant : variants) {
      if (std::string why = whyNotApplicable(*m, scene, &variant); !why.empty()) {
        say(log, "%s (%s): skipped (%s)\n", m->name.c_str(), variant.name.c_str(), why.c_str());
        report.skipped.push_back({m->name, variant.name, why});
        continue;
      }
      for (int level : levels)
        report.rows.push_back(runConfiguration(setup, *m, variant, level, reference.image, refPath,
                                               dir, truth ? &*truth : nullptr, log));
    }
    if (truth && (m->name == "pbgi" || m->name == "vpl"))
      for (int level : levels)
        report.rows.push_back(
            runTwoSimulation(setup, *m, level, reference.image, refPath, dir, *truth, log));
  }
  writeReport(report, setup, reference.info, differentialInfo, log);
  return report;
}

}  // namespace nestlight::bench
