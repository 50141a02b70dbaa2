// Maletz, Wang and Bowers, "Importance-Driven Point Projection for GPU-based Final Gathering"
// (2011), Fig. 7 and 9: micro-buffers against brute force's (nestlight/bench/bench_projection.h).
#include "nestlight/bench/bench_projection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/method.h"
#include "nestlight/gi/methods.h"
#include "nestlight/gi/projection/hemi_octahedral.h"
#include "nestlight/gi/projection/projection_method.h"
#include "nestlight/gi/scene.h"
#include "nestlight/gi/tone_map.h"
#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

struct Configuration {
  std::string name;
  json parameters;
};

struct MicroBuffer {
  int size = 0;
  std::vector<double> luminance;
  std::string covered;     // '1' where a sample covers the texel
  bool truncated = false;  // llvmpipe's loop limit stopped its splats
};

// A dumped micro-buffer, or nothing where the pixel showed no receiver (no file).
bool readMicroBuffer(const fs::path& file, MicroBuffer& mb) {
  if (!fs::exists(file)) return false;
  gi::ImageAttributes a;
  const gi::HdrImage img = gi::readHdrImage(file.string(), &a);
  mb.size = img.width;
  mb.covered = a.count("nestlight:covered") ? a.at("nestlight:covered") : "";
  mb.truncated = a.count("nestlight:truncated") && a.at("nestlight:truncated") == "true";
  if (mb.covered.size() != img.pixels())
    throw Error(
        file.string(), "",
        "no nestlight:covered mask of " + std::to_string(img.pixels()) + " texels in its header");
  mb.luminance.resize(img.pixels());
  for (size_t i = 0; i < img.pixels(); ++i) {
    const float* p = &img.rgb[3 * i];
    mb.luminance[i] = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  }
  return true;
}

// A micro-buffer to look at: 4x larger, tone-mapped at 0 EV (PNG beside the EXR).
void writePreview(const fs::path& exr) {
  const gi::HdrImage mb = gi::readHdrImage(exr.string());
  gi::HdrImage big(4 * mb.width, 4 * mb.height);
  for (int y = 0; y < big.height; ++y)
    for (int x = 0; x < big.width; ++x) big.set(x, y, mb.get(x / 4, y / 4));
  fs::path png = exr;
  gi::writeToneMappedPng(png.replace_extension(".png").string(), big, 0.0);
}

std::string folderName(const std::string& configuration) {
  std::string s = configuration;
  for (char& c : s)
    if (c == ' ') c = '_';
  return s;
}

}  // namespace

std::vector<MicroBufferComparison> runBenchProjection(const BenchProjectionOptions& o) {
  gi::Scene base = gi::loadScene(o.scene);
  base.gi.method = "projection";
  if (o.mode == "albedo") base.gi.mode = gi::RadianceMode::Albedo;
  if (o.mode == "radiance_cache") base.gi.mode = gi::RadianceMode::RadianceCache;
  if (o.width > 0) base.camera.width = o.width;
  if (o.height > 0) base.camera.height = o.height;
  if (o.points > 0) base.gi.parameters["points"] = o.points;
  const int W = base.camera.width, H = base.camera.height;
  const fs::path out = o.out.empty() ? o.scene.parent_path() / "bench-projection" : o.out;
  fs::create_directories(out);
  std::vector<std::array<int, 2>> pixels = o.pixels;
  for (const auto& p : pixels)
    if (p[0] < 0 || p[1] < 0 || p[0] >= W || p[1] >= H)
      throw Error("--pixel", std::to_string(p[0]) + "," + std::to_string(p[1]),
                  "outside the " + std::to_string(W) + "x" + std::to_string(H) + " image");

  const std::vector<Configuration> configurations = {
      {"brute", {{"sampling", "brute"}}},   {"importance", json::object()},
      {"random", {{"sampling", "random"}}}, {"splat 1", {{"splat", 1}}},
      {"splat 2", {{"splat", 2}}},          {"splat 3", {{"splat", 3}}}};
  auto ctx = gl::createHeadlessContext();
  std::printf("device  %s\nscene   %s, %dx%d, %s mode, %zu pixels\n", ctx->description().c_str(),
              o.scene.c_str(), W, H,
              base.gi.mode == gi::RadianceMode::Albedo ? "albedo" : "radiance_cache",
              pixels.size());
  // Without --pixel: five receivers spread over those a 16 x 16 grid of the image finds (a probe
  // frame dumps the grid's micro-buffers; sky, background and, in the radiance-cache mode, the
  // scan are no receivers).
  if (pixels.empty()) {
    json grid = json::array();
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i)
        grid.push_back({int((i + 0.5) * W / 16), int((j + 0.5) * H / 16)});
    gi::Scene s = base;
    s.gi.parameters["dump_pixels"] = grid;
    s.gi.parameters["dump_folder"] = (out / "probe").string();
    s.gi.parameters["grid"] = 16;
    s.gi.parameters["epsilon"] = 1e6;
    s.gi.maxBounces = std::min(s.gi.maxBounces, 2);
    fs::remove_all(out / "probe");
    gi::createMethod(s, {true, true})->render(s.camera);
    std::vector<std::array<int, 2>> found;
    for (const json& p : grid)
      if (fs::exists(out / "probe" / gi::microBufferFileName(p[0].get<int>(), p[1].get<int>())))
        found.push_back({p[0].get<int>(), p[1].get<int>()});
    fs::remove_all(out / "probe");
    const size_t n = std::min<size_t>(5, found.size());
    for (size_t k = 0; k < n; ++k) pixels.push_back(found[(2 * k + 1) * found.size() / (2 * n)]);
    std::printf("probe   %zu of 256 grid pixels show a receiver; compared:", found.size());
    for (const auto& p : pixels) std::printf(" %d,%d", p[0], p[1]);
    std::printf("\n");
  }
  json pixelList = json::array();
  for (const auto& p : pixels) pixelList.push_back({p[0], p[1]});
  json report = {{"device", ctx->description()},
                 {"scene", fs::absolute(o.scene).string()},
                 {"width", W},
                 {"height", H},
                 {"pixels", pixelList}};
  for (const Configuration& c : configurations) {
    gi::Scene s = base;
    for (const auto& [k, v] : c.parameters.items()) s.gi.parameters[k] = v;
    s.gi.parameters["dump_pixels"] = pixelList;
    // Only the listed pixels' micro-buffers are measured: the frame gathers no more than a
    // 16-pixel grid (brute force's every pixel would take minutes).
    s.gi.parameters["grid"] = 16;
    s.gi.parameters["epsilon"] = 1e6;
    // The points' radiance must not differ between configurations: further bounces, gathered
    // with each configuration's sampling, would.
    s.gi.maxBounces = std::min(s.gi.maxBounces, 2);
    s.gi.parameters["dump_folder"] = (out / folderName(c.name)).string();
    fs::remove_all(out / folderName(c.name));
    std::fflush(stdout);
    gi::MethodFrame f = gi::createMethod(s, {true, true})->render(s.camera);
    std::printf("  %-10s %7.1f ms  %s\n", c.name.c_str(), f.seconds * 1e3,
                f.attributes.count("nestlight:projection_points")
                    ? (f.attributes.at("nestlight:projection_points") + " points of S").c_str()
                    : "");
    report["configurations"][c.name] = {
        {"parameters", c.parameters}, {"seconds", f.seconds}, {"summary", f.summary}};
  }

  // Medians over the pixels: one receiver that sees a few points just above its horizon (brute
  // force covering 5% of its map) has the sampled configurations' large splats cover most of it,
  // and its relative rms of 10 would rule a mean.
  auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  };
  std::vector<MicroBufferComparison> results;
  std::vector<double> weights;
  int truncatedReferences = 0;
  for (const Configuration& c : configurations) {
    MicroBufferComparison r;
    r.configuration = c.name;
    std::vector<double> rmsOf, holesOf, spillOf, rmsEOf, irrOf;
    for (const auto& p : pixels) {
      const std::string name = gi::microBufferFileName(p[0], p[1]);
      MicroBuffer b, v;
      if (!readMicroBuffer(out / "brute" / name, b)) continue;  // no receiver there
      if (b.truncated) {  // no reference there (llvmpipe's loop limit)
        if (c.name == "brute") truncatedReferences++;
        continue;
      }
      if (!readMicroBuffer(out / folderName(c.name) / name, v) || v.size != b.size)
        throw Error((out / folderName(c.name) / name).string(), "",
                    "missing, or not the reference's size");
      writePreview(out / folderName(c.name) / name);
      // The irradiance integrand's weights (cos at the receiver times the texel's solid angle):
      // what the receiver's light is made of, where the unweighted texels count the horizon's
      // as much as the zenith's.
      if (weights.size() != b.luminance.size()) {
        const std::vector<double> omega = gi::projection::hemiOctTexelSolidAngles(b.size);
        weights.assign(omega.size(), 0.0);
        for (int t = 0; t < b.size * b.size; ++t) {
          const double u = (t % b.size + 0.5) / b.size, v = (t / b.size + 0.5) / b.size;
          const double x = 1.0 - u - v, z = u - v,
                       y = std::max(1.0 - std::abs(x) - std::abs(z), 0.0);
          weights[size_t(t)] = omega[size_t(t)] * y / std::sqrt(x * x + y * y + z * z);
        }
      }
      double sq = 0, ref = 0, sqE = 0, refE = 0, eV = 0, eB = 0;
      size_t covered = 0, holes = 0, spill = 0;
      for (size_t t = 0; t < b.luminance.size(); ++t) {
        const double d = v.luminance[t] - b.luminance[t];
        sq += d * d;
        ref += b.luminance[t] * b.luminance[t];
        sqE += weights[t] * d * d, refE += weights[t] * b.luminance[t] * b.luminance[t];
        eV += weights[t] * v.luminance[t], eB += weights[t] * b.luminance[t];
        const bool bc = b.covered[t] == '1', vc = v.covered[t] == '1';
        covered += bc;
        holes += bc && !vc;
        spill += vc && !bc;
      }
      const double n = double(b.luminance.size());
      const double rms = ref > 0 ? std::sqrt(sq / ref) : 0.0,
                   holeShare = covered ? double(holes) / double(covered) : 0.0,
                   spillShare = double(spill) / n;
      rmsOf.push_back(rms), holesOf.push_back(holeShare), spillOf.push_back(spillShare);
      const double rmsE = refE > 0 ? std::sqrt(sqE / refE) : 0.0,
                   irr = eB > 0 ? std::abs(eV - eB) / eB : 0.0;
      rmsEOf.push_back(rmsE), irrOf.push_back(irr);
      report["per_pixel"][c.name].push_back({{"pixel", {p[0], p[1]}},
                                             {"rms", rms},
                                             {"holes", holeShare},
                                             {"spill", spillShare},
                                             {"rms_irradiance", rmsE},
                                             {"irradiance_error", irr},
                                             {"reference_covered", double(covered) / n}});
      r.pixels++;
    }
    r.rms = median(rmsOf), r.holes = median(holesOf), r.spill = median(spillOf);
    r.rmsIrradiance = median(rmsEOf), r.irradianceError = median(irrOf);
    results.push_back(r);
  }

  std::string md =
      "| configuration | pixels | rms | rms, irradiance-weighted | irradiance error | holes | "
      "spill "
      "|\n|---|---|---|---|---|---|---|\n";
  char line[256];
  for (const MicroBufferComparison& r : results) {
    std::snprintf(line, sizeof line, "| %s | %d | %.4f | %.4f | %.4f | %.4f | %.4f |\n",
                  r.configuration.c_str(), r.pixels, r.rms, r.rmsIrradiance, r.irradianceError,
                  r.holes, r.spill);
    md += line;
    report["results"][r.configuration] = {{"pixels", r.pixels},
                                          {"rms", r.rms},
                                          {"rms_irradiance", r.rmsIrradiance},
                                          {"irradiance_error", r.irradianceError},
                                          {"holes", r.holes},
                                          {"spill", r.spill}};
  }
  auto find = [&](const std::string& n) -> const MicroBufferComparison& {
    for (const auto& r : results)
      if (r.configuration == n) return r;
    NL_CHECK(false);
    return results.front();
  };
  const auto &imp = find("importance"), &rnd = find("random"), &s1 = find("splat 1"),
             &s3 = find("splat 3");
  std::snprintf(line, sizeof line,
                "\nTargets (the paper's Fig. 9 and 7):\n"
                "- importance rms <= half of random's (irradiance-weighted): %.4f against %.4f: "
                "%s\n"
                "- adaptive splats, fewer holes than 1-texel splats: %.4f against %.4f: %s\n",
                imp.rmsIrradiance, 0.5 * rnd.rmsIrradiance,
                imp.rmsIrradiance <= 0.5 * rnd.rmsIrradiance ? "met" : "missed", imp.holes,
                s1.holes, imp.holes < s1.holes ? "met" : "missed");
  md += line;
  std::snprintf(line, sizeof line,
                "- adaptive splats, less spill than 3-texel splats: %.4f against %.4f: %s\n",
                imp.spill, s3.spill, imp.spill < s3.spill ? "met" : "missed");
  md += line;
  if (imp.pixels == 0 || rnd.rmsIrradiance == 0) {
    md = md.substr(0, md.find("\nTargets"));
    md += "\nTargets not measured: no pixel with light to compare.\n";
  }
  if (truncatedReferences)
    md += "\n" + std::to_string(truncatedReferences) +
          " pixel(s) left out: brute force's splats stopped at llvmpipe's loop limit there (a GPU "
          "has none; fewer points of S, --points 65536, stay within it).\n";
  if (find("brute").pixels == 0)
    md += "\nNo listed pixel shows a receiver: choose others with --pixel.\n";
  else if (rnd.rmsIrradiance == 0)
    md +=
        "\nBrute force's micro-buffers are black (no light reaches the points of S): nothing to "
        "compare.\n";
  std::printf("\n%s", md.c_str());
  std::ofstream(out / "bench_projection.md") << md;
  std::ofstream(out / "bench_projection.json") << report.dump(1) << "\n";
  std::printf("\nwritten to %s (bench_projection.md, .json, the micro-buffers)\n", out.c_str());
  return results;
}

}  // namespace nestlight::bench
