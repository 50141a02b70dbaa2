// The memory NodeStore: the 16-byte point of a GPU store (positions relative to the node, so that
// float keeps the detail of national-grid coordinates; 8-bit colour) and bookkeeping that lets
// tests catch a leaked or doubly released handle.
#include "nestlight/streaming/memory_store.h"

#include <algorithm>
#include <cstring>

namespace nestlight::streaming {

MemoryStore::MemoryStore(const Metadata& meta, bool keepBytes)
    : meta_(meta), rgb_(meta.layout.find(attr::kRgb)), keepBytes_(keepBytes) {
  if (rgb_ >= 0 && !(meta.layout[size_t(rgb_)].type == ScalarType::U16 &&
                     meta.layout[size_t(rgb_)].components == 3))
    rgb_ = -1;
}

void MemoryStore::prepare(const NodeKey& key, PointBuffer&& points, PreparedNode& out) const {
  const size_t n = points.size();
  out.key = key;
  out.numPoints = static_cast<uint32_t>(n);
  out.bytes.resize(n * kBytesPerPoint);
  const uint32_t size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * size, key.y * size, key.z * size};
  const float scale[3] = {float(meta_.scale.x), float(meta_.scale.y), float(meta_.scale.z)};
  const size_t rgbOffset = rgb_ >= 0 ? meta_.layout.offset(size_t(rgb_)) : 0;
  uint8_t* dst = out.bytes.data();
  for (size_t i = 0; i < n; ++i, dst += kBytesPerPoint) {
    float xyz[3];
    for (int a = 0; a < 3; ++a)
      xyz[a] = static_cast<float>(points.pos[3 * i + size_t(a)] - base[a]) * scale[a];
    std::memcpy(dst, xyz, 12);
    uint8_t rgba[4] = {255, 255, 255, 255};
    if (rgb_ >= 0) {
      uint16_t c[3];
      std::memcpy(c, points.attrsOf(i) + rgbOffset, 6);
      for (int a = 0; a < 3; ++a) rgba[a] = static_cast<uint8_t>(c[a] >> 8);
    }
    std::memcpy(dst + 12, rgba, 4);
  }
}

uint64_t MemoryStore::upload(const PreparedNode& node) {
  std::lock_guard<std::mutex> lock(mutex_);
  const uint64_t h = nextHandle_++;
  Entry& e = live_[h];
  e.key = node.key;
  e.size = node.residentBytes();
  if (keepBytes_) e.bytes = node.bytes;
  liveBytes_ += e.size;
  maxLiveBytes_ = std::max(maxLiveBytes_, liveBytes_);
  ++uploads_;
  return h;
}

void MemoryStore::release(uint64_t handle) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = live_.find(handle);
  if (it == live_.end()) {
    ++badReleases_;
    return;
  }
  liveBytes_ -= it->second.size;
  live_.erase(it);
  ++releases_;
}

uint64_t MemoryStore::liveHandles() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return live_.size();
}
uint64_t MemoryStore::liveBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return liveBytes_;
}
uint64_t MemoryStore::maxLiveBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return maxLiveBytes_;
}
uint64_t MemoryStore::uploads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return uploads_;
}
uint64_t MemoryStore::releases() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return releases_;
}
uint64_t MemoryStore::badReleases() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return badReleases_;
}
NodeKey MemoryStore::keyOf(uint64_t handle) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = live_.find(handle);
  return it == live_.end() ? NodeKey{} : it->second.key;
}
std::vector<uint8_t> MemoryStore::bytesOf(uint64_t handle) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = live_.find(handle);
  return it == live_.end() ? std::vector<uint8_t>{} : it->second.bytes;
}

}  // namespace nestlight::streaming
