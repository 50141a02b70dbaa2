// `nestlight bench gi`: speed against error of every GI method on a scene. The reference is
// path traced once to a tight error target and cached; each method then renders at several
// quality settings, timed (median of runs) and compared with it (gi/metrics). Writes CSV, JSON
// and an SVG plot of time against relative error.
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "cli.h"
#include "nestlight/gi/reference/render_scene.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/plot.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// sqrt(sum (t - r)^2 / sum r^2) over all pixels and channels: the relative L2 error the
// reference's stop rule estimates, so "1% error" means the same thing on both sides.
double relativeL2(const gi::HdrImage& t, const gi::HdrImage& r) {
  double d = 0, n = 0;
  for (size_t i = 0; i < t.rgb.size(); ++i) {
    double e = double(t.rgb[i]) - r.rgb[i];
    if (std::isfinite(e)) d += e * e, n += double(r.rgb[i]) * r.rgb[i];
  }
  return n > 0 ? std::sqrt(d / n) : (d > 0 ? INFINITY : 0);
}

std::vector<int> parseIntList(const std::string& text, const std::string& option) {
  std::vector<int> v;
  for (double x : parseNumberList(text, option)) {
    if (!(x >= 1 && x <= (1 << 24)) || x != std::floor(x))
      throw Error(option + ": '" + std::to_string(x) + "' is not a positive integer");
    v.push_back(int(x));
  }
  if (v.empty()) throw Error(option + ": give at least one value");
  return v;
}

std::string fileHash(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return std::to_string(std::hash<std::string>{}(bytes));
}

// What the reference depends on besides the scene file: its octrees (metadata and payload),
// meshes and environment map, by size and modification time, so an edited asset is noticed.
std::string assetStamp(const gi::Scene& s) {
  std::string stamp;
  auto add = [&](const fs::path& p) {
    std::error_code ec;
    auto size = fs::file_size(p, ec);
    auto time = fs::last_write_time(p, ec).time_since_epoch().count();
    stamp += p.string() + "=" + std::to_string(ec ? 0 : size) + "@" + std::to_string(ec ? 0 : time) + ";";
  };
  for (const auto& o : s.octrees) {
    add(o.path / "metadata.json");
    add(o.path / "octree.bin");
  }
  for (const auto& m : s.meshes) add(m.path);
  if (s.environment && !s.environment->path.empty()) add(s.environment->path);
  return std::to_string(std::hash<std::string>{}(stamp));
}

struct Row {
  std::string method;
  int spp = 0;
  std::vector<double> ms;
  double medianMs = 0;
  gi::ReferenceResult result;  // of the first run
  gi::ImageComparison cmp;
  double relL2 = 0;
};

// log-log interpolation of the time at which `rows` (in order of quality) reach `target`.
json timeToError(const std::vector<Row>& rows, double target) {
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].relL2 <= target) {
      if (i == 0) return {{"ms", rows[0].medianMs}, {"how", "reached at the lowest setting"}};
      const Row &a = rows[i - 1], &b = rows[i];
      double t = (std::log(target) - std::log(a.relL2)) / (std::log(b.relL2) - std::log(a.relL2));
      return {{"ms", std::exp(std::log(a.medianMs) + t * (std::log(b.medianMs) - std::log(a.medianMs)))},
              {"how", "interpolated between " + std::to_string(a.spp) + " and " + std::to_string(b.spp) + " spp"}};
    }
  }
  if (rows.empty() || !(rows.back().relL2 > 0)) return {{"ms", nullptr}, {"how", "no data"}};
  // Monte Carlo error falls as 1/sqrt(time): extrapolate from the best setting.
  const Row& b = rows.back();
  double ms = b.medianMs * std::pow(b.relL2 / target, 2);
  return {{"ms", ms}, {"how", "extrapolated as error ~ time^-1/2 from " + std::to_string(b.spp) + " spp"}};
}

}  // namespace

void addBenchGi(CLI::App& app, int& exitCode) {
  CLI::App* bench = app.get_subcommand("bench");
  auto* cmd = bench->add_subcommand(
      "gi",
      "Speed against error of the GI methods on a scene: the path-traced reference is rendered once to\n"
      "--reference-error (cached in the output folder), then each method at each quality setting is\n"
      "timed (median of --runs) and compared with it. Until the real-time GI methods land, the methods\n"
      "are `direct` (one bounce) and `reference` at low sample counts.\n"
      "Example: nestlight make-scene cornell -o cornell && nestlight bench gi cornell/scene.json");
  auto scene = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto runs = std::make_shared<int>(3);
  auto refError = std::make_shared<double>(0.004);
  auto refTime = std::make_shared<double>(1800);
  auto refSpp = std::make_shared<int>(1 << 16);
  auto spp = std::make_shared<std::string>("1,4,16,64");
  auto methods = std::make_shared<std::string>("direct,reference");
  auto width = std::make_shared<int>(0), height = std::make_shared<int>(0);
  auto force = std::make_shared<bool>(false);
  cmd->add_option("scene", *scene, "Scene file (.json)")->required();
  cmd->add_option("-o,--out", *out, "Output folder (default: bench-gi beside the scene)");
  cmd->add_option("--runs", *runs, "Timed runs per setting; the median is reported")->capture_default_str()->check(CLI::Range(1, 100));
  cmd->add_option("--reference-error", *refError, "Relative error the cached reference is rendered to")
      ->capture_default_str()->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--reference-time-limit", *refTime, "Seconds the reference may take at most")
      ->capture_default_str()->check(CLI::Range(1.0, 1e7));
  cmd->add_option("--reference-spp", *refSpp, "Samples per pixel of the reference at most")
      ->capture_default_str()->check(CLI::Range(2, 1 << 24));
  cmd->add_option("--spp", *spp, "Quality settings: samples per pixel, comma-separated")->capture_default_str();
  cmd->add_option("--methods", *methods, "Methods to measure, comma-separated (direct, reference)")->capture_default_str();
  cmd->add_option("--width", *width, "Override the scene camera's width")->check(CLI::Range(1, 16384));
  cmd->add_option("--height", *height, "Override the scene camera's height")->check(CLI::Range(1, 16384));
  cmd->add_flag("--force-reference", *force, "Render the reference again even when a cached one matches");
  cmd->callback([=, &exitCode]() {
    // Options first: a typo must not cost a reference render.
    std::vector<int> levels = parseIntList(*spp, "--spp");
    std::vector<std::string> methodList;
    {
      std::stringstream ss(*methods);
      std::string m;
      while (std::getline(ss, m, ','))
        if (m == "direct" || m == "reference") methodList.push_back(m);
        else throw Error("--methods: unknown method '" + m + "' (direct, reference)");
    }
    const fs::path sceneFile = fs::absolute(*scene);
    const fs::path dir = out->empty() ? sceneFile.parent_path() / "bench-gi" : fs::path(*out);
    fs::create_directories(dir);
    gi::SceneRenderOverrides base;
    if (*width) base.width = *width;
    if (*height) base.height = *height;
    base.quiet = true;
    base.still = true;

    // The reference, cached under a key of everything that changes it.
    gi::Scene probe = gi::loadScene(sceneFile);
    int W = *width ? *width : probe.camera.width, H = *height ? *height : probe.camera.height;
    std::string key = "model" + std::to_string(gi::kReferenceModelVersion) + ":" + fileHash(sceneFile) + ":" +
                      assetStamp(probe) + ":" + std::to_string(W) + "x" + std::to_string(H) + ":" +
                      std::to_string(*refError);
    fs::path refPath = dir / "reference.exr";
    gi::HdrImage reference;
    json refInfo;
    bool cached = false;
    if (!*force && fs::exists(refPath)) {
      gi::ImageAttributes attrs;
      gi::HdrImage img = gi::readHdrImage(refPath.string(), &attrs);
      if (attrs["nestlight:cache_key"] == key) {
        reference = std::move(img);
        cached = true;
        refInfo = {{"cached", true}, {"samples", attrs["nestlight:samples"]},
                   {"relative_error_estimate", attrs["nestlight:relative_error_estimate"]},
                   {"seconds", attrs["nestlight:seconds"]}};
      }
    }
    if (!cached) {
      std::printf("bench gi: rendering the reference to %.4g relative error (at most %.0f s, %d spp)...\n", *refError,
                  *refTime, *refSpp);
      std::fflush(stdout);
      gi::SceneRenderOverrides ov = base;
      ov.method = "reference";
      ov.targetError = *refError;
      ov.timeLimit = *refTime;
      ov.spp = *refSpp;
      ov.seed = 0x5eed;  // independent of the measured runs' seed
      ov.output = dir / "reference.exr.tmp.exr";
      gi::SceneRenderReport rep = gi::renderSceneFile(sceneFile, ov);
      reference = rep.result.image;
      // One that stopped short of the error target (time or sample limit) is kept for this run
      // but not reused: the next run tries again.
      gi::ImageAttributes attrs{{"nestlight:cache_key", rep.result.stopReason == "error target" ? key : "incomplete"},
                                {"nestlight:samples", std::to_string(rep.result.samplesPerPixel)},
                                {"nestlight:relative_error_estimate", std::to_string(rep.result.relativeError)},
                                {"nestlight:seconds", std::to_string(rep.result.seconds)},
                                {"nestlight:stop", rep.result.stopReason}};
      gi::writeExr(refPath.string(), reference, attrs);
      fs::remove(ov.output);
      refInfo = {{"cached", false}, {"samples", rep.result.samplesPerPixel},
                 {"relative_error_estimate", rep.result.relativeError}, {"seconds", rep.result.seconds},
                 {"stop", rep.result.stopReason}, {"rays_per_second", rep.result.raysPerSecond()},
                 {"samples_per_second", rep.result.samplesPerSecond()}};
      std::printf("  reference: %d spp, estimated error %.4f, %.1f s (%s)\n", rep.result.samplesPerPixel,
                  rep.result.relativeError, rep.result.seconds, rep.result.stopReason.c_str());
      if (rep.result.stopReason != "error target")
        std::printf("  warning: the reference stopped before %.4g error; errors below its own are not meaningful\n", *refError);
    }
    gi::writeToneMappedPng((dir / "reference.png").string(), reference, probe.output.exposure);

    // Each method at each setting.
    std::vector<Row> rows;
    std::printf("%-10s %6s %10s %12s %10s %10s %9s %7s %11s\n", "method", "spp", "median ms", "rays/s", "rel L2",
                "RMSE", "PSNR dB", "SSIM", "SSIM (tm)");
    for (const auto& m : methodList) {
      for (int s : levels) {
        Row row;
        row.method = m;
        row.spp = s;
        for (int r = 0; r < *runs; ++r) {
          gi::SceneRenderOverrides ov = base;
          ov.method = m;
          ov.spp = s;
          ov.targetError = 0.0;
          ov.timeLimit = 0.0;
          ov.seed = 1;
          ov.output = dir / (m + "_" + std::to_string(s) + ".exr");
          gi::SceneRenderReport rep = gi::renderSceneFile(sceneFile, ov);
          row.ms.push_back(rep.result.seconds * 1e3);
          if (r == 0) row.result = std::move(rep.result);
        }
        row.medianMs = median(row.ms);
        gi::CompareOptions co;
        co.testName = m + " " + std::to_string(s) + " spp";
        co.referenceName = refPath.string();
        co.exposureStops = probe.output.exposure;
        row.cmp = gi::compareImages(row.result.image, reference, co);
        row.relL2 = relativeL2(row.result.image, reference);
        std::printf("%-10s %6d %10.1f %12.3g %10.4f %10.4g %9.2f %7.4f %11.4f\n", m.c_str(), s, row.medianMs,
                    row.result.raysPerSecond(), row.relL2, row.cmp.linear.rmse, row.cmp.linear.psnr, row.cmp.linear.ssim,
                    row.cmp.toneMapped.ssim);
        std::fflush(stdout);
        rows.push_back(std::move(row));
      }
    }

    // Files: CSV, JSON, SVG.
    const std::string device = cpuName() + ", " + std::to_string(tbb::info::default_concurrency()) +
                               " threads (Embree 3 on the CPU)";
    std::ofstream csv(dir / "bench_gi.csv");
    csv << "method,samples_per_pixel,runs,median_ms,min_ms,max_ms,rays_per_second,samples_per_second,relative_l2,"
           "rmse,relative_mse,psnr_db,ssim,rmse_tonemapped,psnr_tonemapped_db,ssim_tonemapped,nonfinite_pixels\n";
    json jrows = json::array();
    std::vector<gi::PlotSeries> series;
    for (const auto& m : methodList) {
      gi::PlotSeries ps;
      ps.name = m;
      for (const Row& r : rows) {
        if (r.method != m) continue;
        auto [lo, hi] = std::minmax_element(r.ms.begin(), r.ms.end());
        char line[512];
        std::snprintf(line, sizeof line, "%s,%d,%zu,%.3f,%.3f,%.3f,%.6g,%.6g,%.6g,%.6g,%.6g,%.4f,%.6f,%.6g,%.4f,%.6f,%llu\n",
                      r.method.c_str(), r.spp, r.ms.size(), r.medianMs, *lo, *hi, r.result.raysPerSecond(),
                      r.result.samplesPerSecond(), r.relL2, r.cmp.linear.rmse, r.cmp.linear.relativeMse, r.cmp.linear.psnr,
                      r.cmp.linear.ssim, r.cmp.toneMapped.rmse, r.cmp.toneMapped.psnr, r.cmp.toneMapped.ssim,
                      (unsigned long long)r.cmp.test.pixels);
        csv << line;
        jrows.push_back({{"method", r.method}, {"samples_per_pixel", r.spp}, {"runs_ms", r.ms}, {"median_ms", r.medianMs},
                         {"rays_per_second", r.result.raysPerSecond()}, {"samples_per_second", r.result.samplesPerSecond()},
                         {"relative_l2", r.relL2}, {"comparison", gi::toJson(r.cmp)}});
        ps.points.push_back({r.medianMs, r.relL2, std::to_string(r.spp) + " spp"});
      }
      series.push_back(std::move(ps));
    }
    json timeTo1;
    for (const auto& m : methodList) {
      std::vector<Row> mine;
      for (const Row& r : rows)
        if (r.method == m) mine.push_back(r);
      timeTo1[m] = timeToError(mine, 0.01);
    }
    json report = {{"scene", sceneFile.string()}, {"device", device}, {"width", W}, {"height", H},
                   {"runs", *runs}, {"reference", refInfo}, {"rows", jrows}, {"time_to_1_percent", timeTo1},
                   {"error_measure", "relative L2: sqrt(sum (t - r)^2 / sum r^2) over pixels and channels"}};
    std::ofstream(dir / "bench_gi.json") << report.dump(2) << "\n";
    gi::writeSvgPlot((dir / "bench_gi.svg").string(), "GI speed against error: " + sceneFile.parent_path().filename().string(),
                     "time per frame (ms, " + device + ")", "relative L2 error against the reference", series, true, true);
    for (const auto& m : methodList)
      std::printf("time to 1%% relative error, %s: %s ms (%s)\n", m.c_str(),
                  timeTo1[m]["ms"].is_null() ? "-" : std::to_string(int64_t(timeTo1[m]["ms"].get<double>())).c_str(),
                  timeTo1[m]["how"].get<std::string>().c_str());
    std::printf("bench gi: wrote %s/bench_gi.{csv,json,svg} (device: %s)\n", dir.c_str(), device.c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
