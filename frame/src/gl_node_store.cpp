#include "nestlight/frame/gl_node_store.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "nestlight/octree/error.h"
#include "nestlight/octree/rgb9e5.h"

namespace nestlight::frame {

// Octahedral normal encoding (Cigolle et al. 2014, "A Survey of Efficient Representations for
// Independent Unit Vectors"): 2 x 16 bits, max error ~1e-4 rad.
uint32_t packNormal(float x, float y, float z) {
  const float l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
  if (!(l1 > 0) || !std::isfinite(l1)) return 0;
  float u = x / l1, v = y / l1;
  if (z < 0) {
    const float ou = u;
    u = (1 - std::fabs(v)) * (ou >= 0 ? 1.f : -1.f);
    v = (1 - std::fabs(ou)) * (v >= 0 ? 1.f : -1.f);
  }
  auto q = [](float a) {
    return static_cast<uint32_t>(std::lround((std::clamp(a, -1.f, 1.f) * 0.5f + 0.5f) * 65535.f));
  };
  return q(u) | (q(v) << 16);
}

glm::vec3 unpackNormal(uint32_t w) {
  if (w == 0) return glm::vec3(0);
  const float ex = float(w & 0xffffu) / 65535.f * 2.f - 1.f,
              ey = float(w >> 16) / 65535.f * 2.f - 1.f;
  glm::vec3 n(ex, ey, 1.f - std::fabs(ex) - std::fabs(ey));
  if (n.z < 0) {
    const float x = n.x;
    n.x = (1 - std::fabs(n.y)) * (x >= 0 ? 1.f : -1.f);
    n.y = (1 - std::fabs(x)) * (n.y >= 0 ? 1.f : -1.f);
  }
  return glm::normalize(n);
}

namespace {

uint32_t packRgba(double r, double g, double b) {
  auto q = [](double v) { return static_cast<uint32_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5); };
  return q(r) | (q(g) << 8) | (q(b) << 16) | (255u << 24);
}

// ASPRS standard classes (LAS 1.4 table 17), other codes by a hash hue.
uint32_t classColour(uint32_t c) {
  switch (c) {
    case 2:
      return packRgba(0.63, 0.49, 0.33);  // ground
    case 3:
      return packRgba(0.55, 0.80, 0.45);  // low vegetation
    case 4:
      return packRgba(0.30, 0.70, 0.30);  // medium vegetation
    case 5:
      return packRgba(0.10, 0.50, 0.15);  // high vegetation
    case 6:
      return packRgba(0.90, 0.35, 0.30);  // building
    case 7:
      return packRgba(0.95, 0.20, 0.80);  // low point (noise)
    case 9:
      return packRgba(0.20, 0.45, 0.90);  // water
    case 17:
      return packRgba(0.60, 0.60, 0.65);  // bridge deck
    case 0:
    case 1:
      return packRgba(0.75, 0.75, 0.75);  // never classified / unassigned
    default: {
      const double h = std::fmod(c * 0.618033988749895, 1.0) * 6.0;
      const double f = h - std::floor(h);
      const int i = static_cast<int>(h);
      const double rgb[6][3] = {{1, f, 0},     {1 - f, 1, 0}, {0, 1, f},
                                {0, 1 - f, 1}, {f, 0, 1},     {1, 0, 1 - f}};
      return packRgba(rgb[i][0], rgb[i][1], rgb[i][2]);
    }
  }
}

}  // namespace

// Most returns are dark: a square root spreads them.
double intensityGrey(double intensity) {
  return std::sqrt(std::clamp(intensity, 0.0, 65535.0) / 65535.0);
}

uint32_t elevationRamp(double t) {
  t = std::clamp(t, 0.0, 1.0);
  const double stops[5][3] = {{0.27, 0.00, 0.33},
                              {0.23, 0.32, 0.55},
                              {0.13, 0.57, 0.55},
                              {0.37, 0.79, 0.38},
                              {0.99, 0.91, 0.14}};
  const double x = t * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  return packRgba(stops[i][0] + (stops[i + 1][0] - stops[i][0]) * f,
                  stops[i][1] + (stops[i + 1][1] - stops[i][1]) * f,
                  stops[i][2] + (stops[i + 1][2] - stops[i][2]) * f);
}

const char* colourModeName(ColourMode m) {
  switch (m) {
    case ColourMode::Rgb:
      return "rgb";
    case ColourMode::Intensity:
      return "intensity";
    case ColourMode::Classification:
      return "classification";
    case ColourMode::Elevation:
      return "elevation";
    case ColourMode::Normal:
      return "normal";
    case ColourMode::Hdr:
      return "hdr";
  }
  return "?";
}

ColourMode parseColourMode(const std::string& name) {
  for (ColourMode m : {ColourMode::Rgb, ColourMode::Intensity, ColourMode::Classification,
                       ColourMode::Elevation, ColourMode::Normal, ColourMode::Hdr})
    if (name == colourModeName(m)) return m;
  throw Error("unknown colour mode '" + name +
              "' (rgb, intensity, classification, elevation, normal, hdr)");
}

std::vector<ColourMode> availableColourModes(const Metadata& meta, const std::string& hdrLayer) {
  std::vector<ColourMode> out;
  if (meta.layout.has(attr::kRgb)) out.push_back(ColourMode::Rgb);
  if (meta.layout.has(attr::kIntensity)) out.push_back(ColourMode::Intensity);
  if (meta.layout.has(attr::kClassification)) out.push_back(ColourMode::Classification);
  out.push_back(ColourMode::Elevation);
  if (meta.layout.has(attr::kNormal)) out.push_back(ColourMode::Normal);
  if (meta.layer(hdrLayer)) out.push_back(ColourMode::Hdr);
  return out;
}

GlNodeStore::GlNodeStore(const Metadata& meta, ColourMode mode,
                         std::shared_ptr<const ColourLayerReader> layer)
    : meta_(meta), mode_(mode), colourLayer_(std::move(layer)) {
  NL_CHECK_MSG(mode != ColourMode::Hdr || colourLayer_, "ColourMode::Hdr without a colour layer");
  rgb_ = meta.layout.find(attr::kRgb);
  normal_ = meta.layout.find(attr::kNormal);
  intensity_ = meta.layout.find(attr::kIntensity);
  classification_ = meta.layout.find(attr::kClassification);
}

GlNodeStore::~GlNodeStore() = default;

void GlNodeStore::setColourMode(ColourMode m) {
  NL_CHECK_MSG(m != ColourMode::Hdr || colourLayer_, "ColourMode::Hdr without a colour layer");
  mode_ = m;
}

void GlNodeStore::prepare(const NodeKey& key, PointBuffer&& pts,
                          streaming::PreparedNode& out) const {
  const size_t n = pts.size();
  out.key = key;
  out.numPoints = static_cast<uint32_t>(n);
  out.bytes.resize(n * kGpuPointBytes);
  const uint32_t size = meta_.cubeSize >> key.level;
  const uint32_t base[3] = {key.x * size, key.y * size, key.z * size};
  const PointLayout& L = meta_.layout;
  const size_t rgbOff = rgb_ >= 0 ? L.offset(rgb_) : 0, nOff = normal_ >= 0 ? L.offset(normal_) : 0;
  const size_t iOff = intensity_ >= 0 ? L.offset(intensity_) : 0;
  const size_t cOff = classification_ >= 0 ? L.offset(classification_) : 0;
  const ColourMode mode = mode_;
  std::vector<float> hdr;
  if (mode == ColourMode::Hdr) {
    NL_CHECK_MSG(colourLayer_, "ColourMode::Hdr without a colour layer");
    hdr = colourLayer_->readNode(
        key, uint32_t(n));  // throws on a damaged node: the loader counts it bad
  }
  const double zLo = meta_.bounds.min.z,
               zRange = std::max(meta_.bounds.max.z - meta_.bounds.min.z, 1e-9);
  for (size_t i = 0; i < n; ++i) {
    uint8_t* o = &out.bytes[i * kGpuPointBytes];
    const uint32_t* p = &pts.pos[3 * i];
    const float local[3] = {float((p[0] - base[0]) * meta_.scale.x),
                            float((p[1] - base[1]) * meta_.scale.y),
                            float((p[2] - base[2]) * meta_.scale.z)};
    std::memcpy(o, local, 12);
    const uint8_t* a = pts.attrsOf(i);
    float nrm[3] = {0, 0, 0};
    if (normal_ >= 0) std::memcpy(nrm, a + nOff, 12);
    uint32_t colour = packRgba(0.8, 0.8, 0.8);
    switch (mode) {
      case ColourMode::Rgb:
        if (rgb_ >= 0) {
          uint16_t c[3];
          std::memcpy(c, a + rgbOff, 6);
          colour = (c[0] >> 8) | ((c[1] >> 8) << 8) | ((c[2] >> 8) << 16) | (255u << 24);
        }
        break;
      case ColourMode::Intensity:
        if (intensity_ >= 0) {
          uint16_t v;
          std::memcpy(&v, a + iOff, 2);
          const double g = intensityGrey(v);
          colour = packRgba(g, g, g);
        }
        break;
      case ColourMode::Classification:
        if (classification_ >= 0) colour = classColour(a[cOff]);
        break;
      case ColourMode::Elevation:
        colour = elevationRamp((meta_.world(2, p[2]) - zLo) / zRange);
        break;
      case ColourMode::Normal:
        colour = packRgba(nrm[0] * 0.5 + 0.5, nrm[1] * 0.5 + 0.5, nrm[2] * 0.5 + 0.5);
        break;
      case ColourMode::Hdr:
        colour = packRgb9e5(hdr[3 * i], hdr[3 * i + 1], hdr[3 * i + 2]);
        break;
    }
    std::memcpy(o + 12, &colour, 4);
    const uint32_t on = packNormal(nrm[0], nrm[1], nrm[2]);
    std::memcpy(o + 16, &on, 4);
  }
  std::vector<std::shared_ptr<const NodeLayer>> layers;
  {
    std::lock_guard lock(layersMutex_);
    layers = layers_;
  }
  out.layers.assign(layers.size(), {});
  for (size_t l = 0; l < layers.size(); ++l) layers[l]->prepare(key, pts, out.bytes, out.layers[l]);
}

uint64_t GlNodeStore::upload(const streaming::PreparedNode& node) {
  Resident r;
  auto add = [&](const std::vector<uint8_t>& bytes) {
    // Immutable storage, never mapped: the driver may place it in device memory.
    r.buffers.emplace_back(bytes.size(), bytes.empty() ? nullptr : bytes.data(), 0);
    r.bytes.push_back(bytes.size());
  };
  add(node.bytes);
  for (const auto& l : node.layers) add(l);
  const uint64_t h = nextHandle_++;
  live_.emplace(h, std::move(r));
  return h;
}

void GlNodeStore::release(uint64_t handle) {
  auto it = live_.find(handle);
  NL_CHECK_MSG(it != live_.end(), "release of a handle that is not live");
  live_.erase(it);  // the buffers delete themselves
}

GLuint GlNodeStore::layerBuffer(uint64_t handle, size_t layer) const {
  auto it = live_.find(handle);
  NL_CHECK_MSG(it != live_.end(), "a buffer of a handle that is not live");
  return layer < it->second.buffers.size() ? it->second.buffers[layer].id() : 0;
}

size_t GlNodeStore::layerBytes(uint64_t handle, size_t layer) const {
  auto it = live_.find(handle);
  NL_CHECK_MSG(it != live_.end(), "a layer of a handle that is not live");
  return layer < it->second.bytes.size() ? it->second.bytes[layer] : 0;
}

size_t GlNodeStore::addLayer(std::shared_ptr<const NodeLayer> layer) {
  NL_CHECK(layer != nullptr);
  std::lock_guard lock(layersMutex_);
  if (layers_.size() + 1 >= NL_MAX_NODE_LAYERS)
    throw Error("frame: node layer '" + layer->name() + "' is one too many (at most " +
                std::to_string(NL_MAX_NODE_LAYERS - 1) + " besides the points)");
  layers_.push_back(std::move(layer));
  return layers_.size();
}

size_t GlNodeStore::layerCount() const {
  std::lock_guard lock(layersMutex_);
  return layers_.size();
}

uint64_t GlNodeStore::liveBuffers() const {
  uint64_t n = 0;
  for (const auto& [h, r] : live_) n += r.buffers.size();
  return n;
}

uint64_t GlNodeStore::liveBytes() const {
  uint64_t n = 0;
  for (const auto& [h, r] : live_)
    for (size_t b : r.bytes) n += b;
  return n;
}

}  // namespace nestlight::frame
