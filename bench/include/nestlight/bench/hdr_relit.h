// The relighting half of HDR expansion's ground-truth protocol (Sabbadin et al., "High Dynamic
// Range Point Clouds for Real-Time Relighting", 2019, section 6.2 and Table 2's rendering
// columns): virtual objects inserted in the protocol room (hdr_protocol.h), lit by the scan's
// colour as a radiance cache through a GI method, rendered once per colour source and compared with
// the render lit by the true colour over the objects' pixels only (the paper removes the
// background).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "nestlight/gi/hdr_image.h"
#include "nestlight/gi/scene.h"

namespace nestlight::bench {

// Writes the baselines as colour layers of a protocol octree, so that renders read them as any
// other colour source: "ldr" (the scan's colour linearised by gamma 2.2, as expansion leaves the
// points it does not touch) and "landis" (LANDIS-PC: a global inverse tone mapping of it reaching
// `landisMax`, the largest luminance the photograph shows, exposed).
void writeBaselineLayers(const std::filesystem::path& octree, double clipThreshold,
                         double landisMax);

struct RelitOptions {
  std::string method = "pbgi";  // the paper relights with its X-PBGI
  int width = 128, height = 96;
};

// Writes `protocolDir`/relit-<colour>.json: the protocol's scan.octree with colour source
// `colour` ("truth", a layer expand-hdr wrote, "ldr", "landis"), two boxes standing in the sunlit
// part of the floor (a Lambert one, albedo 0.7, and a GGX one, roughness 0.25), the camera on
// them, radiance-cache mode (the scan's colour is its light, nothing else lights). Returns the
// file's path.
std::filesystem::path writeRelitScene(const std::filesystem::path& protocolDir,
                                      const std::string& colour, const RelitOptions& options);

// 1 where the scene camera's pixel centre sees one of the inserted boxes.
std::vector<uint8_t> relitObjectMask(const gi::Scene& scene);

struct RelitError {
  double rms = 0;          // over the masked pixels and RGB channels, in the truth's units
  double relativeRms = 0;  // rms / the truth render's mean over the same pixels and channels
  uint64_t pixels = 0;
};
RelitError compareRelit(const gi::HdrImage& render, const gi::HdrImage& truth,
                        const std::vector<uint8_t>& mask);

}  // namespace nestlight::bench
