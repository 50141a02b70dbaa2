// Maletz, Wang and Bowers, "Importance-Driven Point Projection for GPU-based Final Gathering"
// (2011), Fig. 11 (the adaptive sampling's images as it converges) and Fig. 8 (indirect light
// against a reference), measured against the path-traced reference
// (nestlight/bench/bench_projection.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "bench_gi_reference.h"
#include "nestlight/bench/bench_projection.h"
#include "nestlight/bench/harness.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/metrics.h"
#include "nestlight/gi/projection/projection_method.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

uint64_t attribute(const gi::MethodFrame& f, const std::string& key) {
  auto it = f.attributes.find("nestlight:" + key);
  return it == f.attributes.end() ? 0 : std::stoull(it->second);
}

// The image's gather passes' wall times (MethodContext::syncPassTiming: each pass finished before
// the next): every level's select, gather and upsample, the post filter and the compose. The
// frame's shared work (the raster G-buffer and direct light, S's light and its further bounces)
// is the same in every configuration and reported apart.
bool isLevelPass(const std::string& pass) {
  for (const char* p : {"projection_select_", "projection_gather_", "projection_upsample_",
                        "projection_filter", "projection_compose"})
    if (pass.compare(0, std::strlen(p), p) == 0) return true;
  return false;
}
double passesMs(const gi::MethodFrame& f, bool levelPasses) {
  double ms = 0;
  const std::string prefix = "nestlight:pass_wall_ms:";
  for (const auto& [k, v] : f.attributes)
    if (k.compare(0, prefix.size(), prefix) == 0 &&
        isLevelPass(k.substr(prefix.size())) == levelPasses)
      ms += std::stod(v);
  return ms;
}

// a - b per pixel and channel (the indirect light: a frame less its direct light).
gi::HdrImage difference(const gi::HdrImage& a, const gi::HdrImage& b) {
  gi::HdrImage d(a.width, a.height);
  for (size_t i = 0; i < d.rgb.size(); ++i) d.rgb[i] = a.rgb[i] - b.rgb[i];
  return d;
}

gi::HdrImage absoluteTimes(const gi::HdrImage& a, float k) {
  gi::HdrImage d = a;
  for (float& v : d.rgb) v = k * std::abs(v);
  return d;
}

}  // namespace

std::vector<LevelRow> runBenchProjectionLevels(const BenchProjectionOptions& o) {
  const gi::Scene probe = gi::loadScene(o.scene);
  const int W = o.width > 0 ? o.width : probe.camera.width,
            H = o.height > 0 ? o.height : probe.camera.height;
  gi::Scene base = reference::sceneFor(probe, "projection", o.mode, W, H);
  if (o.points > 0) base.gi.parameters["points"] = o.points;
  if (base.gi.parameters.is_object()) base.gi.parameters.erase("dump_pixels");
  if (!gi::sceneHasLight(base, base.gi.mode))
    throw Error(o.scene.string(), "lights",
                "nothing lights this scene in albedo mode (scan colours are reflectances there, "
                "and it has no lights, no environment and no emissive mesh): use --mode "
                "radiance_cache, or add a light");
  const gi::ProjectionParameters params = gi::projectionParameters(base);
  if (!params.adaptive)
    throw Error(o.scene.string(), "gi.parameters.adaptive",
                "bench projection --levels measures the adaptive sampling's levels: the scene "
                "turns it off");
  int levels = 1;
  for (int step = params.grid; step > 1; step /= 2) levels++;
  const fs::path out = o.out.empty() ? o.scene.parent_path() / "bench-projection" : o.out;
  fs::create_directories(out);
  auto ctx = gl::createHeadlessContext();
  const char* mode = base.gi.mode == gi::RadianceMode::Albedo ? "albedo" : "radiance_cache";
  std::printf("device  %s\nscene   %s, %dx%d, %s mode, %d levels (grid %d), %d runs each\n",
              ctx->description().c_str(), o.scene.c_str(), W, H, mode, levels, params.grid, o.runs);

  reference::Request r;
  r.sceneFile = o.scene;
  r.probe = probe;
  r.mode = o.mode;
  r.width = W, r.height = H;
  r.spp = o.referenceSpp;
  r.error = o.referenceError;
  r.who = "bench projection";
  const fs::path refPath = o.reference.empty() ? out / "reference.exr" : o.reference;
  const reference::Image ref = reference::loadOrRender(r, refPath, stdout);
  const gi::HdrImage refBox = gi::boxFilter(ref.image, 4);
  const double stops = gi::autoExposure(ref.image).stops;
  gi::writeToneMappedPng((out / "levels_reference.png").string(), ref.image, stops);

  // Each configuration: its method made, one untimed frame (shaders, S and its clusters), then
  // the timed runs; the last run's image is measured.
  json report = {{"device", ctx->description()},
                 {"scene", fs::absolute(o.scene).string()},
                 {"width", W},
                 {"height", H},
                 {"mode", mode},
                 {"runs", o.runs},
                 {"reference", ref.info}};
  std::vector<LevelRow> rows;
  gi::HdrImage adaptiveImage;
  for (int k = 1; k <= levels + 1; ++k) {
    const bool every = k > levels;
    gi::Scene s = base;
    LevelRow row;
    if (every) {
      s.gi.parameters["adaptive"] = false;
      row.configuration = "every pixel";
    } else {
      s.gi.parameters["levels"] = k;
      row.levels = k;
      row.configuration =
          "level " + std::to_string(k) + " (step " + std::to_string(params.grid >> (k - 1)) + ")";
    }
    std::unique_ptr<gi::Method> m = gi::createMethod(s, gi::MethodContext(true, true, true));
    gi::MethodFrame f = m->render(s.camera);
    std::vector<double> frame, passes, shared;
    for (int run = 0; run < std::max(o.runs, 1); ++run) {
      f = m->render(s.camera);
      frame.push_back(f.seconds * 1e3);
      passes.push_back(passesMs(f, true));
      shared.push_back(passesMs(f, false));
    }
    row.frameMs = median(frame), row.passesMs = median(passes), row.sharedMs = median(shared);
    row.gathered = attribute(f, "projection_receivers");
    row.receivers = attribute(f, "projection_shaded_pixels");
    row.relativeL2 = gi::relativeL2(f.image, ref.image);
    row.box4 = gi::relativeL2(gi::boxFilter(f.image, 4), refBox);
    std::printf(
        "  %-18s %6.1f%% gathered  frame %8.1f ms  levels' passes %8.1f ms  (shared %.1f "
        "ms)  rel L2 %.4f  box 4 %.4f\n",
        row.configuration.c_str(),
        row.receivers ? 100.0 * double(row.gathered) / double(row.receivers) : 0.0, row.frameMs,
        row.passesMs, row.sharedMs, row.relativeL2, row.box4);
    std::fflush(stdout);
    std::string stem = row.configuration.substr(0, row.configuration.find(" ("));
    std::replace(stem.begin(), stem.end(), ' ', '_');
    gi::writeToneMappedPng((out / ("levels_" + stem + ".png")).string(), f.image, stops);
    report["rows"].push_back({{"configuration", row.configuration},
                              {"levels", row.levels},
                              {"gathered", row.gathered},
                              {"receivers", row.receivers},
                              {"frame_ms", row.frameMs},
                              {"level_passes_ms", row.passesMs},
                              {"shared_passes_ms", row.sharedMs},
                              {"frame_ms_runs", frame},
                              {"relative_l2", row.relativeL2},
                              {"box4", row.box4},
                              {"summary", f.summary}});
    if (k == levels) adaptiveImage = f.image;
    rows.push_back(row);
  }

  // Fig. 8: the indirect light alone. Direct light is `raster`'s frame (the same G-buffer, shadow
  // maps and lights); the reference's indirect light is the reference less that.
  gi::Scene direct = reference::sceneFor(probe, "raster", o.mode, W, H);
  const gi::MethodFrame d = gi::createMethod(direct, {true, true})->render(direct.camera);
  const gi::HdrImage indirect = difference(adaptiveImage, d.image),
                     refIndirect = difference(ref.image, d.image);
  const double indirectStops = gi::autoExposure(refIndirect).stops;
  gi::writeToneMappedPng((out / "indirect_projection.png").string(), indirect, indirectStops);
  gi::writeToneMappedPng((out / "indirect_reference.png").string(), refIndirect, indirectStops);
  gi::writeToneMappedPng((out / "indirect_difference_2x.png").string(),
                         absoluteTimes(difference(indirect, refIndirect), 2.0f), indirectStops);
  const double indirectL2 = gi::relativeL2(indirect, refIndirect),
               indirectBox4 =
                   gi::relativeL2(gi::boxFilter(indirect, 4), gi::boxFilter(refIndirect, 4));
  report["indirect"] = {{"relative_l2", indirectL2}, {"box4", indirectBox4}};

  std::string md =
      "| configuration | pixels gathered | frame ms | levels' passes ms | shared passes ms | rel "
      "L2 "
      "| box 4 |\n|---|---|---|---|---|---|---|\n";
  char line[320];
  for (const LevelRow& x : rows) {
    std::snprintf(line, sizeof line, "| %s | %.1f%% (%llu) | %.1f | %.1f | %.1f | %.4f | %.4f |\n",
                  x.configuration.c_str(),
                  x.receivers ? 100.0 * double(x.gathered) / double(x.receivers) : 0.0,
                  (unsigned long long)x.gathered, x.frameMs, x.passesMs, x.sharedMs, x.relativeL2,
                  x.box4);
    md += line;
  }
  // Fig. 11's question: how soon the refining image is as good as gathering every pixel. The
  // first level within 10% of every pixel's box-4 error, its pixels and time against every
  // pixel's; and the same for the last level (the converged adaptive image).
  const LevelRow& every = rows.back();
  auto shareOf = [&](const LevelRow& x) {
    return every.gathered ? double(x.gathered) / double(every.gathered) : 0.0;
  };
  auto timeOf = [&](const LevelRow& x) {
    return every.passesMs > 0 ? x.passesMs / every.passesMs : 0.0;
  };
  const LevelRow* first = nullptr;
  for (int k = 0; k < levels && !first; ++k)
    if (rows[size_t(k)].box4 <= 1.1 * every.box4) first = &rows[size_t(k)];
  const LevelRow& adaptive = rows[size_t(levels) - 1];
  const bool met = first && shareOf(*first) <= 0.35 && timeOf(*first) <= 1.0 / 3.0;
  if (first)
    std::snprintf(line, sizeof line,
                  "\nTarget (Fig. 11): within 10%% of every pixel's box-4 error (%.4f) at <= 35%% "
                  "of its pixels and <= 1/3 of its levels' time: %s at %s (box 4 %.4f, %.1f%% of "
                  "the pixels, %.2f of the time)\n",
                  every.box4, met ? "met" : "missed", first->configuration.c_str(), first->box4,
                  100.0 * shareOf(*first), timeOf(*first));
  else
    std::snprintf(line, sizeof line,
                  "\nTarget (Fig. 11): within 10%% of every pixel's box-4 error (%.4f): missed, no "
                  "level reaches it (the last: %.4f)\n",
                  every.box4, adaptive.box4);
  md += line;
  std::snprintf(line, sizeof line,
                "The converged adaptive image (%s): box 4 %.4f (%.3f of every pixel's), %.1f%% of "
                "the pixels, %.2f of the time\n",
                adaptive.configuration.c_str(), adaptive.box4,
                every.box4 > 0 ? adaptive.box4 / every.box4 : 0.0, 100.0 * shareOf(adaptive),
                timeOf(adaptive));
  md += line;
  std::snprintf(line, sizeof line,
                "\nFig. 8, indirect light alone (the frame less raster's direct light) against the "
                "reference's: rel L2 %.4f, box 4 %.4f (indirect_*.png, the difference at 2x)\n",
                indirectL2, indirectBox4);
  md += line;
  report["target"] = {{"first_within_10_percent", first ? first->configuration : ""},
                      {"pixel_share", first ? shareOf(*first) : 0.0},
                      {"time_ratio", first ? timeOf(*first) : 0.0},
                      {"met", met},
                      {"converged_box4_ratio", every.box4 > 0 ? adaptive.box4 / every.box4 : 0.0},
                      {"converged_pixel_share", shareOf(adaptive)},
                      {"converged_time_ratio", timeOf(adaptive)}};
  std::printf("\n%s", md.c_str());
  std::ofstream(out / "bench_projection_levels.md") << md;
  std::ofstream(out / "bench_projection_levels.json") << report.dump(1) << "\n";
  std::printf("\nwritten to %s (bench_projection_levels.md, .json, levels_*.png, indirect_*.png)\n",
              out.c_str());
  return rows;
}

}  // namespace nestlight::bench
