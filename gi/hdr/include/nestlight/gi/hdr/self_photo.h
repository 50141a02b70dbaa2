// A stand-in HDR photograph for a real scan that came without one: the scan's own colour,
// linear, rendered from a view with its highlights pushed beyond 1, which is what an HDR camera
// would record of a scene whose scanner clipped. `nestlight bench hdr --scan` expands a scan with
// it and renders the scan before and after (the lion in docs/HDR.md).
#pragma once

#include <filesystem>
#include <glm/glm.hpp>
#include <string>

#include "nestlight/gi/hdr/views.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/octree/metadata.h"

namespace nestlight::gi::hdr {

// Luminance above 0.5 raised smoothly (smoothstep), up to 16 times at 1.
glm::vec3 pushedHighlights(const glm::vec3& ldr);

// The photograph's camera (one side of the scan's bounds) and another 60 degrees round for the
// images before and after, both 640 x 480, 40 degrees.
struct SelfPhotoViews {
  View photo, image;
};
SelfPhotoViews selfPhotoViews(const Metadata& meta);

// The scan at `octree` rendered from `view` with its colour's highlights pushed.
HdrImage renderSelfPhoto(const std::filesystem::path& octree, const View& view);

// Renders colour layer `layer` ("ldr": the scan's own colour) from `view` and writes
// `stem`.exr and PNGs tone-mapped at exposures 1 and 1/8 (`stem`-e1.png, `stem`-e1_8.png: values
// beyond 1 keep their shape in the second).
void writeBeforeAfter(const std::filesystem::path& octree, const View& view,
                      const std::string& layer, const std::filesystem::path& stem);

}  // namespace nestlight::gi::hdr
