// `nestlight bench hdr`: HDR expansion on the ground-truth protocol (Sabbadin et al. 2019,
// section 6.2): stage timings against point count (their Table 1), the cloud colour's error
// against the truth beside the baselines (their Table 2's point-cloud column), for both modes, and
// the error of relit renders of inserted objects against the render lit by the truth (Table 2's
// rendering columns).
// Each expansion runs as a child `nestlight expand-hdr` so that its peak memory is its own.
#include "nestlight/bench/bench_hdr.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <thread>

#include "nestlight/bench/harness.h"
#include "nestlight/bench/hdr_protocol.h"
#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/gi/hdr/self_photo.h"
#include "nestlight/gi/methods.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;

void runBenchHdrScan(const BenchHdrOptions& o) {
  const fs::path work = o.work;
  fs::create_directories(work);
  const fs::path copy = work / "scan.octree";
  fs::remove_all(copy);
  fs::copy(o.scanDemo, copy, fs::copy_options::recursive);
  const gi::hdr::SelfPhotoViews views = gi::hdr::selfPhotoViews(OctreeReader(copy).metadata());
  const gi::hdr::View& imageView = views.image;
  gi::writeExr((work / "photo.exr").string(), gi::hdr::renderSelfPhoto(copy, views.photo));
  const std::string text = runSelf(
      {"expand-hdr", copy.string(), "--photo", (work / "photo.exr").string(), "--auto-views",
       std::to_string(o.autoViews), "--face-size", std::to_string(o.faceSize), "--threshold",
       std::to_string(o.threshold), "--json", "-q",
       // The photograph pushes the scan's own highlights beyond 1, a tone change by design,
       // which the exposure checks refuse (highlight slope): the demo shows the expansion
       // anyway, with the checks' warnings in its report.
       "--force"},
      work / "expand.log");
  const json report = json::parse(text);
  gi::hdr::writeBeforeAfter(copy, imageView, "ldr", work / "before");
  gi::hdr::writeBeforeAfter(copy, imageView, "hdr", work / "after");
  std::printf(
      "%s: %llu points, %llu over-exposed (LDR luminance > %g): %llu expanded, %llu in-filled; "
      "exposure "
      "2^%.3f; largest value %.3g; %.2f s, peak %s\n",
      o.scanDemo.c_str(), (unsigned long long)report["points"].get<uint64_t>(),
      (unsigned long long)report["overexposed_points"].get<uint64_t>(), o.threshold,
      (unsigned long long)report["expanded_points"].get<uint64_t>(),
      (unsigned long long)report["infilled_points"].get<uint64_t>(),
      report["log2_exposure"].get<double>(), report["max_value"].get<double>(),
      report["seconds"]["total"].get<double>(),
      humanBytes(report["peak_rss_bytes"].get<double>()).c_str());
  std::printf(
      "images: %s/before-e1.png, before-e1_8.png, after-e1.png, after-e1_8.png (and .exr)\n",
      o.work.c_str());
  std::ofstream(o.out) << report.dump(2) << "\n";
}

namespace {

// One protocol size: its scene (made once), the expansions in each mode, the error of every
// layer judged against the truth, and the relit renders.
json benchSize(const BenchHdrOptions& o, uint64_t points,
               const std::vector<std::string>& modeList) {
  const fs::path dir = fs::path(o.work) / ("hdr_protocol_" + std::to_string(points));
  if (!fs::exists(dir / "protocol.json")) {
    ProtocolOptions po;
    po.points = points;
    po.overwrite = true;
    po.quiet = true;
    std::printf("making the protocol scene of %s points in %s\n",
                humanCount(double(points)).c_str(), dir.c_str());
    makeHdrProtocol(dir, po);
  }
  const fs::path octree = dir / "scan.octree";
  json size = {{"points", points}, {"methods", json::object()}};
  const gi::HdrImage photo = gi::readHdrImage((dir / "photo.exr").string());
  double photoMax = 0;
  for (size_t i = 0; i < photo.pixels(); ++i)
    photoMax =
        std::max(photoMax, double(0.2126f * photo.rgb[3 * i] + 0.7152f * photo.rgb[3 * i + 1] +
                                  0.0722f * photo.rgb[3 * i + 2]));
  // Without an expansion run here, the exposure the protocol clipped with (the search finds
  // it within a quarter stop).
  double log2Exposure =
      std::log2(json::parse(std::ifstream(dir / "protocol.json")).value("exposure", 1.0));
  for (const auto& mode : modeList) {
    const std::string layer = mode == "rgb" ? "pmatch_rgb" : "pmatch_lum";
    std::map<std::string, std::vector<double>> stages;
    double peak = 0;
    json last;
    for (int r = 0; r < o.runs; ++r) {
      std::vector<std::string> args = {"expand-hdr",   octree.string(),
                                       "--photo",      (dir / "photo.exr").string(),
                                       "--mode",       mode,
                                       "--auto-views", std::to_string(o.autoViews),
                                       "--face-size",  std::to_string(o.faceSize),
                                       "--layer",      layer,
                                       "--json",       "-q"};
      if (!o.unregistered) {
        // The protocol's photograph is registered: its camera is in protocol.json.
        const json p = json::parse(std::ifstream(dir / "protocol.json"));
        std::ofstream(dir / "photo-view.json")
            << json{{"views", json::array({p.at("photo_view")})}}.dump(2);
        args.insert(args.end(), {"--photo-view", (dir / "photo-view.json").string()});
      }
      const std::string text = runSelf(args, dir / ("expand-" + layer + ".log"));
      last = json::parse(text);
      for (auto& [k, v] : last["seconds"].items()) stages[k].push_back(v.get<double>());
      peak = std::max(peak, last["peak_rss_bytes"].get<double>());
    }
    log2Exposure = last["log2_exposure"].get<double>();
    const LayerError err = compareWithTruth(octree, layer);
    json m = {{"seconds_median", json::object()},
              {"peak_rss_bytes", peak},
              {"error", err.toJson()},
              {"report", last}};
    for (auto& [k, v] : stages) m["seconds_median"][k] = median(v);
    const double total = m["seconds_median"].value("total", 0.0);
    std::printf(
        "%-8s %-10s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f  %9.2f %9s %8.3f %9.3f\n",
        humanCount(double(points)).c_str(),
        ("PMATCH" + std::string(mode == "rgb" ? "RGB" : "LUM")).c_str(),
        m["seconds_median"].value("render", 0.0), m["seconds_median"].value("patchmatch", 0.0),
        m["seconds_median"].value("back_projection", 0.0), m["seconds_median"].value("infill", 0.0),
        m["seconds_median"].value("write_layer", 0.0), total, total / (double(points) / 1e6),
        humanBytes(peak).c_str(), err.rmsClipped, err.stopsClipped);
    size["methods"][mode == "rgb" ? "PMATCHRGB" : "PMATCHLUM"] = m;
  }
  std::vector<std::pair<std::string, std::string>> judged;  // layer, name in the table
  for (const auto& mode : modeList)
    judged.emplace_back(mode == "rgb" ? "pmatch_rgb" : "pmatch_lum",
                        mode == "rgb" ? "PMATCHRGB" : "PMATCHLUM");
  for (size_t at = 0; !o.layers.empty() && at <= o.layers.size();) {
    const size_t comma = std::min(o.layers.find(',', at), o.layers.size());
    const std::string layer = o.layers.substr(at, comma - at);
    at = comma + 1;
    const LayerError err = compareWithTruth(octree, layer);
    std::printf("%-8s %-10s %8s %8s %8s %8s %8s %8s  %9s %9s %8.3f %9.3f\n",
                humanCount(double(points)).c_str(), layer.c_str(), "", "", "", "", "", "", "", "",
                err.rmsClipped, err.stopsClipped);
    size["methods"][layer] = {{"error", err.toJson()}};
    judged.emplace_back(layer, layer);
  }
  for (const std::string base : {"ldr", "landis"}) {
    const LayerError err = compareWithTruth(octree, base, 0.9, std::exp2(log2Exposure) * photoMax);
    std::printf("%-8s %-10s %8s %8s %8s %8s %8s %8s  %9s %9s %8.3f %9.3f\n",
                humanCount(double(points)).c_str(), base == "ldr" ? "LDR" : "LANDIS-PC", "", "", "",
                "", "", "", "", "", err.rmsClipped, err.stopsClipped);
    size["methods"][base == "ldr" ? "LDR" : "LANDISPC"] = {{"error", err.toJson()}};
  }
  if (o.relit.method != "none") {
    writeBaselineLayers(octree, 0.9, std::exp2(log2Exposure) * photoMax);
    auto render = [&](const std::string& colour, std::vector<uint8_t>* mask) {
      const gi::Scene scene = gi::loadScene(writeRelitScene(dir, colour, o.relit));
      if (mask) *mask = relitObjectMask(scene);
      gi::MethodFrame f = gi::createMethod(scene, {true, false})->render(scene.camera);
      gi::writeExr((dir / ("relit-" + colour + ".exr")).string(), f.image, f.attributes);
      return f;
    };
    std::vector<uint8_t> mask;
    const gi::MethodFrame truth = render("truth", &mask);
    judged.emplace_back("ldr", "LDR");
    judged.emplace_back("landis", "LANDISPC");
    std::printf(
        "relit renders (%s, %dx%d, %.2f s a frame), %llu object pixels, against the truth's:",
        o.relit.method.c_str(), o.relit.width, o.relit.height, truth.seconds,
        (unsigned long long)std::count(mask.begin(), mask.end(), uint8_t(1)));
    for (const auto& [layer, name] : judged) {
      const RelitError e = compareRelit(render(layer, nullptr).image, truth.image, mask);
      std::printf("  %s RMS %.4f (%.1f%%)", name.c_str(), e.rms, 100 * e.relativeRms);
      size["methods"][name]["relit"] = {{"rms", e.rms},
                                        {"relative_rms", e.relativeRms},
                                        {"pixels", e.pixels},
                                        {"method", o.relit.method}};
    }
    std::printf("\n");
  }
  return size;
}

}  // namespace

void runBenchHdr(const BenchHdrOptions& o) {
  json results = {{"device", cpuName()},     {"threads", std::thread::hardware_concurrency()},
                  {"runs", o.runs},          {"auto_views", o.autoViews},
                  {"face_size", o.faceSize}, {"sizes", json::array()}};
  std::vector<std::string> modeList;
  for (const auto& m : {"rgb", "luminance"})
    if (o.modes == "both" || o.modes.find(m) != std::string::npos) modeList.push_back(m);
  std::printf("%-8s %-10s %8s %8s %8s %8s %8s %8s  %9s %9s %8s %9s\n", "points", "method", "render",
              "match", "project", "infill", "layer", "total", "s/Mpts", "peak", "RMSclip",
              "stopsclip");
  for (const uint64_t points : o.sizes) {
    results["sizes"].push_back(benchSize(o, points, modeList));
    std::fflush(stdout);
  }
  std::ofstream(o.out) << results.dump(2) << "\n";
  std::printf("results written to %s\n", o.out.c_str());
}

}  // namespace nestlight::bench
