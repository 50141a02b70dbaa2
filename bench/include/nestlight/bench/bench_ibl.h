// `nestlight bench ibl`: the equal-time comparison of Kronander et al., "Real-time video based
// lighting using GPU raytracing" (2014), Fig. 3, made measurable. For generated scenes (a glossy
// sphere on a floor under a moving-sun video light probe, and under a shared HDR environment map
// turning as a probe sequence), every frame's ground truth is the reference's direct light
// (gi/reference, Embree); each estimator of the `ibl` method (MIS, BIS, SMC, and environment-map
// sampling alone as the baseline) renders the sequence at several sample counts, and the harness
// reports per frame the relative L2 error (of pixels, and of 4 x 4 block means with the ratio of
// the image means), the variance (two seeds), the flicker (the frame-to-frame change of the error
// image) and the frame time; per estimator the time to 5% and 2% error. Writes CSV, JSON and SVG
// plots.
#pragma once

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace nestlight::bench {

struct BenchIblOptions {
  std::filesystem::path out = "bench-ibl";
  // "moving-sun" (generated), "scanned" (the moving sun on scanned receivers: the object scene's
  // town in the albedo mode), "shared" (../shared/data/hdr/stage_env_latlong.exr, a film stage's
  // small bright lamps) and "outdoor" (royal_esplanade_1k.hdr, a sunny square), each turned 4
  // degrees a frame; a shared map's scene is skipped with a message without the shared data.
  std::vector<std::string> scenes = {"moving-sun", "scanned", "shared"};
  std::vector<std::string> estimators = {"mis", "bis", "smc", "env"};
  std::vector<int> samples = {4, 16, 64};  // the ibl method's quality levels (samples per pixel)
  int frames = 8;
  int size = 128;        // the error study's image side
  int timingSize = 512;  // frame times are also measured at this side (0: not)
  int timingFrames = 3;
  int referenceSpp = 4096;
  float roughness = 0.2f;  // the sphere's GGX roughness
  bool variance = true;    // a second seed per setting, for the variance
  std::filesystem::path sharedData;
  std::string device;
};

struct BenchIblReport {
  nlohmann::json json;
  std::filesystem::path dir;
};

// Throws nestlight::Error for bad options and failed renders. Progress and tables go to `log`.
BenchIblReport runBenchIbl(const BenchIblOptions& options, std::FILE* log = stdout);

}  // namespace nestlight::bench
