// HDR expansion, Algorithm 1 of Sabbadin et al. 2019 (see expand.h for the stages and
// colour conventions).
#include "nestlight/gi/hdr/expand.h"

#include <fcntl.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <mutex>
#include <random>
#include <unordered_map>
#include <unordered_set>

#include "nestlight/converters/builder.h"
#include "nestlight/gi/hdr/exposure.h"
#include "nestlight/gi/hdr/patchmatch.h"
#include "nestlight/gi/hdr/poisson_infill.h"
#include "nestlight/gi/hdr/renderings.h"
#include "nestlight/gi/sampling.h"
#include "nestlight/octree/colour_layer.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi::hdr {

namespace fs = std::filesystem;
using json = nlohmann::json;

const char* expansionModeName(ExpansionMode m) {
  return m == ExpansionMode::Rgb ? "rgb" : "luminance";
}

json ExpandReport::toJson() const {
  json v = json::array();
  for (const auto& view : views) v.push_back(view.name);
  return {{"log2_exposure", log2Exposure},
          {"exposure_distance", exposureDistance},
          {"views", v},
          {"points", points},
          {"nodes", nodes},
          {"overexposed_points", overexposed},
          {"expanded_points", projected},
          {"unseen_points", unseen},
          {"rejected_match_points", rejectedMatches},
          {"infilled_points", infilled},
          {"islands", islands},
          {"island_points", islandPoints},
          {"infill_chunks", chunks},
          {"infill_chunk_max_points", chunkMaxPoints},
          {"cg_iterations_max", cgIterationsMax},
          {"matched_pixels", matchedPixels},
          {"covered_pixels", coveredPixels},
          {"blind_pixels", blindPixels},
          {"background_pixels", backgroundPixels},
          {"stray_pixels", strayPixels},
          {"max_value", maxValue},
          {"bounded_values", boundedValues},
          {"exposure", checks.toJson()},
          {"warnings", warnings},
          {"clamped_values", clampedValues},
          {"seconds", seconds},
          {"peak_rss_bytes", peakRssBytes}};
}

json ExposureChecks::toJson() const {
  return {
      {"method", method},       {"histogram_log2", histogramLog2},   {"spread_stops", spreadStops},
      {"slope", slope},         {"highlight_slope", highlightSlope}, {"pairs", pairs},
      {"rematches", rematches}, {"range_log2", {rangeLo, rangeHi}},  {"photo_max", photoMax},
      {"bound", bound},         {"matched_share", matchedShare},     {"failed", failed}};
}

glm::vec3 landisExpand(const glm::vec3& ldr, double threshold, double maxLuminance,
                       double exponent) {
  const double y = luminance(ldr);
  if (!(y > threshold) || threshold >= 1) return ldr;
  const double k = std::pow(std::min(1.0, (y - threshold) / (1 - threshold)), exponent);
  const double expanded = (1 - k) * y + k * maxLuminance * y;
  return ldr * float(expanded / y);
}

namespace {

// The exposed photograph's value at masked-out pixels (display values are in [0, 1]): one such
// sample in a patch costs 99^2, far beyond any t_h.
constexpr float kMaskedOut = 100.0f;

// 1 where every covered pixel of the (2r+1)^2 patch around a covered pixel is over-exposed
// (linear LDR luminance above t_l): a summed-area table of the pixels that are not.
std::vector<uint8_t> blindPatches(const HdrImage& ldr, const std::vector<uint8_t>& covered, int r, double overexposed) {
  const int w = ldr.width, h = ldr.height;
  std::vector<uint32_t> sat(size_t(w + 1) * size_t(h + 1), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      const Rgb c = ldr.get(x, y);
      const bool informative =
          covered[i] && !(luminance(Rgb(linearFromDisplay(c.r), linearFromDisplay(c.g), linearFromDisplay(c.b))) > overexposed);
      sat[size_t(y + 1) * size_t(w + 1) + size_t(x + 1)] = uint32_t(informative) + sat[size_t(y) * size_t(w + 1) + size_t(x + 1)] +
                                                           sat[size_t(y + 1) * size_t(w + 1) + size_t(x)] -
                                                           sat[size_t(y) * size_t(w + 1) + size_t(x)];
    }
  std::vector<uint8_t> out(ldr.pixels(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - r), x1 = std::min(w, x + r + 1), y0 = std::max(0, y - r), y1 = std::min(h, y + r + 1);
      const uint32_t n = sat[size_t(y1) * size_t(w + 1) + size_t(x1)] - sat[size_t(y0) * size_t(w + 1) + size_t(x1)] -
                         sat[size_t(y1) * size_t(w + 1) + size_t(x0)] + sat[size_t(y0) * size_t(w + 1) + size_t(x0)];
      out[size_t(y) * size_t(w) + size_t(x)] = covered[size_t(y) * size_t(w) + size_t(x)] && n == 0;
    }
  return out;
}

// Per-point scratch record: the HDR colour so far and what happened to the point.
enum PointState : uint32_t {
  kKept = 0,       // not over-exposed: its LDR colour is its HDR colour
  kProjected = 1,  // over-exposed, given a matched HDR value
  kTarget = 2,     // over-exposed, no valid value: to in-fill
  kInfilled = 3,
  kIsland = 4,  // to in-fill, but no valid neighbour in reach: LDR kept
};
struct ScratchRecord {
  float rgb[3];
  uint32_t state;
};
static_assert(sizeof(ScratchRecord) == 16);

class Scratch {
 public:
  Scratch(const fs::path& path, uint64_t points) : path_(path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw Error(path.string(), "",
                  std::string("cannot create the scratch file: ") + std::strerror(errno));
    if (::ftruncate(fd_, off_t(points * sizeof(ScratchRecord))) != 0)
      throw Error(path.string(), "",
                  std::string("cannot size the scratch file: ") + std::strerror(errno));
  }
  ~Scratch() {
    ::close(fd_);
    std::error_code ec;
    fs::remove(path_, ec);
  }
  void read(uint64_t first, size_t count, std::vector<ScratchRecord>& out) const {
    out.resize(count);
    io(false, first, count, out.data());
  }
  void write(uint64_t first, const std::vector<ScratchRecord>& in) {
    io(true, first, in.size(), const_cast<ScratchRecord*>(in.data()));
  }

 private:
  void io(bool write, uint64_t first, size_t count, ScratchRecord* data) const {
    uint8_t* p = reinterpret_cast<uint8_t*>(data);
    size_t left = count * sizeof(ScratchRecord);
    uint64_t off = first * sizeof(ScratchRecord);
    while (left > 0) {
      const ssize_t r =
          write ? ::pwrite(fd_, p, left, off_t(off)) : ::pread(fd_, p, left, off_t(off));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0)
        throw Error(path_.string(), Error::atByte(off),
                    std::string("scratch I/O failed: ") + std::strerror(errno));
      p += r, left -= size_t(r), off += uint64_t(r);
    }
  }
  fs::path path_;
  int fd_ = -1;
};

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Box-filters `img` down by an integer factor until its long side is at most `maxSize`.
HdrImage shrink(const HdrImage& img, int maxSize) {
  const int f = std::max(1, (std::max(img.width, img.height) + maxSize - 1) / maxSize);
  if (f == 1) return img;
  HdrImage out(img.width / f, img.height / f);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      glm::dvec3 s(0);
      int n = 0;
      for (int j = 0; j < f; ++j)
        for (int i = 0; i < f; ++i) {
          const Rgb c = img.get(x * f + i, y * f + j);
          if (std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b))
            s += glm::dvec3(c), n++;
        }
      out.set(x, y, n ? Rgb(s / double(n)) : Rgb(0));
    }
  return out;
}

// A uniform sample of the over-exposed points that does not depend on the order threads visit
// nodes in (reservoir sampling did, and so did the automatic views): every point gets a hash of
// its index in the scan, and the sample keeps the smallest hashes (bottom-k sampling).
struct Sample {
  struct Entry {
    uint64_t hash;
    glm::dvec3 position;
    glm::vec3 normal;
    bool operator<(const Entry& o) const { return hash < o.hash; }
  };
  std::vector<Entry> heap;  // a max-heap on hash, at most the sample's size
  std::vector<glm::dvec3> positions;
  std::vector<glm::vec3> normals;

  static uint64_t hashOf(uint64_t index) {  // splitmix64's finaliser
    uint64_t x = index + 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
  }
  void offer(const Entry& e, size_t capacity) {
    if (heap.size() < capacity) {
      heap.push_back(e);
      std::push_heap(heap.begin(), heap.end());
    } else if (e.hash < heap.front().hash) {
      std::pop_heap(heap.begin(), heap.end());
      heap.back() = e;
      std::push_heap(heap.begin(), heap.end());
    }
  }
  // The sample in hash order.
  void finish() {
    std::sort(heap.begin(), heap.end());
    for (const Entry& e : heap) positions.push_back(e.position), normals.push_back(e.normal);
  }
};

}  // namespace

std::vector<View> automaticViews(const std::vector<glm::dvec3>& positions,
                                 const std::vector<glm::vec3>& normals,
                                 const glm::dvec3& scanCentre, double scanDiagonal, int count,
                                 int faceSize) {
  std::vector<View> views;
  if (count <= 0) return views;
  if (positions.empty()) {
    // Nothing is over-exposed: one cube map at the centre still gives the in-fill its context.
    for (auto& f : cubeMap("auto0", scanCentre, faceSize)) views.push_back(f);
    return views;
  }
  // k-means (Lloyd, 10 rounds) seeded by farthest points: clusters of over-exposed surface.
  std::vector<glm::dvec3> centres{positions[0]};
  while (int(centres.size()) < count && centres.size() < positions.size()) {
    size_t best = 0;
    double bestD = -1;
    for (size_t i = 0; i < positions.size(); ++i) {
      double d = INFINITY;
      for (const auto& c : centres) d = std::min(d, glm::length(positions[i] - c));
      if (d > bestD) bestD = d, best = i;
    }
    if (bestD <= 0) break;
    centres.push_back(positions[best]);
  }
  std::vector<size_t> label(positions.size(), 0);
  for (int round = 0; round < 10; ++round) {
    for (size_t i = 0; i < positions.size(); ++i) {
      double bestD = INFINITY;
      for (size_t c = 0; c < centres.size(); ++c)
        if (const double d = glm::length(positions[i] - centres[c]); d < bestD)
          bestD = d, label[i] = c;
    }
    std::vector<glm::dvec3> sum(centres.size(), glm::dvec3(0));
    std::vector<size_t> n(centres.size(), 0);
    for (size_t i = 0; i < positions.size(); ++i) sum[label[i]] += positions[i], n[label[i]]++;
    for (size_t c = 0; c < centres.size(); ++c)
      if (n[c]) centres[c] = sum[c] / double(n[c]);
  }
  for (size_t c = 0; c < centres.size(); ++c) {
    glm::dvec3 normalSum(0);
    double extent = 0;
    size_t n = 0;
    for (size_t i = 0; i < positions.size(); ++i) {
      if (label[i] != c) continue;
      n++;
      extent = std::max(extent, glm::length(positions[i] - centres[c]));
      if (!normals.empty()) normalSum += glm::dvec3(normals[i]);
    }
    if (n == 0) continue;
    // A 90-degree face sees a disc of radius d at distance d: stand back by the cluster's
    // extent, at least 5% of the scan, at most a quarter of it.
    const double distance = std::clamp(extent * 1.2, 0.05 * scanDiagonal, 0.25 * scanDiagonal);
    glm::dvec3 dir;
    if (glm::length(normalSum) > 0.3 * double(n)) {
      dir = glm::normalize(normalSum);
    } else {
      dir = scanCentre - centres[c];
      dir = glm::length(dir) > 1e-9 ? glm::normalize(dir) : glm::dvec3(0, 0, 1);
    }
    for (auto& f : cubeMap("auto" + std::to_string(c), centres[c] + dir * distance, faceSize))
      views.push_back(f);
  }
  return views;
}

ExpandReport expandHdr(const fs::path& dir, const HdrImage& photo, const ExpandOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  auto progress = [&](const std::string& stage, double f) {
    if (o.progress) o.progress(stage, f);
  };
  ExpandReport rep;
  if (o.writeLayer) checkLayerName(o.layerName);  // before hours of work, not after
  OctreeReader reader(dir);
  const Metadata& meta = reader.metadata();
  ScanAccess scan(reader);
  if (o.writeLayer) removeOrphanLayerFiles(dir, meta);
  auto nodes = reader.allNodes();
  std::sort(nodes.begin(), nodes.end(), [](auto& a, auto& b) { return a.first < b.first; });
  std::vector<uint64_t> base(nodes.size() + 1, 0);
  std::unordered_map<NodeKey, size_t, NodeKeyHash> nodeIndex;
  for (size_t i = 0; i < nodes.size(); ++i) {
    base[i + 1] = base[i] + nodes[i].second.numPoints;
    nodeIndex[nodes[i].first] = i;
  }
  rep.points = base.back();
  rep.nodes = nodes.size();
  if (rep.points == 0) throw Error(dir.string(), "", "the scan holds no points");
  if (photo.pixels() == 0) throw Error("", "", "the photograph has no pixels");
  if (!o.photoMask.empty() && o.photoMask.size() != photo.pixels())
    throw Error("", "photo mask",
                "has " + std::to_string(o.photoMask.size()) + " pixels, the photograph " +
                    std::to_string(photo.width) + " x " + std::to_string(photo.height) +
                    ": a mask is drawn on the photograph itself, at its size");
  auto maskedIn = [&](size_t i) { return o.photoMask.empty() || o.photoMask[i] != 0; };

  // Pass A: the scan's luminance histogram (eq. 1) and a sample of its over-exposed points.
  auto t = Clock::now();
  std::vector<double> counts(kHistogramBins, 0.0);
  std::atomic<uint64_t> overexposed{0};
  Sample sample;
  std::mutex mutex;
  const size_t kSampleMax = 20000;
  std::atomic<uint64_t> nodesDone{0};
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints == 0) return;
    const ScanNode n = scan.read(key, entry);
    std::vector<double> local(kHistogramBins, 0.0);
    std::vector<size_t> over;
    for (size_t i = 0; i < n.ldr.size(); ++i) {
      const double y = luminance(n.ldr[i]);
      local[size_t(std::clamp(int(y * kHistogramBins), 0, kHistogramBins - 1))] += 1;
      if (y > o.overexposed) over.push_back(i);
    }
    overexposed += over.size();
    std::lock_guard<std::mutex> lock(mutex);
    for (int b = 0; b < kHistogramBins; ++b) counts[size_t(b)] += local[size_t(b)];
    for (size_t i : over)
      sample.offer({Sample::hashOf(base[ni] + i), n.world[i], n.normal.empty() ? glm::vec3(0) : n.normal[i]},
                   kSampleMax);
    progress("statistics", double(++nodesDone) / double(nodes.size()));
  });
  rep.overexposed = overexposed;
  sample.finish();
  Histogram scanHistogram;
  scanHistogram.counted = rep.points;
  for (int b = 0; b < kHistogramBins; ++b)
    scanHistogram.mass[size_t(b)] = counts[size_t(b)] / double(rep.points);
  rep.seconds["statistics"] = seconds(t);

  // The photograph's range, and the exposure the paper's histogram search (eq. 1, 2) finds: the
  // starting point when nothing registers the photograph, and on record otherwise.
  t = Clock::now();
  // Pixels of exactly zero carry no measurement (a rendered photograph's background, a masked
  // area): counted, they would pull the histogram, and so the exposure, towards black.
  std::vector<float> photoY;
  photoY.reserve(photo.pixels());
  double photoMax = 0;
  for (size_t i = 0; i < photo.pixels(); ++i) {
    // Masked out: what the photograph shows there is not the scanned scene (sky, a lamp beyond
    // the scan, people), so it is no evidence of the exposure and bounds no value.
    if (!maskedIn(i)) continue;
    const Rgb c(photo.rgb[3 * i], photo.rgb[3 * i + 1], photo.rgb[3 * i + 2]);
    for (int k = 0; k < 3; ++k)
      if (std::isfinite(c[k])) photoMax = std::max(photoMax, double(c[k]));
    if (const float y = luminance(c); y != 0.0f) photoY.push_back(y);
  }
  std::vector<float> positiveY;
  for (float y : photoY)
    if (std::isfinite(y) && y > 0) positiveY.push_back(y);
  if (positiveY.empty())
    throw Error("", "",
                o.photoMask.empty()
                    ? "the photograph has no positive finite luminance (black or broken): "
                      "nothing to match"
                    : "the photograph has no positive finite luminance where its mask lets it "
                      "count: nothing to match");
  ExposureChecks& checks = rep.checks;
  checks.photoMax = photoMax;
  {
    // The exposed photograph must bring its brightest luminance beyond the scan's clipping (by
    // minHeadroom), or it says nothing about the clipped points, and must leave its darkest
    // percentile under 1, or it is clipped almost everywhere and nothing matches.
    const size_t p1 = positiveY.size() / 100;
    std::nth_element(positiveY.begin(), positiveY.begin() + std::ptrdiff_t(p1), positiveY.end());
    const double dark = positiveY[p1];
    const double bright = *std::max_element(positiveY.begin(), positiveY.end());
    checks.rangeLo = std::log2(o.minHeadroom / bright);
    checks.rangeHi = std::max(checks.rangeLo, std::log2(1.0 / dark));
  }
  rep.exposureUsable = true;
  if (o.log2Exposure) {
    checks.method = "forced";
    rep.log2Exposure = *o.log2Exposure;
  } else if (o.photoView) {
    checks.method = "photo-view";  // estimated from the photograph's own view, after the renderings
  } else {
    checks.method = "matches";
    const ExposureSearch ex = findBestExposure(photoY, scanHistogram);
    if (!ex.usable)
      throw Error(
          "", "",
          "the photograph has no positive finite luminance (black or broken): nothing to match");
    rep.log2Exposure = checks.histogramLog2 = ex.log2Exposure;
    rep.exposureDistance = ex.distance;
  }
  rep.seconds["exposure"] = seconds(t);

  // The views: given, or cube maps looking at the over-exposed points.
  const Box3d& b = meta.bounds;
  const glm::dvec3 centre{(b.min.x + b.max.x) / 2, (b.min.y + b.max.y) / 2,
                          (b.min.z + b.max.z) / 2};
  const double diagonal =
      glm::length(glm::dvec3(b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z));
  rep.views = o.views.empty() ? automaticViews(sample.positions, sample.normals, centre, diagonal,
                                               o.autoViews, o.faceSize)
                              : o.views;
  // The photograph as PatchMatch sees it (box-filtered down to maxPhotoSize).
  const HdrImage small = shrink(photo, o.maxPhotoSize);
  // The mask at PatchMatch's size: a pixel counts only if every photograph pixel it averages does.
  std::vector<uint8_t> smallMask;
  if (!o.photoMask.empty()) {
    HdrImage m(photo.width, photo.height);
    for (size_t i = 0; i < photo.pixels(); ++i)
      if (o.photoMask[i]) m.rgb[3 * i] = m.rgb[3 * i + 1] = m.rgb[3 * i + 2] = 1.0f;
    const HdrImage shrunk = shrink(m, o.maxPhotoSize);
    smallMask.resize(shrunk.pixels());
    for (size_t i = 0; i < shrunk.pixels(); ++i) smallMask[i] = shrunk.rgb[3 * i] >= 0.999f;
  }
  if (o.photoView) {
    // Rendered at the matched photograph's size, so that its pixels are the photograph's and the
    // identity start is the identity.
    const View& v = *o.photoView;
    const double aspect = double(v.width) / double(v.height), photoAspect = double(photo.width) / double(photo.height);
    if (std::abs(aspect / photoAspect - 1.0) > 0.01)
      throw Error("", "photo view",
                  "is " + std::to_string(v.width) + " x " + std::to_string(v.height) + ", the photograph " +
                      std::to_string(photo.width) + " x " + std::to_string(photo.height) +
                      ": a registered camera has the photograph's aspect");
    View sized = lookAt(v.position, v.position + v.forward, v.up, v.fovYDegrees, small.width, small.height);
    sized.name = v.name.empty() ? "photo" : v.name;
    rep.views.insert(rep.views.begin(), sized);
  }
  if (rep.views.empty()) throw Error("", "", "no views to render the scan from");

  // Pass B: LDR renderings.
  t = Clock::now();
  SplatOptions splat;
  splat.progress = [&](uint64_t d, uint64_t n) { progress("render", double(d) / double(n)); };
  std::vector<Rendering> renderings = renderViews(scan, rep.views, Payload::Display8, splat);
  rep.seconds["render"] = seconds(t);

  // Checks of the exposure's pairs (the matched share is checked after back-projection). A forced
  // exposure is measured all the same, for the record, but the caller vouches for it.
  const double photoClip = 0.99 * double(*std::max_element(positiveY.begin(), positiveY.end()));
  auto recordPairs = [&](const PairEstimate& pe) {
    checks.spreadStops = pe.spreadStops;
    checks.slope = pe.slope;
    checks.highlightSlope = pe.highlightSlope;
    checks.pairs = pe.pairs;
  };
  auto exposureFailures = [&]() {
    std::vector<std::string> f;
    char buf[400];
    if (checks.pairs < o.minPairs) {
      std::snprintf(
          buf, sizeof buf,
          "only %llu pixel pairs that the renderings explain and the scan recorded unclipped "
          "(at least %llu): the exposure rests on nothing",
          (unsigned long long)checks.pairs, (unsigned long long)o.minPairs);
      f.push_back(buf);
    } else if (checks.spreadStops > o.maxSpreadStops) {
      std::snprintf(
          buf, sizeof buf,
          "the log ratios between the scan's colour and the photograph spread over %.2f stops "
          "(at most %.2f; %llu pixel pairs, slope %.2f where a pure exposure change gives 1): "
          "the photograph's tone is not an exposure change of the scan's colour, or the pairs "
          "are of different things",
          checks.spreadStops, o.maxSpreadStops, (unsigned long long)checks.pairs, checks.slope);
      f.push_back(buf);
    }
    if (checks.pairs >= o.minPairs && checks.highlightSlope > o.maxHighlightSlope) {
      std::snprintf(
          buf, sizeof buf,
          "towards the clipping the photograph's tone grows %.2f times as fast as the scan's in "
          "log "
          "terms (at most %.2f; 1 is an exposure change): the values beyond the clipping would "
          "overshoot the truth",
          checks.highlightSlope, o.maxHighlightSlope);
      f.push_back(buf);
    }
    if (rep.log2Exposure < checks.rangeLo || rep.log2Exposure > checks.rangeHi) {
      std::snprintf(
          buf, sizeof buf,
          "the exposure 2^%.2f is outside the plausible range 2^%.2f to 2^%.2f (from where the "
          "photograph's brightest value reaches %.2f times the scan's clipping to where its "
          "darkest "
          "percentile clips)",
          rep.log2Exposure, checks.rangeLo, checks.rangeHi, o.minHeadroom);
      f.push_back(buf);
    }
    return f;
  };
  auto stopOnFailures = [&](const std::vector<std::string>& failed) {
    if (failed.empty()) return;
    checks.failed.insert(checks.failed.end(), failed.begin(), failed.end());
    if (o.force) {
      for (const auto& f : failed) rep.warnings.push_back(f);
      return;
    }
    std::string msg = "the HDR layer would not be trusted, so none was written: ";
    for (size_t i = 0; i < failed.size(); ++i) msg += (i ? "; " : "") + failed[i];
    char buf[160];
    std::snprintf(buf, sizeof buf, " (exposure 2^%.2f, found from %s).", rep.log2Exposure,
                  checks.method.c_str());
    msg += buf;
    msg += o.photoView ? ""
                       : " Pass the photograph's camera (--photo-view cams.json) so that only the "
                         "pixels the scan covers count.";
    msg += o.photoMask.empty()
               ? " Pass a mask (--photo-mask mask.png, white where the photograph shows the "
                 "scanned scene) to leave out what the scan lacks."
               : "";
    msg +=
        " Pass the exposure if you know it (--exposure STOPS, log2 of the factor from the "
        "photograph's values to the "
        "scan's, 1 being the scan's clipping), or --force to write the layer anyway.";
    throw Error(msg);
  };
  auto linearLuminance = [](const Rgb& display) {
    return luminance(Rgb(linearFromDisplay(display.r), linearFromDisplay(display.g),
                         linearFromDisplay(display.b)));
  };
  // Registered: pairs where the scan renders in the photograph's own view (its coverage), never
  // the background the scan lacks.
  auto photoViewPairs = [&]() {
    const HdrImage ldr = renderings[0].image();
    std::vector<float> scanY, photoYs;
    for (size_t i = 0; i < ldr.pixels(); ++i) {
      if (!renderings[0].covered(i) || (!smallMask.empty() && !smallMask[i])) continue;
      scanY.push_back(
          linearLuminance(ldr.get(int(i % size_t(ldr.width)), int(i / size_t(ldr.width)))));
      photoYs.push_back(
          luminance(Rgb(small.rgb[3 * i], small.rgb[3 * i + 1], small.rgb[3 * i + 2])));
    }
    return estimateExposureFromPairs(scanY, photoYs, 0.02, o.overexposed, photoClip);
  };
  if (o.photoView && !o.log2Exposure) {
    t = Clock::now();
    const PairEstimate pe = photoViewPairs();
    recordPairs(pe);
    if (pe.usable) rep.log2Exposure = pe.log2Exposure;
    stopOnFailures(exposureFailures());
    rep.seconds["exposure"] = rep.seconds["exposure"].get<double>() + seconds(t);
  }

  // PatchMatch of each rendering against the exposed photograph (display values, as the scan's
  // camera recorded them), then the HDR mapping: the photograph's values at the matches.
  t = Clock::now();
  struct Expanded {
    HdrImage hdr;            // exposure * photo at the match (linear, LDR units)
    std::vector<float> ssd;  // +inf: no point, or match rejected
  };
  std::vector<Expanded> expanded(renderings.size());
  HdrImage exposedDisplay(small.width, small.height);
  // Pairs at the matches that pass t_h (and are not blind): the unregistered exposure's evidence.
  std::vector<float> matchScanY, matchPhotoY;
  // The photograph's pixels a point may take its value from: registered, where the scan renders in
  // the photograph's own view; with a mask, where the mask lets it count; both, both. Elsewhere
  // the photograph shows what the scan lacks (sky, a lamp beyond it). Empty: every pixel.
  std::vector<uint8_t> photoCoverage =
      o.photoView ? renderings[0].coverage() : std::vector<uint8_t>();
  if (!smallMask.empty()) {
    if (photoCoverage.empty()) {
      photoCoverage = smallMask;
    } else {
      for (size_t i = 0; i < photoCoverage.size(); ++i) photoCoverage[i] &= smallMask[i];
    }
  }
  auto explainedTarget = [&](glm::vec2 p) {
    // The fetch is bilinear: every pixel of its 2 x 2 footprint must be the scan's.
    const int x0 = std::clamp(int(std::floor(p.x)), 0, small.width - 1),
              y0 = std::clamp(int(std::floor(p.y)), 0, small.height - 1);
    const int x1 = std::min(x0 + 1, small.width - 1), y1 = std::min(y0 + 1, small.height - 1);
    auto at = [&](int x, int y) {
      return photoCoverage[size_t(y) * size_t(small.width) + size_t(x)] != 0;
    };
    return at(x0, y0) && at(x1, y0) && at(x0, y1) && at(x1, y1);
  };
  auto match = [&](float exposure) {
    rep.coveredPixels = rep.matchedPixels = rep.blindPixels = rep.backgroundPixels = 0;
    matchScanY.clear();
    matchPhotoY.clear();
    for (size_t i = 0; i < small.rgb.size(); ++i)
      exposedDisplay.rgb[i] = displayFromLinear(std::clamp(exposure * small.rgb[i], 0.0f, 1.0f));
    // Masked-out pixels far outside the display range: a patch touching one costs more than any
    // threshold, so PatchMatch looks for the region's match elsewhere instead of finding it there
    // and having it rejected afterwards.
    for (size_t i = 0; i < smallMask.size(); ++i)
      if (!smallMask[i]) exposedDisplay.rgb[3 * i] = exposedDisplay.rgb[3 * i + 1] = exposedDisplay.rgb[3 * i + 2] = kMaskedOut;
    for (size_t vi = 0; vi < renderings.size(); ++vi) {
      const HdrImage ldr = renderings[vi].image();
      const std::vector<uint8_t> mask = renderings[vi].coverage();
      PatchMatchOptions pm;
      pm.patchRadius = o.patchRadius;
      pm.iterations = o.patchIterations;
      pm.seed = 1 + vi;
      pm.identityStart = o.photoView && vi == 0;
      if (pm.identityStart) {
        // Registered: rendered at the photograph's size from its camera, so no rotation or scale,
        // and matches only move locally (misregistration, the renderings' splats).
        pm.rotation = false;
        pm.minScale = pm.maxScale = 1.0f;
        pm.searchRadius = float(o.photoSearchRadius);  // 0: anywhere
      }
      const PatchMatchField field = generalizedPatchMatch(ldr, exposedDisplay, pm, &mask);
      Expanded& e = expanded[vi];
      e.hdr = fetch(field, small);
      for (float& v : e.hdr.rgb) v = std::isfinite(v) ? std::max(0.0f, v * exposure) : 0.0f;
      e.ssd = field.ssd;
      const std::vector<uint8_t> blind =
          pm.identityStart || !o.rejectBlindPatches
              ? std::vector<uint8_t>()
              : blindPatches(ldr, mask, o.patchRadius, o.overexposed);
      for (size_t i = 0; i < e.ssd.size(); ++i) {
        if (!mask[i]) {
          e.ssd[i] = INFINITY;
          continue;
        }
        if (!blind.empty() && blind[i]) {
          rep.blindPixels++;
          e.ssd[i] = INFINITY;
          continue;
        }
        if (!photoCoverage.empty() && e.ssd[i] <= o.maxSsd && !explainedTarget(field.position[i])) {
          rep.backgroundPixels++;
          e.ssd[i] = INFINITY;
          continue;
        }
        rep.coveredPixels++;
        if (e.ssd[i] <= o.maxSsd) {
          rep.matchedPixels++;
          if (!o.photoView) {
            const int x = int(i % size_t(ldr.width)), y = int(i / size_t(ldr.width));
            matchScanY.push_back(linearLuminance(ldr.get(x, y)));
            matchPhotoY.push_back(luminance(e.hdr.get(x, y)) / exposure);
          }
        } else {
          e.ssd[i] = INFINITY;
        }
      }
      if (!o.debugDir.empty()) {
        fs::create_directories(o.debugDir);
        const std::string stem = (o.debugDir / rep.views[vi].name).string();
        writeExr(stem + "-ldr.exr", ldr);
        writeExr(stem + "-hdr.exr", e.hdr);
      }
      progress("patchmatch", double(vi + 1) / double(renderings.size()));
    }
  };
  match(float(std::exp2(rep.log2Exposure)));
  if (!o.photoView && !o.log2Exposure) {
    // Unregistered: the exposure from the matches that pass t_h. When it moves the histogram's
    // answer by more than half a stop, the matching is repeated once at the new exposure (the
    // matches were made against a photograph exposed wrongly, so they are fewer and poorer).
    PairEstimate pe =
        estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip);
    if (pe.usable && pe.pairs >= o.minPairs &&
        std::fabs(pe.log2Exposure - rep.log2Exposure) > 0.5) {
      rep.log2Exposure = pe.log2Exposure;
      checks.rematches++;
      match(float(std::exp2(rep.log2Exposure)));
      pe = estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip);
    }
    recordPairs(pe);
    if (pe.usable && pe.pairs >= o.minPairs) {
      // The values fetched at the matches scale with the exposure: rescale rather than match again.
      const float k = float(std::exp2(pe.log2Exposure - rep.log2Exposure));
      for (auto& e : expanded)
        for (float& v : e.hdr.rgb) v *= k;
      rep.log2Exposure = pe.log2Exposure;
    }
    stopOnFailures(exposureFailures());
  } else if (o.log2Exposure) {
    // Forced: measured for the record at the registered view's coverage or at the matches.
    if (o.photoView) {
      recordPairs(photoViewPairs());
    } else {
      recordPairs(
          estimateExposureFromPairs(matchScanY, matchPhotoY, 0.02, o.overexposed, photoClip));
    }
  }
  const float exposure = float(std::exp2(rep.log2Exposure));
  if (!o.photoView && o.maxLocalRatio > 0) {
    // Unregistered, a clipped patch whose unclipped rim resembles a light's glow matches that
    // light (a lamp the scan lacks: its exposed core is as white as the clipped floor) and fetches
    // hundreds of times the clipping, where the clipped region around it fetched a few times it.
    // A clipped surface's radiance is smooth next to its neighbours' matches; a value far above
    // the median of the matched values around it is a stray match, and the in-fill would spread
    // it. Measured with the lamp in the frame but not in the scan: values up to 370 times the
    // clipping beside floor matches of 2 to 4 made the layer 2.66 against the LDR colour's 0.71
    // (0.31 rejected). A light the scan has loses its rim matches the same way and is in-filled.
    const int r = o.localRadius;
    for (size_t vi = 0; vi < renderings.size(); ++vi) {
      Expanded& e = expanded[vi];
      const int w = e.hdr.width, h = e.hdr.height;
      std::vector<float> y(size_t(w) * size_t(h), -1.0f);
      for (size_t i = 0; i < y.size(); ++i)
        if (std::isfinite(e.ssd[i]))
          y[i] = luminance(e.hdr.get(int(i % size_t(w)), int(i / size_t(w))));
      std::vector<float> window;
      for (int py = 0; py < h; ++py)
        for (int px = 0; px < w; ++px) {
          const size_t i = size_t(py) * size_t(w) + size_t(px);
          if (y[i] <= 1.0f) continue;  // within the clipping: nothing expanded
          window.clear();
          for (int dy = -r; dy <= r; ++dy)
            for (int dx = -r; dx <= r; ++dx) {
              const int qx = px + dx, qy = py + dy;
              if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
              if (const float v = y[size_t(qy) * size_t(w) + size_t(qx)]; v >= 0)
                window.push_back(v);
            }
          std::nth_element(window.begin(), window.begin() + std::ptrdiff_t(window.size() / 2),
                           window.end());
          if (y[i] > float(o.maxLocalRatio) * std::max(1.0f, window[window.size() / 2])) {
            e.ssd[i] = INFINITY;
            rep.strayPixels++;
          }
        }
    }
  }
  // The bound of the layer's values: the photograph's largest value times the exposure; where it
  // is registered, its largest where the scan renders (what lies beyond, a lamp the scan lacks,
  // is no point's value).
  double explainedMax = photoMax;
  if (!photoCoverage.empty()) {
    explainedMax = 0;
    for (size_t i = 0; i < small.pixels(); ++i)
      if (photoCoverage[i])
        for (int k = 0; k < 3; ++k)
          if (const float v = small.rgb[3 * i + size_t(k)]; std::isfinite(v))
            explainedMax = std::max(explainedMax, double(v));
  }
  checks.bound = std::max(1.0, double(exposure) * explainedMax);
  if (!o.debugDir.empty()) {
    writeExr((o.debugDir / "photo-exposed.exr").string(), exposedDisplay);
    writeViews(o.debugDir / "views.json", rep.views);
  }
  rep.seconds["patchmatch"] = seconds(t);

  // Pass C: back-projection into the scratch file.
  t = Clock::now();
  const fs::path scratchPath =
      (o.scratchDir.empty() ? dir : o.scratchDir) / (o.layerName + ".expand.scratch");
  Scratch scratch(scratchPath, rep.points);
  std::atomic<uint64_t> projected{0}, unseen{0}, rejected{0}, targets{0};
  nodesDone = 0;
  tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
    const auto& [key, entry] = nodes[ni];
    if (entry.numPoints == 0) return;
    const ScanNode n = scan.read(key, entry);
    std::vector<ScratchRecord> out(n.world.size());
    std::vector<std::pair<glm::dvec3, double>> candidates;
    uint64_t p = 0, u = 0, r = 0;
    for (size_t i = 0; i < n.world.size(); ++i) {
      const glm::vec3 l = n.ldr[i];
      ScratchRecord& rec = out[i];
      rec.rgb[0] = l.r, rec.rgb[1] = l.g, rec.rgb[2] = l.b;
      rec.state = kKept;
      const double y = luminance(l);
      if (!(y > o.overexposed)) continue;
      double weights = 0;
      bool seen = false;
      candidates.clear();
      for (size_t vi = 0; vi < renderings.size(); ++vi) {
        // The photograph's own view decides alone for the points it matched.
        if (vi == 1 && o.photoView && !candidates.empty()) break;
        const View& v = renderings[vi].view;
        glm::dvec2 px;
        double d;
        if (!v.project(n.world[i], px, d)) continue;
        const int x = int(std::floor(px.x)), yy = int(std::floor(px.y));
        if (x < 0 || yy < 0 || x >= v.width || yy >= v.height) continue;
        const size_t pi = size_t(yy) * size_t(v.width) + size_t(x);
        // Visible when no splat lies clearly in front: splats are a node spacing across.
        if (d > double(renderings[vi].depth(pi)) + 2.0 * n.spacing + 1e-3 * d) continue;
        seen = true;
        const float ssd = expanded[vi].ssd[pi];
        if (!std::isfinite(ssd)) continue;
        const Rgb h = expanded[vi].hdr.get(x, yy);
        glm::dvec3 c;
        if (o.mode == ExpansionMode::Rgb) {
          c = glm::dvec3(h);
        } else {
          c = glm::dvec3(l) * (double(luminance(h)) / y);
        }
        // The quality field weights candidates: low SSD, high weight.
        const double w = 1.0 / (double(ssd) + 1e-3);
        weights += w;
        candidates.push_back({c, w});
      }
      if (weights > 0) {
        // The weighted median (by luminance) of the views' candidates, where the paper takes the
        // weighted mean. Inside a clipped region every white patch of the photograph matches
        // with SSD 0, so one view may fetch the lamp's values for a sunlit floor; the mean keeps
        // a share of that outlier, the median drops it. Measured on the ground-truth protocol
        // (300k points, 2 cube maps): cloud RMS on the clipped sunlit floor 134 -> 56, on the
        // window wall 151 -> 5.7 (docs/HDR.md).
        std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
          return luminance(Rgb(a.first)) < luminance(Rgb(b.first));
        });
        glm::dvec3 c = candidates.back().first;
        double below = 0;
        for (const auto& [cand, w] : candidates)
          if ((below += w) >= 0.5 * weights) {
            c = cand;
            break;
          }
        rec.rgb[0] = float(c.x), rec.rgb[1] = float(c.y), rec.rgb[2] = float(c.z);
        rec.state = kProjected;
        p++;
      } else {
        rec.state = kTarget;
        (seen ? r : u)++;
      }
    }
    scratch.write(base[ni], out);
    projected += p, unseen += u, rejected += r, targets += u + r;
    progress("back-projection", double(++nodesDone) / double(nodes.size()));
  });
  rep.projected = projected, rep.unseen = unseen, rep.rejectedMatches = rejected;
  if (rep.overexposed > 0) {
    // Few matched points and many to in-fill: the in-fill would carry a handful of values (right
    // or wrong) over the whole clipped range.
    checks.matchedShare = double(rep.projected) / double(rep.overexposed);
    if (checks.matchedShare < o.minMatchedShare) {
      char buf[400];
      std::snprintf(
          buf, sizeof buf,
          "only %.1f%% of the over-exposed points (%llu of %llu) took a value from the photograph "
          "(at least %.1f%%): the rest would be in-filled from them",
          100 * checks.matchedShare, (unsigned long long)rep.projected,
          (unsigned long long)rep.overexposed, 100 * o.minMatchedShare);
      stopOnFailures({buf});
    }
  }
  renderings.clear();
  expanded.clear();
  rep.seconds["back_projection"] = seconds(t);

  // Pass D: the in-fill (eq. 3), chunk by chunk. Chunks tile the octree's cube adaptively: a
  // cube is split while its points (its subtree's, plus its share of its ancestors') exceed the
  // budget. Only chunks holding points to in-fill are solved.
  t = Clock::now();
  if (targets > 0) {
    std::unordered_map<NodeKey, uint64_t, NodeKeyHash> subtree;
    for (const auto& [key, e] : nodes)
      for (NodeKey k = key;; k = k.parent()) {
        subtree[k] += e.numPoints;
        if (k.level == 0) break;
      }
    auto estimate = [&](const NodeKey& c) {
      double s = 0;
      if (auto it = subtree.find(c); it != subtree.end()) s = double(it->second);
      for (uint32_t l = 0; l < c.level; ++l) {
        auto it = nodeIndex.find(c.ancestor(l));
        if (it != nodeIndex.end())
          s += double(nodes[it->second].second.numPoints) / std::pow(8.0, c.level - l);
      }
      return s;
    };
    std::unordered_set<NodeKey, NodeKeyHash> cells;
    std::vector<NodeKey> stack{NodeKey::root()};
    while (!stack.empty()) {
      const NodeKey c = stack.back();
      stack.pop_back();
      if (estimate(c) > double(o.chunkPoints) && c.level < meta.depth && subtree.count(c)) {
        for (int i = 0; i < 8; ++i) stack.push_back(c.child(i));
      } else {
        cells.insert(c);
      }
    }
    // Which cells hold points to in-fill.
    auto cellOf = [&](const uint32_t* q) {
      for (uint32_t l = 0;; ++l) {
        const uint32_t s = meta.cubeSize >> l;
        const NodeKey k{l, q[0] / s, q[1] / s, q[2] / s};
        if (cells.count(k) || l >= 31) return k;
      }
    };
    std::unordered_map<NodeKey, uint64_t, NodeKeyHash> cellTargets;
    for (size_t ni = 0; ni < nodes.size(); ++ni) {
      if (nodes[ni].second.numPoints == 0) continue;
      std::vector<ScratchRecord> recs;
      scratch.read(base[ni], nodes[ni].second.numPoints, recs);
      bool any = false;
      for (const auto& r : recs) any = any || r.state == kTarget;
      if (!any) continue;
      const PointBuffer pts = reader.readNode(nodes[ni].first);
      for (size_t i = 0; i < recs.size(); ++i)
        if (recs[i].state == kTarget) cellTargets[cellOf(&pts.pos[3 * i])]++;
    }
    std::vector<NodeKey> todo;
    for (const auto& [k, n] : cellTargets) todo.push_back(k);
    std::sort(todo.begin(), todo.end());
    const double finest = meta.levelSpacing(meta.depth);
    InfillOptions io;
    io.k = o.neighbours;
    io.mode = o.mode == ExpansionMode::Rgb ? InfillMode::Rgb : InfillMode::Luminance;
    for (size_t ci = 0; ci < todo.size(); ++ci) {
      const NodeKey cell = todo[ci];
      const Box3d cube = meta.nodeBounds(cell.level, cell.x, cell.y, cell.z);
      const double margin = std::max(0.1 * (cube.max.x - cube.min.x), 16.0 * finest);
      Box3d box = cube;
      box.min = {cube.min.x - margin, cube.min.y - margin, cube.min.z - margin};
      box.max = {cube.max.x + margin, cube.max.y + margin, cube.max.z + margin};
      const glm::dvec3 origin{(cube.min.x + cube.max.x) / 2, (cube.min.y + cube.max.y) / 2,
                              (cube.min.z + cube.max.z) / 2};
      // Gather every point in the box, from every node whose cube meets it.
      std::vector<glm::vec3> pos, ldr, hdr;
      std::vector<InfillRole> role;
      struct Origin {
        uint32_t node;
        uint32_t index;
        bool core;
      };
      std::vector<Origin> from;
      for (size_t ni = 0; ni < nodes.size(); ++ni) {
        const auto& [key, entry] = nodes[ni];
        if (entry.numPoints == 0) continue;
        const Box3d nb = meta.nodeBounds(key.level, key.x, key.y, key.z);
        if (nb.min.x > box.max.x || nb.max.x < box.min.x || nb.min.y > box.max.y ||
            nb.max.y < box.min.y || nb.min.z > box.max.z || nb.max.z < box.min.z)
          continue;
        const ScanNode n = scan.read(key, entry);
        std::vector<ScratchRecord> recs;
        scratch.read(base[ni], n.world.size(), recs);
        for (size_t i = 0; i < n.world.size(); ++i) {
          const glm::dvec3& w = n.world[i];
          if (w.x < box.min.x || w.x > box.max.x || w.y < box.min.y || w.y > box.max.y ||
              w.z < box.min.z || w.z > box.max.z)
            continue;
          const bool core = w.x >= cube.min.x && w.x < cube.max.x && w.y >= cube.min.y &&
                            w.y < cube.max.y && w.z >= cube.min.z && w.z < cube.max.z;
          pos.push_back(glm::vec3(w - origin));
          ldr.push_back(n.ldr[i]);
          hdr.push_back({recs[i].rgb[0], recs[i].rgb[1], recs[i].rgb[2]});
          role.push_back(recs[i].state == kTarget ? InfillRole::Target : InfillRole::Fixed);
          from.push_back({uint32_t(ni), uint32_t(i), core});
        }
      }
      rep.chunks++;
      rep.chunkMaxPoints = std::max<uint64_t>(rep.chunkMaxPoints, pos.size());
      std::vector<InfillOutcome> outcome;
      const InfillStats st = poissonInfill(pos, ldr, hdr, role, io, &outcome);
      rep.cgIterationsMax = std::max<uint64_t>(rep.cgIterationsMax, st.cgIterations);
      // Write back the core's solved points, node by node.
      std::unordered_map<uint32_t, std::vector<size_t>> byNode;
      for (size_t i = 0; i < from.size(); ++i)
        if (from[i].core && role[i] == InfillRole::Target) byNode[from[i].node].push_back(i);
      for (auto& [ni, list] : byNode) {
        std::vector<ScratchRecord> recs;
        scratch.read(base[ni], nodes[ni].second.numPoints, recs);
        for (size_t i : list) {
          ScratchRecord& r = recs[from[i].index];
          r.rgb[0] = hdr[i].r, r.rgb[1] = hdr[i].g, r.rgb[2] = hdr[i].b;
          if (outcome[i] == InfillOutcome::Island) {
            r.state = kIsland;
            rep.islandPoints++;
          } else {
            r.state = kInfilled;
            rep.infilled++;
          }
        }
        scratch.write(base[ni], recs);
      }
      rep.islands += st.islands;  // components, counted per chunk (one may span two chunks)
      progress("in-fill", double(ci + 1) / double(todo.size()));
    }
  }
  rep.seconds["infill"] = seconds(t);

  // Pass E: the layer.
  t = Clock::now();
  if (o.writeLayer) {
    std::atomic<uint64_t> maxBits{0};
    // Nothing written exceeds what the photograph recorded (times the exposure): the in-fill's
    // gradients can carry a few matched values far beyond it.
    const float bound = float(checks.bound);
    std::atomic<uint64_t> bounded{0};
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
      std::vector<ScratchRecord> recs;
      scratch.read(base[ni], nodes[ni].second.numPoints, recs);
      float m = 0;
      uint64_t nb = 0;
      for (const auto& r : recs)
        for (int c = 0; c < 3; ++c) {
          nb += r.rgb[c] > bound;
          m = std::max(m, std::min(r.rgb[c], bound));
        }
      bounded += nb;
      uint32_t bits;
      std::memcpy(&bits, &m, 4);
      uint64_t cur = maxBits.load();
      while (bits > cur && !maxBits.compare_exchange_weak(cur, bits)) {
      }
    });
    const uint32_t bits = uint32_t(maxBits.load());
    float maxValue;
    std::memcpy(&maxValue, &bits, 4);
    rep.maxValue = maxValue;
    rep.boundedValues = bounded;
    // Half floats end at 65504: a scale keeps larger values (dynamic ranges beyond 1e5 of 1).
    const double scale = std::max(1.0, double(maxValue) / 60000.0);
    ColourLayerWriter writer(dir, o.layerName, scale);
    nodesDone = 0;
    tbb::parallel_for(size_t(0), nodes.size(), [&](size_t ni) {
      std::vector<ScratchRecord> recs;
      scratch.read(base[ni], nodes[ni].second.numPoints, recs);
      std::vector<float> rgb(recs.size() * 3);
      for (size_t i = 0; i < recs.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[3 * i + size_t(c)] = std::min(recs[i].rgb[c], bound);
      writer.writeNode(nodes[ni].first, rgb.data(), recs.size());
      progress("write layer", double(++nodesDone) / double(nodes.size()));
    });
    rep.seconds["write_layer"] = seconds(t);
    rep.seconds["total"] = seconds(t0);
    rep.peakRssBytes = peakRssBytes();
    rep.clampedValues = writer.clampedValues();
    json build = rep.toJson();
    build["mode"] = expansionModeName(o.mode);
    build["overexposed_threshold"] = o.overexposed;
    build["max_ssd"] = o.maxSsd;
    build["neighbours"] = o.neighbours;
    build["exposure_log2"] = rep.log2Exposure;
    if (!o.commandLine.is_null()) build["command"] = o.commandLine;
    writer.finish(build);
  }
  rep.seconds["total"] = seconds(t0);
  rep.peakRssBytes = peakRssBytes();
  return rep;
}

}  // namespace nestlight::gi::hdr
