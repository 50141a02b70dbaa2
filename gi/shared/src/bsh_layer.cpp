#include "nestlight/gi/shared/bsh_layer.h"

#include <chrono>
#include <cstring>

#include "nestlight/octree/error.h"

namespace nestlight::gi {

BshLayer::BshLayer(const Metadata& meta, BshOptions options,
                   std::shared_ptr<const ScanColours> colours, std::shared_ptr<const ClipSet> clip)
    : meta_(meta), options_(options), colours_(std::move(colours)), clip_(std::move(clip)) {
  if (clip_ && clip_->empty()) clip_.reset();
  // The recorded colour needs no octree path (only a layer is read from the folder).
  if (!colours_)
    colours_ =
        std::make_shared<const ScanColours>(std::filesystem::path(), meta_, ScanColours::kRecorded);
  normal_ = meta.layout.find(attr::kNormal);
}

Bsh BshLayer::build(const NodeKey& key, const PointBuffer& points,
                    const std::vector<uint8_t>& gpuPoints) const {
  const size_t n = points.size();
  NL_CHECK(gpuPoints.size() == n * frame::kGpuPointBytes);
  BshPoints in;
  in.position.resize(n);
  std::vector<float> rgb;
  colours_->linear(key, points, rgb);
  in.colour.resize(n);
  std::memcpy(in.colour.data(), rgb.data(), n * sizeof(glm::vec3));
  if (normal_ >= 0) in.normal.resize(n);
  const size_t nOff = normal_ >= 0 ? meta_.layout.offset(normal_) : 0;
  // A node the volumes cut through: its points tested one by one, in the world frame (the node's
  // float frame would round national-grid coordinates).
  const bool test =
      clip_ && clip_->keeps(meta_.nodeBounds(key.level, key.x, key.y, key.z)) == Overlap::Partial;
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i) {
    if (test && !clip_->keeps(meta_.worldPoint(&points.pos[3 * i]))) continue;
    std::memcpy(&in.position[kept], &gpuPoints[i * frame::kGpuPointBytes], 12);
    in.colour[kept] = in.colour[i];
    const uint8_t* a = points.attrsOf(i);
    if (normal_ >= 0) std::memcpy(&in.normal[kept], a + nOff, 12);
    ++kept;
  }
  in.position.resize(kept), in.colour.resize(kept);
  if (normal_ >= 0) in.normal.resize(kept);
  BshOptions opt = options_;
  opt.leafRadius = float(meta_.levelSpacing(key.level));
  if (opt.discRadii) {
    in.radius = opt.discRadii(in, opt.leafRadius);
    NL_CHECK(in.radius.size() == kept);
  }
  return buildBsh(in, opt);
}

void BshLayer::prepare(const NodeKey& key, const PointBuffer& points,
                       const std::vector<uint8_t>& gpuPoints, std::vector<uint8_t>& out) const {
  const auto t0 = std::chrono::steady_clock::now();
  const Bsh bsh = build(key, points, gpuPoints);
  nanoseconds_ += uint64_t(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t0)
          .count());
  builds_++;
  points_ += points.size();
  nodes_ += bsh.nodes.size();
  out.resize(bsh.nodes.size() * sizeof(BshNode));
  if (!out.empty()) std::memcpy(out.data(), bsh.nodes.data(), out.size());
}

BshLayer::Totals BshLayer::totals() const {
  return {builds_.load(), points_.load(), nodes_.load(), nanoseconds_.load()};
}

}  // namespace nestlight::gi
