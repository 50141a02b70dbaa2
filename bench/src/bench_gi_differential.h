// `bench gi`'s ground truth of differential rendering (Rohmer, Jendersie and Grosch, "Natural
// Environment Illumination", IEEE TVCG 2017): for a scene with inserted meshes and a captured
// radiance layer (gi.parameters.capture), R1 is the usual reference and R0 the reference without
// the inserted meshes; what a differential method adds to the capture should be R1 - R0 on the
// scan, and its inserted meshes should look as in R1. Private to bench/src (bench gi, bench
// diffrender).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"

namespace nestlight::bench::differential {

// What the rows are measured against, made once a bench.
struct Truth {
  gi::HdrImage r1;       // the reference
  gi::HdrImage r0;       // the reference without the inserted meshes
  gi::HdrImage change;   // R1 - R0
  gi::HdrImage capture;  // the capture layer as the frame shows it (radiance-cache raster)
  gi::HdrImage albedo;   // the scan's albedo per pixel as the reference reads it (capped at 1)
  gi::HdrImage mask;     // diffrender's mask: 1 scan pixel, 2 inserted mesh, 0 else
  int scale = 1;         // diffrender's delta_scale, from the size of its dL image
  double r0Error = 0, r0ObjectError = 0, r0ChangeError = 1;
  // The capture against R0 on scan pixels: the baked layer's noise and its splats' difference
  // from the reference's discs, which no differential method adds to the capture can remove.
  double captureError = 0;
  nlohmann::json info;
};

// The scene has inserted meshes and names a capture layer: R0, the two-simulation baselines and
// diffrender's extra metrics apply.
bool applies(const gi::Scene& scene);

// The scene as it was captured: the meshes marked inserted dropped.
gi::Scene withoutInserted(gi::Scene scene);

// The mask, capture and albedo images of `scene` (the bench's prepared scene, any method),
// rendered once by diffrender (its AOVs, at 1 sample, into aovDir) and the raster frame; r0 and
// change from the two references. Throws nestlight::Error where a render fails.
Truth makeTruth(const gi::Scene& scene, const gi::HdrImage& r1, gi::HdrImage r0,
                const std::filesystem::path& aovDir);

struct Metrics {
  double deltaL2 = 0;           // dL on whole scan blocks against R1 - R0's block means
  double objectL2 = 0;          // the composite on inserted-mesh pixels against R1
  std::optional<double> rhoL2;  // the material estimate against the albedo (diffrender only)
  size_t scanBlocks = 0, objectPixels = 0;
};

// `delta` at the image's size or at 1 / truth.scale of it (diffrender's AOV); it is box-averaged
// to 1 / scale and compared on the blocks whose every pixel is a scan pixel, where R1 - R0 is
// averaged the same way. `rho` (optional) likewise against the albedo.
Metrics measure(const gi::HdrImage& composite, const gi::HdrImage& delta, const gi::HdrImage* rho,
                const Truth& truth);

// Two-simulation differential rendering: the capture plus (with - without) on scan pixels, `with`
// elsewhere (the inserted meshes, the background). `delta` receives with - without.
gi::HdrImage twoSimulation(const gi::HdrImage& with, const gi::HdrImage& without,
                           const Truth& truth, gi::HdrImage& delta);

// Sets `key` of the scene's gi.parameters (an object made where it is not one).
void setGiParameter(gi::Scene& scene, const std::string& key, const nlohmann::json& value);

}  // namespace nestlight::bench::differential
