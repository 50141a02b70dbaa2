// The relighting half of the ground-truth protocol (see hdr_relit.h).
#include "nestlight/bench/hdr_relit.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nestlight/converters/test_scenes.h"
#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/gi/reference/path_tracer.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace gi;
using namespace gi::hdr;

namespace {

struct Box {
  glm::dvec3 lo, hi;
  const char* material;
};
// In the sunlit patch of the floor (x 0.8-2.6, y 0.4-2.6), clear of the room's block: the
// floor under and around them is clipped in the LDR scan, so their light is what expansion
// restores; the lamp above adds a highlight on the glossy one.
const Box kBoxes[] = {{{1.15, 1.0, 0.0}, {1.75, 1.6, 0.6}, "matte"},
                      {{1.95, 1.55, 0.0}, {2.35, 1.95, 0.9}, "glossy"}};

bool hitsBox(const glm::vec3& o, const glm::vec3& d, const glm::vec3& lo, const glm::vec3& hi) {
  float t0 = 0, t1 = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const float inv = 1.0f / d[a];
    float ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

}  // namespace

void writeBaselineLayers(const fs::path& octree, double clipThreshold, double landisMax) {
  OctreeReader reader(octree);
  ScanAccess scan(reader);
  const auto nodes = reader.allNodes();
  // Half floats hold 65504: a larger LANDIS-PC maximum is stored divided by a scale.
  const double landisScale = std::max(1.0, landisMax / 60000.0);
  ColourLayerWriter ldr(octree, "ldr", 1.0), landis(octree, "landis", landisScale);
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    const ScanNode n = scan.read(key, entry);
    std::vector<float> a(3 * n.ldr.size()), b(3 * n.ldr.size());
    for (size_t i = 0; i < n.ldr.size(); ++i) {
      const glm::vec3 l = landisExpand(n.ldr[i], clipThreshold, landisMax);
      for (int c = 0; c < 3; ++c) a[3 * i + size_t(c)] = n.ldr[i][c], b[3 * i + size_t(c)] = l[c];
    }
    ldr.writeNode(key, a.data(), n.ldr.size());
    landis.writeNode(key, b.data(), n.ldr.size());
  });
  const json build = {{"tool", "nestlight bench hdr"},
                      {"clip_threshold", clipThreshold},
                      {"landis_max", landisMax}};
  ldr.finish(build);
  landis.finish(build);
}

fs::path writeRelitScene(const fs::path& protocolDir, const std::string& colour,
                         const RelitOptions& o) {
  writeBoxObj(protocolDir / "box.obj");
  json meshes = json::array();
  for (const Box& b : kBoxes)
    meshes.push_back({{"path", "box.obj"},
                      {"transform",
                       {{"translate", {b.lo.x, b.lo.y, b.lo.z}},
                        {"scale", {b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z}}}},
                      {"material", b.material}});
  const json scene = {
      {"version", 1},
      {"octrees", {{{"path", "scan.octree"}, {"colour", colour}}}},
      {"materials",
       {{"matte", {{"type", "lambert"}, {"base_color", 0.7}}},
        {"glossy",
         {{"type", "ggx"}, {"base_color", 0.8}, {"roughness", 0.25}, {"metallic", 0.0}}}}},
      {"meshes", meshes},
      {"camera",
       {{"eye", {0.55, 0.35, 1.45}},
        {"target", {1.75, 1.5, 0.4}},
        {"up", {0.0, 0.0, 1.0}},
        {"fov", 50.0},
        {"width", o.width},
        {"height", o.height}}},
      {"gi", {{"method", o.method}, {"mode", "radiance_cache"}}}};
  const fs::path file = protocolDir / ("relit-" + colour + ".json");
  std::ofstream out(file);
  out << scene.dump(2) << "\n";
  if (!out) throw Error(file.string(), "", "cannot write the scene file");
  return file;
}

std::vector<uint8_t> relitObjectMask(const Scene& scene) {
  const SceneCamera& c = scene.camera;
  std::vector<uint8_t> mask(size_t(c.width) * size_t(c.height), 0);
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      glm::vec3 o, d;
      cameraRay(c, scene.origin, float(x) + 0.5f, float(y) + 0.5f, &o, &d);
      for (const Box& b : kBoxes)
        if (hitsBox(o, d, scene.local(b.lo), scene.local(b.hi)))
          mask[size_t(y) * size_t(c.width) + size_t(x)] = 1;
    }
  return mask;
}

RelitError compareRelit(const HdrImage& render, const HdrImage& truth,
                        const std::vector<uint8_t>& mask) {
  NL_CHECK(render.width == truth.width && render.height == truth.height &&
           mask.size() == truth.pixels());
  double sq = 0, sum = 0;
  RelitError e;
  for (size_t p = 0; p < mask.size(); ++p) {
    if (!mask[p]) continue;
    ++e.pixels;
    for (int c = 0; c < 3; ++c) {
      const double d = double(render.rgb[3 * p + size_t(c)]) - truth.rgb[3 * p + size_t(c)];
      sq += d * d;
      sum += truth.rgb[3 * p + size_t(c)];
    }
  }
  if (e.pixels == 0) return e;
  e.rms = std::sqrt(sq / double(3 * e.pixels));
  const double mean = sum / double(3 * e.pixels);
  e.relativeRms = mean > 0 ? e.rms / mean : 0;
  return e;
}

}  // namespace nestlight::bench
