#include "nestlight/gi/hdr/renderings.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>

#include "nestlight/octree/error.h"
#include "nestlight/octree/spacing.h"

namespace nestlight::gi::hdr {

namespace {
constexpr uint64_t kEmpty = ~uint64_t(0);

uint32_t floatBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
}  // namespace

// ---------------------------------------------------------------------------------------------

ScanAccess::ScanAccess(OctreeReader& reader) : reader_(&reader) {
  const auto& layout = reader.metadata().layout;
  rgb_ = layout.find(attr::kRgb);
  normal_ = layout.find(attr::kNormal);
  if (rgb_ < 0 || layout[size_t(rgb_)].type != ScalarType::U16 ||
      layout[size_t(rgb_)].components != 3)
    throw Error(reader.dir().string(), "", "the scan has no rgb colour (uint16 x3) to expand");
  if (normal_ >= 0 &&
      (layout[size_t(normal_)].type != ScalarType::F32 || layout[size_t(normal_)].components != 3))
    normal_ = -1;
}

ScanNode ScanAccess::read(const NodeKey& key, const HierarchyEntry& entry) const {
  const Metadata& m = reader_->metadata();
  ScanNode n;
  n.key = key;
  const double measured = measuredSpacing(m, key.level, entry);
  n.spacing = measured > 0 ? measured : m.levelSpacing(key.level);
  const PointBuffer pts = reader_->readNode(key);
  const size_t count = pts.size();
  n.world.resize(count);
  n.ldr.resize(count);
  if (normal_ >= 0) n.normal.resize(count);
  const size_t rgbOff = m.layout.offset(size_t(rgb_));
  const size_t nOff = normal_ >= 0 ? m.layout.offset(size_t(normal_)) : 0;
  for (size_t i = 0; i < count; ++i) {
    for (int a = 0; a < 3; ++a) n.world[i][a] = m.world(a, double(pts.pos[3 * i + size_t(a)]));
    const uint8_t* at = pts.attrsOf(i);
    uint16_t c[3];
    std::memcpy(c, at + rgbOff, 6);
    for (int a = 0; a < 3; ++a) n.ldr[i][a] = linearFromDisplay(float(c[a]) / 65535.0f);
    if (normal_ >= 0) std::memcpy(&n.normal[i], at + nOff, 12);
  }
  return n;
}

// ---------------------------------------------------------------------------------------------

Rendering::Rendering(const View& v, Payload p)
    : view(v), payload(p), pixels(new std::atomic<uint64_t>[size()]) {
  for (size_t i = 0; i < size(); ++i) pixels[i].store(kEmpty, std::memory_order_relaxed);
}

float Rendering::depth(size_t i) const {
  const uint64_t v = pixels[i].load(std::memory_order_relaxed);
  if (v == kEmpty) return INFINITY;
  const uint32_t bits = uint32_t(v >> 32);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

HdrImage Rendering::image() const {
  HdrImage img(view.width, view.height);
  for (size_t i = 0; i < size(); ++i) {
    const uint64_t v = pixels[i].load(std::memory_order_relaxed);
    if (v == kEmpty) continue;
    const uint32_t p = uint32_t(v);
    glm::vec3 c =
        payload == Payload::Rgb9e5
            ? unpackRgb9e5(p)
            : glm::vec3(float(p & 255), float(p >> 8 & 255), float(p >> 16 & 255)) / 255.0f;
    img.rgb[3 * i] = c.r, img.rgb[3 * i + 1] = c.g, img.rgb[3 * i + 2] = c.b;
  }
  return img;
}

std::vector<uint8_t> Rendering::coverage() const {
  std::vector<uint8_t> out(size());
  for (size_t i = 0; i < size(); ++i) out[i] = covered(i) ? 1 : 0;
  return out;
}

double splatRadiusPixels(const View& view, double spacing, double depth,
                         const SplatOptions& options) {
  return std::clamp(options.radiusScale * spacing * view.focalPixels() / depth, 0.5,
                    options.maxRadiusPixels);
}

namespace {

// True when the node's cube may be seen by the view (conservative: the cube's corners are all
// outside one side of the frustum, or all behind the camera, otherwise drawn).
bool cubeMayBeVisible(const View& v, const Box3d& b) {
  const glm::dvec3 r = v.right();
  const double tx = 0.5 * v.width / v.focalPixels(), ty = 0.5 * v.height / v.focalPixels();
  int behind = 0, left = 0, rightOut = 0, below = 0, above = 0;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p{c & 1 ? b.max.x : b.min.x, c & 2 ? b.max.y : b.min.y,
                       c & 4 ? b.max.z : b.min.z};
    const glm::dvec3 rel = p - v.position;
    const double d = glm::dot(rel, v.forward), x = glm::dot(rel, r), y = glm::dot(rel, v.up);
    behind += d <= 0;
    left += x < -tx * d;
    rightOut += x > tx * d;
    below += y < -ty * d;
    above += y > ty * d;
  }
  return behind < 8 && left < 8 && rightOut < 8 && below < 8 && above < 8;
}

void atomicMin(std::atomic<uint64_t>& a, uint64_t v) {
  uint64_t cur = a.load(std::memory_order_relaxed);
  while (v < cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}

}  // namespace

std::vector<Rendering> renderViews(const ScanAccess& scan, const std::vector<View>& views,
                                   Payload payload, const SplatOptions& options) {
  std::vector<Rendering> out;
  out.reserve(views.size());
  for (const auto& v : views) out.emplace_back(v, payload);
  const Metadata& m = scan.reader().metadata();
  const auto nodes = scan.reader().allNodes();
  std::atomic<uint64_t> done{0};
  std::mutex progressMutex;
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints > 0) {
      const Box3d box = m.nodeBounds(key.level, key.x, key.y, key.z);
      std::vector<size_t> seen;
      for (size_t vi = 0; vi < views.size(); ++vi)
        if (cubeMayBeVisible(views[vi], box)) seen.push_back(vi);
      if (!seen.empty() || options.visit) {
        const ScanNode node = scan.read(key, entry);
        std::vector<uint32_t> colours;
        if (options.colour) {
          options.colour(node, colours);
          NL_CHECK(colours.size() == node.world.size());
        } else {
          colours.resize(node.world.size());
          for (size_t i = 0; i < colours.size(); ++i) {
            uint32_t p = 0;
            for (int c = 0; c < 3; ++c)
              p |= uint32_t(std::lround(displayFromLinear(node.ldr[i][c]) * 255.0f)) << (8 * c);
            colours[i] = p;
          }
        }
        for (size_t vi : seen) {
          const View& v = views[vi];
          Rendering& target = out[vi];
          for (size_t i = 0; i < node.world.size(); ++i) {
            glm::dvec2 px;
            double d;
            if (!v.project(node.world[i], px, d)) continue;
            const double rad = splatRadiusPixels(v, node.spacing, d, options);
            const int x0 = std::max(0, int(std::floor(px.x - rad))),
                      x1 = std::min(v.width - 1, int(std::floor(px.x + rad)));
            const int y0 = std::max(0, int(std::floor(px.y - rad))),
                      y1 = std::min(v.height - 1, int(std::floor(px.y + rad)));
            if (x0 > x1 || y0 > y1) continue;
            const uint64_t word = uint64_t(floatBits(float(d))) << 32 | colours[i];
            for (int y = y0; y <= y1; ++y)
              for (int x = x0; x <= x1; ++x)
                atomicMin(target.pixels[size_t(y) * size_t(v.width) + size_t(x)], word);
          }
        }
        if (options.visit) options.visit(node);
      }
    }
    const uint64_t d = ++done;
    if (options.progress && (d % 64 == 0 || d == nodes.size())) {
      std::lock_guard<std::mutex> lock(progressMutex);
      options.progress(d, nodes.size());
    }
  });
  return out;
}

}  // namespace nestlight::gi::hdr
