// `nestlight bench projection`: the micro-buffer figures of Maletz, Wang and Bowers,
// "Importance-Driven Point Projection for GPU-based Final Gathering" (2011), Fig. 7 and 9, made
// measurable. At a few pixels of a scene the projection method writes its micro-buffers
// (gi.parameters.dump_pixels) for brute force (every point of S, its own area: the reference
// micro-buffer), importance sampling (the paper), random sampling with as many points, and
// importance sampling with fixed splats of 1, 2 and 3 texels instead of the adaptive ones (eq. 3).
// Each is compared texel by texel with brute force's:
//   rms    the texels' luminance, relative: sqrt(sum of squared differences over the sum of brute
//          force's squares) (over its mean, a dark micro-buffer with one bright texel ruled);
//   rms, irradiance-weighted   the same with each texel weighted by its share of the receiver's
//          irradiance (cos at the receiver times the texel's solid angle): the paper's
//          importance puts samples where the irradiance comes from, not on the horizon;
//   irradiance error   |E - E_brute| / E_brute of the micro-buffer's irradiance;
//   holes  texels brute force covers that the configuration leaves empty (its share of them);
//   spill  texels the configuration covers that brute force leaves empty (its share of all):
//          splats beyond the surfaces' outlines.
// Medians over the pixels. The paper's claims, as targets: importance's irradiance-weighted rms at
// most half of random's (Fig. 9); adaptive
// splats leave fewer holes than 1-texel ones and spill less than 3-texel ones (Fig. 7).
// Writes bench_projection.md (the table as printed) and bench_projection.json, and keeps the
// micro-buffers (OUT/<configuration>/projection_X_Y.exr, a PNG of each beside it).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace nestlight::bench {

struct BenchProjectionOptions {
  std::filesystem::path scene;
  std::filesystem::path out;  // empty: bench-projection beside the scene
  // Image pixels (x, y; top row 0); empty: five receivers spread over those a 16 x 16 grid of
  // the image finds.
  std::vector<std::array<int, 2>> pixels;
  std::string mode;           // empty: the scene's; radiance_cache or albedo
  int width = 0, height = 0;  // 0: the scene camera's
  int points = 0;             // |S| (gi.parameters.points); 0: the scene's or the default
  // runBenchProjectionLevels: frames timed per configuration (the median reported), and the
  // path-traced reference (cached at `reference`, default OUT/reference.exr).
  int runs = 3;
  int referenceSpp = 1024;
  double referenceError = 0.01;
  std::filesystem::path reference;
};

struct MicroBufferComparison {
  std::string configuration;
  int pixels = 0;  // receivers compared (a pixel showing no receiver is skipped)
  // Medians over the pixels (each pixel's in the JSON).
  double rms = 0, rmsIrradiance = 0, irradianceError = 0, holes = 0, spill = 0;
};

// Runs the configurations and returns their comparisons with brute force, brute force first.
std::vector<MicroBufferComparison> runBenchProjection(const BenchProjectionOptions& o);

}  // namespace nestlight::bench

namespace nestlight::bench {

// The paper's Fig. 11 and 8 made measurable (`bench projection --levels`): the image after each
// level of the adaptive sampling (gi.parameters.levels 1, 2, ...: what the progressive view shows
// as each level completes) and with every pixel gathered (adaptive false), each against the
// path-traced reference: the share of receiver pixels gathered, the frame's time and the levels'
// passes' (wall times, each pass finished before the next), relative L2 and box 4 (of
// 4 x 4 block means). Target (the issue's): the refining image within 10% of every pixel's box-4
// error at <= 35% of its pixels and <= 1/3 of its levels' time (the first level that gets there
// is named; the converged adaptive image's figures follow). Fig. 8: the indirect light alone
// (the frame less `raster`'s direct light) against the reference's (the same difference), as
// PNGs with their difference at 2x. Writes bench_projection_levels.md and .json.
struct LevelRow {
  std::string configuration;  // "level 1 (step 4)", ..., "every pixel"
  int levels = 0;             // 0: every pixel
  uint64_t gathered = 0, receivers = 0;
  // Medians over the runs: the frame, the levels' passes (select, gather, upsample, filter,
  // compose) and the passes every configuration shares (G-buffer, direct light, S and its light).
  double frameMs = 0, passesMs = 0, sharedMs = 0;
  double relativeL2 = 0, box4 = 0;
};
std::vector<LevelRow> runBenchProjectionLevels(const BenchProjectionOptions& o);

}  // namespace nestlight::bench
