// Renderings of a scan for HDR expansion (Sabbadin et al., "High Dynamic Range Point Clouds for
// Real-Time Relighting", 2019, section 4.1: the scan splatted into viewports whose camera matrices
// are kept for back-projection).
//
// Splatted on the CPU, node by node straight from the octree, so that the expansion runs on a
// server without a GPU and any scan size passes through in bounded memory. Each pixel keeps the
// nearest splat as one 64-bit word, depth above payload, so that threads splat concurrently with
// an atomic minimum and no lock. The payload is 8-bit display RGB (what PatchMatch compares) or
// RGB9E5 shared-exponent linear colour (HDR renderings: the ground-truth protocol's photograph).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "nestlight/gi/hdr/views.h"
#include "nestlight/gi/hdr_image.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/rgb9e5.h"

namespace nestlight::gi::hdr {

// The octree's RGB9E5 (nestlight/octree/rgb9e5.h) on glm vectors.
inline uint32_t packRgb9e5(glm::vec3 rgb) {
  return nestlight::packRgb9e5(rgb.r, rgb.g, rgb.b);
}
inline glm::vec3 unpackRgb9e5(uint32_t v) {
  glm::vec3 c;
  nestlight::unpackRgb9e5(v, &c.x);
  return c;
}

// A decoded node in world terms.
struct ScanNode {
  NodeKey key;
  std::vector<glm::dvec3> world;  // positions
  std::vector<glm::vec3> ldr;     // linear LDR colour (stored rgb / 65535, gamma 2.2 removed)
  std::vector<glm::vec3> normal;  // empty when the scan has none
  double spacing = 0;             // the node's measured (else nominal) point spacing, world units
};

// Reads nodes as ScanNodes. Throws nestlight::Error when the scan has no rgb colour.
class ScanAccess {
 public:
  explicit ScanAccess(OctreeReader& reader);
  OctreeReader& reader() const { return *reader_; }
  ScanNode read(const NodeKey& key, const HierarchyEntry& entry) const;
  bool hasNormals() const { return normal_ >= 0; }

 private:
  OctreeReader* reader_;
  int rgb_ = -1, normal_ = -1;
};

constexpr double kGamma = 2.2;  // the paper's assumed response of the scanner's camera
inline float linearFromDisplay(float v) {
  return std::pow(std::max(v, 0.0f), float(kGamma));
}
inline float displayFromLinear(float v) {
  return std::pow(std::max(v, 0.0f), float(1.0 / kGamma));
}

enum class Payload { Display8, Rgb9e5 };

struct Rendering {
  View view;
  Payload payload = Payload::Display8;
  std::unique_ptr<std::atomic<uint64_t>[]> pixels;  // depth bits << 32 | payload; ~0: empty

  explicit Rendering(const View& v, Payload p);
  size_t size() const { return size_t(view.width) * size_t(view.height); }
  bool covered(size_t i) const { return pixels[i].load(std::memory_order_relaxed) != ~uint64_t(0); }
  float depth(size_t i) const;
  // Display values in [0, 1] (Display8) or linear colour (Rgb9e5); black where nothing landed.
  HdrImage image() const;
  std::vector<uint8_t> coverage() const;  // 1 where a point landed
};

struct SplatOptions {
  double radiusScale = 0.75;  // splat half-size in units of the node's point spacing
  double maxRadiusPixels = 8;
  // Called per node on the splatting thread: the payload of each point (packRgb9e5 or RGBA8 of
  // display values); empty: the display colour of the scan's rgb.
  std::function<void(const ScanNode&, std::vector<uint32_t>&)> colour;
  // Called per node after splatting, on the splatting thread (statistics over every point).
  std::function<void(const ScanNode&)> visit;
  std::function<void(uint64_t nodesDone, uint64_t nodesTotal)> progress;
};

// Splats every point of the scan into every view (one pass over the nodes).
std::vector<Rendering> renderViews(const ScanAccess& scan, const std::vector<View>& views,
                                   Payload payload, const SplatOptions& options = {});

// The splat half-size in pixels of a point at `depth` in `view` (as renderViews draws it).
double splatRadiusPixels(const View& view, double spacing, double depth,
                         const SplatOptions& options);

}  // namespace nestlight::gi::hdr
