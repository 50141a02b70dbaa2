#include "nestlight/gi/pbgi/bsh_layer.h"

#include <chrono>
#include <cstring>

#include "nestlight/gi/srgb.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi::pbgi {

BshLayer::BshLayer(const Metadata& meta, BshOptions options) : meta_(meta), options_(options) {
  rgb_ = meta.layout.find(attr::kRgb);
  normal_ = meta.layout.find(attr::kNormal);
}

Bsh BshLayer::build(const NodeKey& key, const PointBuffer& points, const std::vector<uint8_t>& gpuPoints) const {
  const size_t n = points.size();
  NL_CHECK(gpuPoints.size() == n * frame::kGpuPointBytes);
  BshPoints in;
  in.position.resize(n);
  in.colour.assign(n, glm::vec3(0.8f));
  if (normal_ >= 0) in.normal.resize(n);
  const size_t rgbOff = rgb_ >= 0 ? meta_.layout.offset(rgb_) : 0;
  const size_t nOff = normal_ >= 0 ? meta_.layout.offset(normal_) : 0;
  for (size_t i = 0; i < n; ++i) {
    std::memcpy(&in.position[i], &gpuPoints[i * frame::kGpuPointBytes], 12);
    const uint8_t* a = points.attrsOf(i);
    if (rgb_ >= 0) {
      uint16_t v[3];
      std::memcpy(v, a + rgbOff, 6);
      in.colour[i] = glm::vec3(srgbDecode(v[0] / 65535.0f), srgbDecode(v[1] / 65535.0f), srgbDecode(v[2] / 65535.0f));
    }
    if (normal_ >= 0) std::memcpy(&in.normal[i], a + nOff, 12);
  }
  BshOptions opt = options_;
  opt.leafRadius = float(meta_.levelSpacing(key.level));
  return buildBsh(in, opt);
}

void BshLayer::prepare(const NodeKey& key, const PointBuffer& points, const std::vector<uint8_t>& gpuPoints,
                       std::vector<uint8_t>& out) const {
  const auto t0 = std::chrono::steady_clock::now();
  const Bsh bsh = build(key, points, gpuPoints);
  nanoseconds_ += uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0).count());
  builds_++;
  points_ += points.size();
  nodes_ += bsh.nodes.size();
  out.resize(bsh.nodes.size() * sizeof(BshNode));
  if (!out.empty()) std::memcpy(out.data(), bsh.nodes.data(), out.size());
}

BshLayer::Totals BshLayer::totals() const { return {builds_.load(), points_.load(), nodes_.load(), nanoseconds_.load()}; }

}  // namespace nestlight::gi::pbgi
