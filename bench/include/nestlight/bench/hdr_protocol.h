// The ground-truth protocol of HDR expansion (Sabbadin et al., "High Dynamic Range Point Clouds
// for Real-Time Relighting", 2019, section 6.2), made runnable: a scan whose true HDR colour is
// known, clipped to LDR by eq. 2 (times an exposure, clamped to [0, 1], gamma 2.2, 16 bits), an
// HDR photograph rendered from the true colour, and the error of an expansion against the truth.
//
// The scene is a textured room, 4 m a side, lit by a ceiling lamp (an emitter up to 2000 times
// brighter than the walls) and a patch of sunlight on the floor: a dynamic range of 1e5, with
// about a tenth of the points clipped. True colour is a pure, smooth function of a point's
// position and normal, so it can be recomputed from the octree's stored points exactly enough
// (millimetre quantisation moves it by less than 1e-4 relative); it is also written as the
// octree's "truth" colour layer.
#pragma once

#include <cstdint>
#include <filesystem>
#include <glm/glm.hpp>
#include <limits>
#include <nlohmann/json.hpp>

#include "nestlight/gi/hdr/views.h"
#include "nestlight/gi/hdr_image.h"

namespace nestlight::bench {

struct ProtocolOptions {
  uint64_t points = 1'000'000;
  uint64_t seed = 1;
  double exposure = 0.5;  // the scan camera's exposure (eq. 2); the truth times this clips at 1
  int photoWidth = 480, photoHeight = 360;
  // Points above this height (m) are left out: a scan that lacks part of what a photograph of
  // the whole room sees (above 2.9, the ceiling and its lamp). Infinite: the whole room.
  double maxHeight = std::numeric_limits<double>::infinity();
  bool overwrite = false;
  bool quiet = true;
};

// The room's true radiance at a point on one of its surfaces (normal facing into the room).
glm::vec3 protocolRadiance(const glm::dvec3& position, const glm::vec3& normal);
// The photograph's camera: inside the room, seeing the lamp and the sunlit floor.
gi::hdr::View protocolPhotoView(int width, int height);

// Writes dir/scan.octree (LDR rgb, normals, and the "truth" colour layer: the true radiance
// times the exposure, in the LDR colour's units), dir/photo.exr (the true radiance, linear,
// rendered from the scan) and dir/protocol.json (exposure, counts). Returns protocol.json's path.
std::filesystem::path makeHdrProtocol(const std::filesystem::path& dir,
                                      const ProtocolOptions& options);

// Errors of a colour layer against the "truth" layer of a protocol octree, per point (RMS over
// channels): over every point and over the points clipped in the scan.
struct LayerError {
  double rmsAll = 0, rmsClipped = 0;
  // RMS of log2(luminance / true luminance) over the clipped points, in stops: RMS is ruled by the
  // brightest points (a lamp 2000 times the walls), stops weigh every clipped point alike.
  double stopsClipped = 0;
  uint64_t points = 0, clipped = 0;
  nlohmann::json toJson() const;
};
// `layer` "ldr" compares the scan's own colour (no expansion); "landis" a global inverse tone
// mapping of it (LANDIS-PC) with `landisMax` the largest luminance to reach.
LayerError compareWithTruth(const std::filesystem::path& octree, const std::string& layer,
                            double clipThreshold = 0.9, double landisMax = 0);

}  // namespace nestlight::bench
