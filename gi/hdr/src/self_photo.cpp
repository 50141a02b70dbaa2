#include "nestlight/gi/hdr/self_photo.h"

#include <algorithm>
#include <memory>

#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi::hdr {

glm::vec3 pushedHighlights(const glm::vec3& ldr) {
  const float y = 0.2126f * ldr.r + 0.7152f * ldr.g + 0.0722f * ldr.b;
  const float t = std::clamp((y - 0.5f) / 0.5f, 0.0f, 1.0f);
  return ldr * (1.0f + 15.0f * t * t * (3.0f - 2.0f * t));
}

SelfPhotoViews selfPhotoViews(const Metadata& meta) {
  const Box3d& b = meta.bounds;
  const glm::dvec3 lo{b.min.x, b.min.y, b.min.z}, hi{b.max.x, b.max.y, b.max.z};
  const glm::dvec3 centre = (lo + hi) * 0.5;
  const double diagonal = glm::length(hi - lo);
  return {
      lookAt(centre + diagonal * glm::dvec3(1.0, 0.6, 0.5), centre, {0, 0, 1}, 40.0, 640, 480),
      lookAt(centre + diagonal * glm::dvec3(-0.3, 1.1, 0.5), centre, {0, 0, 1}, 40.0, 640, 480)};
}

namespace {
// `colour(node, i)` of every point splatted from `view`, linear.
template <typename F>
HdrImage renderLinear(OctreeReader& reader, const View& view, F colour) {
  ScanAccess scan(reader);
  SplatOptions so;
  so.colour = [&](const ScanNode& n, std::vector<uint32_t>& out) {
    out.resize(n.world.size());
    colour(n, out);
  };
  return renderViews(scan, {view}, Payload::Rgb9e5, so)[0].image();
}
}  // namespace

HdrImage renderSelfPhoto(const std::filesystem::path& octree, const View& view) {
  OctreeReader reader(octree);
  return renderLinear(reader, view, [](const ScanNode& n, std::vector<uint32_t>& out) {
    for (size_t i = 0; i < out.size(); ++i) out[i] = packRgb9e5(pushedHighlights(n.ldr[i]));
  });
}

void writeBeforeAfter(const std::filesystem::path& octree, const View& view,
                      const std::string& layer, const std::filesystem::path& stem) {
  OctreeReader reader(octree);
  std::unique_ptr<ColourLayerReader> colours;
  if (layer != "ldr")
    colours = std::make_unique<ColourLayerReader>(octree, reader.metadata(), layer);
  const HdrImage img =
      renderLinear(reader, view, [&](const ScanNode& n, std::vector<uint32_t>& out) {
        std::vector<float> rgb;
        if (colours) rgb = colours->readNode(n.key, uint32_t(n.world.size()));
        for (size_t i = 0; i < out.size(); ++i)
          out[i] = packRgb9e5(colours ? glm::vec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2])
                                      : n.ldr[i]);
      });
  writeExr(stem.string() + ".exr", img);
  for (const float e : {1.0f, 0.125f}) {
    HdrImage d = img;
    for (float& v : d.rgb) v = displayFromLinear(std::min(1.0f, v * e));
    writePng(stem.string() + (e == 1.0f ? "-e1.png" : "-e1_8.png"), d);
  }
}

}  // namespace nestlight::gi::hdr
