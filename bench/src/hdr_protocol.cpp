// The ground-truth protocol of HDR expansion (see hdr_protocol.h).
#include "nestlight/bench/hdr_protocol.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <numbers>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/reader.h"
#include "nestlight/gi/hdr/expand.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_writer.h"

namespace nestlight::bench {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace gi;
using namespace gi::hdr;

namespace {

constexpr double kRoom = 4.0;

struct Face {
  glm::dvec3 origin, u, v;  // origin + s u + t v, s, t in [0, 1]
  glm::vec3 normal;
};

// The room's walls (normals inwards) and a block standing on the floor (normals outwards).
const Face kFaces[] = {
    {{0, 0, 0}, {kRoom, 0, 0}, {0, kRoom, 0}, {0, 0, 1}},       // floor
    {{0, 0, kRoom}, {kRoom, 0, 0}, {0, kRoom, 0}, {0, 0, -1}},  // ceiling
    {{0, 0, 0}, {0, kRoom, 0}, {0, 0, kRoom}, {1, 0, 0}},       // red wall, x = 0
    {{kRoom, 0, 0}, {0, kRoom, 0}, {0, 0, kRoom}, {-1, 0, 0}},  // green wall, x = 4
    {{0, 0, 0}, {kRoom, 0, 0}, {0, 0, kRoom}, {0, 1, 0}},       // y = 0
    {{0, kRoom, 0}, {kRoom, 0, 0}, {0, 0, kRoom}, {0, -1, 0}},  // y = 4, the window wall
    {{2.6, 2.4, 1.2}, {0.8, 0, 0}, {0, 0.8, 0}, {0, 0, 1}},     // block top
    {{2.6, 2.4, 0}, {0.8, 0, 0}, {0, 0, 1.2}, {0, -1, 0}},      // block sides
    {{2.6, 3.2, 0}, {0.8, 0, 0}, {0, 0, 1.2}, {0, 1, 0}},
    {{2.6, 2.4, 0}, {0, 0.8, 0}, {0, 0, 1.2}, {-1, 0, 0}},
    {{3.4, 2.4, 0}, {0, 0.8, 0}, {0, 0, 1.2}, {1, 0, 0}},
};
constexpr size_t kFaceCount = sizeof(kFaces) / sizeof(kFaces[0]);

double window(double x, double lo, double hi, double soft) {
  return 1.0 / (1.0 + std::exp(-(x - lo) / soft)) / (1.0 + std::exp((x - hi) / soft));
}

uint64_t mix(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ull;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
double unit(uint64_t h) {
  return double(h >> 11) * 0x1.0p-53;
}

class ProtocolReader : public PointReader {
 public:
  ProtocolReader(uint64_t points, uint64_t seed, double exposure, double maxHeight)
      : points_(points), seed_(seed), exposure_(exposure), maxHeight_(maxHeight) {
    header_.path = "hdr-protocol-room";
    header_.format = "synthetic";
    header_.declaredPoints = points;
    Box3d b;
    b.min = {0, 0, 0};
    b.max = {kRoom, kRoom, kRoom};
    header_.declaredBounds = b;
    header_.layout.add({std::string(attr::kRgb), ScalarType::U16, 3,
                        "LDR colour: truth x exposure, clamped, gamma 2.2"});
    header_.layout.add({std::string(attr::kNormal), ScalarType::F32, 3, ""});
    header_.rgbBits = 16;
    double total = 0;
    for (const auto& f : kFaces) total += glm::length(glm::cross(f.u, f.v)), cdf_.push_back(total);
    for (double& c : cdf_) c /= total;
  }
  const SourceHeader& header() const override { return header_; }
  bool read(PointBatch& batch, size_t maxPoints) override {
    batch.clear();
    const size_t n = size_t(std::min<uint64_t>(maxPoints, points_ - next_));
    if (n == 0) return false;
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * 18);
    for (size_t k = 0; k < n; ++k) {
      const uint64_t i = next_ + k;
      uint64_t h = mix(seed_ * 0x9E3779B97F4A7C15ull + i);
      const Face* fp;
      glm::dvec3 p;
      // A point above maxHeight is drawn again (from the next hash), so the count stays.
      for (;; h = mix(h + 3)) {
        const double pick = unit(h);
        const size_t fi = size_t(std::lower_bound(cdf_.begin(), cdf_.end(), pick) - cdf_.begin());
        fp = &kFaces[std::min(fi, kFaceCount - 1)];
        // Millimetre grid: the stored positions are these exactly.
        p = fp->origin + unit(mix(h + 1)) * fp->u + unit(mix(h + 2)) * fp->v;
        for (int a = 0; a < 3; ++a) p[a] = std::round(p[a] * 1000.0) / 1000.0;
        if (p.z <= maxHeight_) break;
      }
      const Face& f = *fp;
      for (int a = 0; a < 3; ++a) batch.xyz[3 * k + size_t(a)] = p[a];
      const glm::vec3 l = protocolRadiance(p, f.normal) * float(exposure_);
      uint16_t rgb[3];
      for (int c = 0; c < 3; ++c)
        rgb[c] = uint16_t(std::lround(displayFromLinear(std::clamp(l[c], 0.0f, 1.0f)) * 65535.0f));
      std::memcpy(&batch.attrs[18 * k], rgb, 6);
      std::memcpy(&batch.attrs[18 * k + 6], &f.normal, 12);
    }
    next_ += n;
    return true;
  }
  void rewind() override { next_ = 0; }
  uint64_t bytesConsumed() const override { return next_ * 18; }
  uint64_t bytesTotal() const override { return points_ * 18; }

 private:
  SourceHeader header_;
  uint64_t points_, seed_, next_ = 0;
  double exposure_, maxHeight_;
  std::vector<double> cdf_;
};

}  // namespace

glm::vec3 protocolRadiance(const glm::dvec3& p, const glm::vec3& n) {
  glm::vec3 albedo(0.7f, 0.7f, 0.7f);
  const bool block = p.x > 2.59 && p.x < 3.41 && p.y > 2.39 && p.y < 3.21 && p.z < 1.21;
  if (block)
    albedo = {0.45f, 0.5f, 0.62f};
  else if (n.x > 0.5f)
    albedo = {0.63f, 0.065f, 0.05f};
  else if (n.x < -0.5f)
    albedo = {0.14f, 0.45f, 0.09f};
  // A texture of incommensurate waves (periods 0.5 to 1 m): patches are distinguishable, so
  // that matching has something to hold on to.
  const double t = std::sin(7.3 * p.x + 2.1 * p.y - 3.7 * p.z + 0.3) *
                       std::sin(-2.9 * p.x + 8.1 * p.y + 4.3 * p.z + 1.1) +
                   0.5 * std::sin(5.1 * p.x - 6.7 * p.y + 9.7 * p.z + 2.0);
  const float texture = float(0.72 + 0.25 * t / 1.5);
  // Irradiance: ambient, a ceiling lamp (inverse square, cosine at the receiver), sunlight
  // through a window onto the floor and the window wall.
  const glm::dvec3 lamp{2.0, 2.0, 3.95};
  const glm::dvec3 d = lamp - p;
  const double dist2 = std::max(glm::dot(d, d), 1e-4);
  double e = 1.5 + 30.0 * std::max(0.0, glm::dot(glm::dvec3(n), d) / std::sqrt(dist2)) / dist2;
  if (n.z > 0.5f) e += 50.0 * window(p.x, 0.8, 2.6, 0.05) * window(p.y, 0.4, 2.6, 0.05);
  if (n.y < -0.5f) e += 25.0 * window(p.x, 1.2, 2.8, 0.05) * window(p.z, 1.0, 2.6, 0.05);
  glm::vec3 radiance = albedo * texture * float(e / std::numbers::pi);
  if (n.z < -0.5f && p.z > 3.99) {
    const double r2 = (p.x - 2.0) * (p.x - 2.0) + (p.y - 2.0) * (p.y - 2.0);
    radiance += glm::vec3(1.0f, 0.95f, 0.85f) * float(2000.0 * std::exp(-r2 / (2 * 0.12 * 0.12)));
  }
  return radiance;
}

View protocolPhotoView(int width, int height) {
  // Wide (110 degrees): from the wall opposite the window, the lamp, the window's light on the
  // far wall and the far half of the sunlit floor.
  View v = lookAt({2.0, 0.3, 2.0}, {2.0, 4.0, 2.0}, {0, 0, 1}, 110.0, width, height);
  v.name = "photo";
  return v;
}

fs::path makeHdrProtocol(const fs::path& dir, const ProtocolOptions& o) {
  if (!(o.maxHeight >= 0))  // the floor (height 0) always has room
    throw Error("", "protocol",
                "the largest height must be 0 or more, got " + std::to_string(o.maxHeight));
  fs::create_directories(dir);
  const fs::path octree = dir / "scan.octree";
  BuildOptions bo;
  bo.output = octree;
  bo.overwrite = o.overwrite;
  bo.precision = 0.001;
  bo.progress = o.quiet ? ProgressMode::Quiet : ProgressMode::Auto;
  bo.commandLine = {{"generator", "hdr protocol"},
                    {"points", o.points},
                    {"seed", o.seed},
                    {"exposure", o.exposure}};
  std::vector<std::unique_ptr<PointReader>> sources;
  sources.push_back(std::make_unique<ProtocolReader>(o.points, o.seed, o.exposure, o.maxHeight));
  buildOctree(std::move(sources), bo);

  // The truth layer, from the stored points (their positions and normals are exact).
  OctreeReader reader(octree);
  ScanAccess scan(reader);
  const auto nodes = reader.allNodes();
  uint64_t clipped = 0;
  std::mutex mutex;
  {
    ColourLayerWriter truth(octree, "truth", 1.0);
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
      const ScanNode n = scan.read(nodes[ni].first, nodes[ni].second);
      std::vector<float> rgb(n.world.size() * 3);
      uint64_t c = 0;
      for (size_t i = 0; i < n.world.size(); ++i) {
        const glm::vec3 v = protocolRadiance(n.world[i], n.normal[i]) * float(o.exposure);
        for (int a = 0; a < 3; ++a) rgb[3 * i + size_t(a)] = v[a];
        c += luminance(n.ldr[i]) > 0.9f;
      }
      truth.writeNode(nodes[ni].first, rgb.data(), n.world.size());
      std::lock_guard<std::mutex> lock(mutex);
      clipped += c;
    });
    truth.finish({{"what", "the protocol's true radiance times the scan's exposure (LDR units)"},
                  {"exposure", o.exposure}});
  }

  // The photograph: the true radiance (absolute units), as the camera would record it in HDR.
  const View photoView = protocolPhotoView(o.photoWidth, o.photoHeight);
  SplatOptions so;
  so.colour = [](const ScanNode& n, std::vector<uint32_t>& out) {
    out.resize(n.world.size());
    for (size_t i = 0; i < n.world.size(); ++i)
      out[i] = packRgb9e5(protocolRadiance(n.world[i], n.normal[i]));
  };
  const std::vector<Rendering> photo = renderViews(scan, {photoView}, Payload::Rgb9e5, so);
  writeExr((dir / "photo.exr").string(), photo[0].image(),
           {{"nestlight:protocol", "true radiance of the room"}});

  const json p = {{"scan", "scan.octree"},     {"photo", "photo.exr"},
                  {"exposure", o.exposure},    {"points", reader.metadata().points},
                  {"clipped_points", clipped}, {"photo_view", viewToJson(photoView)},
                  {"truth_layer", "truth"}};
  const std::string text = p.dump(2) + "\n";
  writeFileAtomic(dir / "protocol.json", text.data(), text.size());
  return dir / "protocol.json";
}

json LayerError::toJson() const {
  return {{"rms_all", rmsAll},
          {"rms_clipped", rmsClipped},
          {"stops_clipped", stopsClipped},
          {"points", points},
          {"clipped_points", clipped}};
}

LayerError compareWithTruth(const fs::path& octree, const std::string& layer, double clipThreshold,
                            double landisMax) {
  OctreeReader reader(octree);
  ScanAccess scan(reader);
  const Metadata& m = reader.metadata();
  ColourLayerReader truth(octree, m, "truth");
  std::unique_ptr<ColourLayerReader> other;
  if (layer != "ldr" && layer != "landis")
    other = std::make_unique<ColourLayerReader>(octree, m, layer);
  const auto nodes = reader.allNodes();
  double sumAll = 0, sumClipped = 0, sumStops = 0;
  LayerError err;
  std::mutex mutex;
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints == 0) return;
    const ScanNode n = scan.read(key, entry);
    const std::vector<float> t = truth.readNode(key, entry.numPoints);
    std::vector<float> v;
    if (other) v = other->readNode(key, entry.numPoints);
    double a = 0, c = 0, st = 0;
    uint64_t nc = 0;
    for (size_t i = 0; i < n.ldr.size(); ++i) {
      glm::vec3 h = n.ldr[i];
      if (other)
        h = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
      else if (layer == "landis")
        h = landisExpand(n.ldr[i], clipThreshold, landisMax);
      double s = 0;
      for (int ch = 0; ch < 3; ++ch)
        s += (double(h[ch]) - t[3 * i + size_t(ch)]) * (double(h[ch]) - t[3 * i + size_t(ch)]);
      s /= 3;
      a += s;
      if (luminance(n.ldr[i]) > clipThreshold) {
        c += s, nc++;
        const double yt = luminance(Rgb(t[3 * i], t[3 * i + 1], t[3 * i + 2]));
        const double stops = std::log2(std::max(double(luminance(h)), 1e-6) / std::max(yt, 1e-6));
        st += stops * stops;
      }
    }
    std::lock_guard<std::mutex> lock(mutex);
    sumAll += a, sumClipped += c, sumStops += st;
    err.points += n.ldr.size();
    err.clipped += nc;
  });
  err.rmsAll = err.points ? std::sqrt(sumAll / double(err.points)) : 0;
  err.rmsClipped = err.clipped ? std::sqrt(sumClipped / double(err.clipped)) : 0;
  err.stopsClipped = err.clipped ? std::sqrt(sumStops / double(err.clipped)) : 0;
  return err;
}

}  // namespace nestlight::bench
