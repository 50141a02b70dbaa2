// Scan points as oriented discs, meshes as triangles, in one Embree 3 scene (Embree's
// RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT and RTC_GEOMETRY_TYPE_TRIANGLE). Disc radii follow local
// point spacing (issue 4; the surfel view of points of paper 004 section 6).
#include "nestlight/gi/shared/reference_scene.h"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nanoflann.hpp>
#include <tuple>

#include "nestlight/gi/scan_colour.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi {
namespace {

constexpr size_t kBytesPerDisc =
    sizeof(glm::vec4) + sizeof(glm::vec3) + sizeof(Rgb) + sizeof(float);
constexpr int kRadiusNeighbours = 8;
// Discs must close an evenly sampled surface, or rays leak through it and the reference renders
// too dark (a Poisson-disk sampled room: 1 to 3% darker than the same room as meshes, up to 8% on
// walls in albedo mode). A maximal Poisson-disk sample with minimum distance r leaves no surface
// point farther than r from a sample (else one more sample would fit), so discs of radius r close
// it. Its density is about 0.7 / r^2 (random close packing of the r/2 exclusion discs covers
// ~55% of the plane), so 9 samples (a point and its 8 neighbours) fill a disc of radius
// sqrt(9 / (0.7 pi)) r = 2.0 r on average and half the 8th-neighbour distance is about r; it is
// less where the neighbours crowd, and gaps open there. On a square grid of step a the covering
// radius is a / sqrt(2), exactly half the 8th-neighbour distance. A factor of 1.5 on half the
// 8th-neighbour distance leaves a margin of 50% over both (the test
// `Reference.ClosedPoissonSampledBoxLeaksNoRay` checks the Poisson-disk case and that the old
// factor leaks); the cost is overlap, which discs that share a plane do not see.
constexpr float kDiscCoverage = 1.5f;

struct DiscAdaptor {
  const std::vector<glm::vec4>& d;
  size_t kdtree_get_point_count() const { return d.size(); }
  float kdtree_get_pt(size_t i, size_t dim) const { return d[i][int(dim)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using DiscTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, DiscAdaptor>,
                                        DiscAdaptor, 3, uint32_t>;

// Distinct positions of `discs` (a k-d tree's queries turn quadratic on a leaf of identical
// points), which one each disc is, and the first disc at each.
struct DistinctPositions {
  std::vector<glm::vec4> unique;
  std::vector<uint32_t> uniqueOf, firstOf;
};
DistinctPositions distinctPositions(const std::vector<glm::vec4>& discs) {
  std::vector<uint32_t> order(discs.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  auto key = [&](uint32_t i) { return std::tuple(discs[i].x, discs[i].y, discs[i].z); };
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  DistinctPositions d;
  d.uniqueOf.resize(discs.size());
  for (size_t j = 0; j < order.size(); ++j) {
    if (j == 0 || key(order[j]) != key(order[j - 1]))
      d.unique.push_back(discs[order[j]]), d.firstOf.push_back(order[j]);
    d.uniqueOf[order[j]] = uint32_t(d.unique.size() - 1);
  }
  return d;
}

void embreeError(void*, RTCError code, const char* message) {
  // Embree reports misuse here; it is a programming error (bad buffers), never user input.
  nestlight::checkFailed(
      "Embree", __FILE__, __LINE__,
      std::string("error ") + std::to_string(int(code)) + ": " + (message ? message : ""));
}

}  // namespace

void assignDiscRadii(std::vector<glm::vec4>& discs, float radiusScale,
                     const std::vector<float>* maxRadius) {
  NL_CHECK(!maxRadius || maxRadius->size() == discs.size());
  if (discs.empty()) return;
  // Spacing is measured between distinct positions: coincident copies (merged scans, a
  // million duplicates) neither shrink their neighbours' discs nor degrade the k-d tree.
  DistinctPositions distinct = distinctPositions(discs);
  std::vector<glm::vec4>& unique = distinct.unique;
  const std::vector<uint32_t>& uniqueOf = distinct.uniqueOf;
  DiscAdaptor adaptor{unique};
  DiscTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const size_t k = std::min<size_t>(kRadiusNeighbours + 1, unique.size());  // +1: the point itself
  tbb::parallel_for(tbb::blocked_range<size_t>(0, unique.size(), 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      std::vector<uint32_t> idx(k);
                      std::vector<float> d2(k);
                      for (size_t i = r.begin(); i < r.end(); ++i) {
                        float q[3] = {unique[i].x, unique[i].y, unique[i].z};
                        size_t found = tree.knnSearch(q, k, idx.data(), d2.data());
                        float dk = found > 1 ? std::sqrt(d2[found - 1]) : 0.0f;
                        unique[i].w = radiusScale * kDiscCoverage * 0.5f * dk;
                      }
                    });
  for (size_t i = 0; i < discs.size(); ++i) {
    discs[i].w = unique[uniqueOf[i]].w;
    if (maxRadius) discs[i].w = std::min(discs[i].w, (*maxRadius)[i]);
  }
}

void assignDiscThickness(DiscCloud& c) {
  c.thickness.clear();
  if (c.normals.empty() || c.discs.empty()) return;
  NL_CHECK(c.normals.size() == c.discs.size());
  c.thickness.assign(c.discs.size(), 0.0f);
  // Neighbours are distinct positions (each stands for the first disc there), as for radii.
  const DistinctPositions distinct = distinctPositions(c.discs);
  DiscAdaptor adaptor{distinct.unique};
  DiscTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const size_t k = std::min<size_t>(kRadiusNeighbours + 1, distinct.unique.size());
  // Neighbours further than 30 degrees off belong to another surface (a crease, a thin wall's
  // far side): their extent is geometry, not noise.
  const float sameSurface = 0.8660254f;  // cos 30 degrees
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, c.discs.size(), 4096),
      [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint32_t> idx(k);
        std::vector<float> d2(k);
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const glm::vec3 p(c.discs[i]), n = c.normals[i];
          float q[3] = {p.x, p.y, p.z};
          size_t found = tree.knnSearch(q, k, idx.data(), d2.data());
          // Heights above (+) and below (-) the plane, as sums for mean and variance.
          double s[2] = {0, 0}, s2[2] = {0, 0};
          int m = 0;
          for (size_t jj = 0; jj < found; ++jj) {
            if (idx[jj] == distinct.uniqueOf[i]) continue;
            const uint32_t j = distinct.firstOf[idx[jj]];
            const glm::vec3 nj = c.normals[j];
            float cosA = glm::dot(nj, n);
            if (cosA < sameSurface) continue;
            float along = glm::dot(glm::vec3(c.discs[j]) - p, n);
            float reach = c.discs[j].w * std::sqrt(std::max(0.0f, 1 - cosA * cosA));
            float h[2] = {along + reach, -along + reach};
            for (int side = 0; side < 2; ++side)
              s[side] += h[side], s2[side] += double(h[side]) * h[side];
            ++m;
          }
          if (m < 2) continue;  // isolated: nothing of its own surface around to shadow it
          float t = 0;
          for (int side = 0; side < 2; ++side) {
            double mean = s[side] / m, var = std::max(0.0, s2[side] / m - mean * mean);
            t = std::max(t, float(mean + 3 * std::sqrt(var)));
          }
          float cap = c.discs[i].w;
          c.thickness[i] =
              std::isfinite(t)
                  ? std::clamp(t, 0.0f, std::isfinite(cap) ? std::max(cap, 0.0f) : 0.0f)
                  : 0.0f;
        }
      });
}

DiscCloud loadDiscCloud(const SceneOctree& octree, const glm::dvec3& origin,
                        DiscCloudStats* statsOut) {
  OctreeReader reader(octree.path);
  const Metadata& meta = reader.metadata();
  DiscCloudStats stats;
  stats.octreeDepth = int(meta.depth);
  auto nodes = reader.allNodes();  // breadth first
  // Points per level, to pick the deepest level that fits the budget.
  std::vector<uint64_t> perLevel(meta.depth + 1, 0);
  for (auto& [key, e] : nodes)
    if (key.level <= meta.depth) perLevel[key.level] += e.numPoints;
  int wanted = octree.maxLevel ? std::min<int>(*octree.maxLevel, int(meta.depth)) : int(meta.depth);
  int level = -1;
  uint64_t total = 0;
  for (int l = 0; l <= wanted; ++l) {
    if ((total + perLevel[l]) * kBytesPerDisc > octree.memoryBudget) {
      stats.limitedByBudget = true;
      break;
    }
    total += perLevel[l];
    level = l;
  }
  if (level < 0)
    throw Error(octree.path.string(), "",
                "the root node's " + std::to_string(perLevel[0]) +
                    " points do not fit the memory budget of " +
                    std::to_string(octree.memoryBudget) + " bytes");
  stats.deepestLevel = level;
  const ScanColours colours(octree.path, meta, octree.colour);
  std::vector<float> rgb;
  const int normal = meta.layout.find(attr::kNormal);
  const size_t nOff = normal >= 0 ? meta.layout.offset(normal) : 0;
  DiscCloud cloud;
  cloud.discs.reserve(total);
  cloud.colour.reserve(total);
  if (normal >= 0) cloud.normals.reserve(total);
  const glm::dvec3 base = glm::dvec3(meta.offset.x, meta.offset.y, meta.offset.z) - origin;
  std::vector<float> maxRadius;
  maxRadius.reserve(total);
  for (auto& [key, e] : nodes) {
    if (int(key.level) > level || e.numPoints == 0) continue;
    PointBuffer pts = reader.readNode(key);
    colours.linear(key, pts, rgb);
    stats.nodes++;
    // A node's sample keeps points at least its spacing apart, so it leaves no surface point
    // farther than that from a sample: no disc needs to be wider (with the same margin).
    const float nodeSpacing =
        float(meta.levelSpacing(key.level)) * octree.radiusScale * kDiscCoverage;
    for (size_t i = 0; i < pts.size(); ++i) {
      const uint32_t* p = &pts.pos[3 * i];
      glm::dvec3 local = base + glm::dvec3(p[0], p[1], p[2]) *
                                    glm::dvec3(meta.scale.x, meta.scale.y, meta.scale.z);
      cloud.discs.emplace_back(glm::vec3(local), 0.0f);
      maxRadius.push_back(nodeSpacing);
      const uint8_t* a = pts.attrsOf(i);
      cloud.colour.push_back(Rgb(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]) * octree.colourScale);
      if (normal >= 0) {
        glm::vec3 n;
        std::memcpy(&n, a + nOff, 12);
        float len = glm::length(n);
        cloud.normals.push_back(len > 0 && std::isfinite(len) ? n / len : glm::vec3(0, 0, 1));
      }
    }
  }
  assignDiscRadii(cloud.discs, octree.radiusScale, &maxRadius);
  stats.points = cloud.discs.size();
  stats.bytes = stats.points * kBytesPerDisc;
  for (const auto& d : cloud.discs) stats.zeroRadius += d.w <= 0;
  if (statsOut) *statsOut = stats;
  return cloud;
}

struct ReferenceScene::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

std::unique_ptr<ReferenceScene> ReferenceScene::load(const Scene& scene,
                                                     void (*log)(const std::string&)) {
  std::vector<DiscCloud> clouds;
  std::vector<DiscCloudStats> stats;
  for (const auto& o : scene.octrees) {
    DiscCloudStats st;
    clouds.push_back(loadDiscCloud(o, scene.origin, &st));
    stats.push_back(st);
    if (log) {
      std::string line = o.path.string() + ": " + std::to_string(st.points) +
                         " discs from levels 0-" + std::to_string(st.deepestLevel) + " of 0-" +
                         std::to_string(st.octreeDepth);
      if (st.limitedByBudget) line += " (memory budget)";
      if (clouds.back().normals.empty())
        line += "; no normals: discs face each ray (convert with --estimate-normals)";
      if (st.zeroRadius)
        line += "; " + std::to_string(st.zeroRadius) + " coincident points get no extent";
      log(line);
    }
  }
  std::vector<TriangleMesh> meshes;
  std::vector<uint32_t> meshMaterial;
  std::vector<MeshReadReport> reports;
  for (const auto& m : scene.meshes) {
    MeshReadReport report;
    TriangleMesh mesh = readMesh(m.path.string(), &report);
    glm::mat4 localFromObject = scene.localFromObject(m);
    glm::mat3 normalFrom = glm::transpose(glm::inverse(glm::mat3(localFromObject)));
    for (auto& p : mesh.positions) p = glm::vec3(localFromObject * glm::vec4(p, 1.0f));
    for (auto& n : mesh.normals) {
      n = normalFrom * n;
      float len = glm::length(n);
      n = len > 0 ? n / len : glm::vec3(0, 0, 1);
    }
    if (log) {
      log(m.path.string() + ": " + std::to_string(mesh.triangles()) + " triangles" +
          (report.degenerateDropped
               ? " (" + std::to_string(report.degenerateDropped) + " degenerate dropped)"
               : ""));
      for (const auto& w : report.warnings) log(m.path.string() + ": warning: " + w);
    }
    meshes.push_back(std::move(mesh));
    meshMaterial.push_back(m.material);
    reports.push_back(report);
  }
  EnvironmentMap env;
  if (scene.environment) {
    const auto& e = *scene.environment;
    if (e.constant) {
      env = EnvironmentMap::constant(*e.constant * e.scale);
    } else {
      env = loadEnvironmentAt(e);
      if (log) {
        std::string line = (e.sequence.empty() ? e.path : e.sequence).string() + ": environment " +
                           std::to_string(env.image().width) + "x" +
                           std::to_string(env.image().height);
        if (env.invalidTexels())
          line += "; " + std::to_string(env.invalidTexels()) +
                  " non-finite or negative texels set to 0";
        if (env.black()) line += "; all black: it adds no light";
        log(line);
      }
    }
  }
  auto rs = std::make_unique<ReferenceScene>(std::move(clouds), std::move(meshes),
                                             std::move(meshMaterial), scene.materials, scene.lights,
                                             std::move(env), scene.origin);
  rs->cloudStats_ = std::move(stats);
  rs->meshReports_ = std::move(reports);
  return rs;
}

ReferenceScene::ReferenceScene(std::vector<DiscCloud> clouds, std::vector<TriangleMesh> meshes,
                               std::vector<uint32_t> meshMaterial, std::vector<Material> materials,
                               std::vector<Light> lights, EnvironmentMap environment,
                               glm::dvec3 origin)
    : clouds_(std::move(clouds)),
      meshes_(std::move(meshes)),
      meshMaterial_(std::move(meshMaterial)),
      materials_(std::move(materials)),
      lights_(std::move(lights)),
      environment_(std::make_shared<const EnvironmentMap>(std::move(environment))),
      origin_(origin) {
  NL_CHECK(meshMaterial_.size() == meshes_.size());
  for (uint32_t m : meshMaterial_) NL_CHECK(m < materials_.size());
  build();
}

ReferenceScene::~ReferenceScene() = default;

void ReferenceScene::build() {
  rtc_ = std::make_unique<Embree>();
  rtc_->device = rtcNewDevice(nullptr);
  if (!rtc_->device)
    throw Error("Embree: cannot create a device (error " +
                std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
  rtcSetDeviceErrorFunction(rtc_->device, embreeError, nullptr);
  rtc_->scene = rtcNewScene(rtc_->device);
  rtcSetSceneBuildQuality(rtc_->scene, RTC_BUILD_QUALITY_HIGH);
  float maxCoord = 0;
  for (uint32_t ci = 0; ci < clouds_.size(); ++ci) {
    DiscCloud& c = clouds_[ci];
    NL_CHECK(c.colour.size() == c.discs.size());
    NL_CHECK(c.normals.empty() || c.normals.size() == c.discs.size());
    if (c.discs.empty()) continue;
    for (auto& d : c.discs) {
      if (!(d.w >= 0) || !std::isfinite(d.w)) d.w = 0;  // zero extent: never hit, never NaN
      maxCoord = std::max({maxCoord, std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    }
    bool oriented = !c.normals.empty();
    if (oriented && c.thickness.size() != c.discs.size()) assignDiscThickness(c);
    RTCGeometry g = rtcNewGeometry(rtc_->device, oriented ? RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT
                                                          : RTC_GEOMETRY_TYPE_DISC_POINT);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, c.discs.data(), 0,
                               sizeof(glm::vec4), c.discs.size());
    // Embree may read 16 bytes at the last FLOAT3 element: one element of padding.
    if (oriented) c.normals.reserve(c.normals.size() + 1);
    if (oriented)
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, c.normals.data(),
                                 0, sizeof(glm::vec3), c.normals.size());
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(rtc_->scene, g);
    rtcReleaseGeometry(g);
    if (geometry_.size() <= id) geometry_.resize(id + 1);
    geometry_[id] = {true, ci};
  }
  for (uint32_t mi = 0; mi < meshes_.size(); ++mi) {
    TriangleMesh& m = meshes_[mi];
    if (m.indices.empty()) continue;
    for (const auto& p : m.positions)
      maxCoord = std::max({maxCoord, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
    RTCGeometry g = rtcNewGeometry(rtc_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // Embree reads 16 bytes at the last vertex: the shared buffer gets one padding vertex.
    m.positions.reserve(m.positions.size() + 1);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m.positions.data(),
                               0, sizeof(glm::vec3), m.positions.size());
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m.indices.data(), 0,
                               3 * sizeof(uint32_t), m.triangles());
    rtcCommitGeometry(g);
    unsigned id = rtcAttachGeometry(rtc_->scene, g);
    rtcReleaseGeometry(g);
    if (geometry_.size() <= id) geometry_.resize(id + 1);
    geometry_[id] = {false, mi};
  }
  rtcCommitScene(rtc_->scene);
  extent_ = std::max(1.0f, maxCoord);
}

uint64_t ReferenceScene::discs() const {
  uint64_t n = 0;
  for (const auto& c : clouds_) n += c.discs.size();
  return n;
}

uint64_t ReferenceScene::triangles() const {
  uint64_t n = 0;
  for (const auto& m : meshes_) n += m.triangles();
  return n;
}

bool ReferenceScene::intersect(const glm::vec3& o, const glm::vec3& d, float tMax,
                               SurfaceHit* hit) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = o.x, rh.ray.org_y = o.y, rh.ray.org_z = o.z;
  rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
  rh.ray.tnear = 0;
  rh.ray.tfar = tMax;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.flags = 0;
  rh.ray.time = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(rtc_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
    hit->kind = SurfaceHit::Kind::None;
    return false;
  }
  auto [isCloud, index] = geometry_[rh.hit.geomID];
  hit->t = rh.ray.tfar;
  hit->position = o + d * rh.ray.tfar;
  glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
  float len = glm::length(ng);
  ng = len > 0 ? ng / len : -d;
  hit->geometricNormal = ng;
  hit->shadingNormal = ng;
  if (isCloud) {
    const DiscCloud& c = clouds_[index];
    hit->kind = SurfaceHit::Kind::Disc;
    hit->colour = c.colour[rh.hit.primID];
    hit->radius = c.discs[rh.hit.primID].w;
    hit->thickness = c.thickness.empty() ? 0.0f : c.thickness[rh.hit.primID];
    hit->orientedDisc = !c.normals.empty();
    hit->material = 0;
  } else {
    const TriangleMesh& m = meshes_[index];
    hit->kind = SurfaceHit::Kind::Triangle;
    hit->material = meshMaterial_[index];
    hit->radius = 0;
    const uint32_t* tri = &m.indices[3 * size_t(rh.hit.primID)];
    float u = rh.hit.u, v = rh.hit.v, w = 1 - u - v;
    if (!m.normals.empty()) {
      glm::vec3 n = w * m.normals[tri[0]] + u * m.normals[tri[1]] + v * m.normals[tri[2]];
      float nl = glm::length(n);
      if (nl > 0 && std::isfinite(nl)) hit->shadingNormal = n / nl;
    }
    hit->colour = m.colors.empty()
                      ? Rgb(1.0f)
                      : w * m.colors[tri[0]] + u * m.colors[tri[1]] + v * m.colors[tri[2]];
  }
  return true;
}

bool ReferenceScene::occluded(const glm::vec3& o, const glm::vec3& d, float tMax) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay ray;
  ray.org_x = o.x, ray.org_y = o.y, ray.org_z = o.z;
  ray.dir_x = d.x, ray.dir_y = d.y, ray.dir_z = d.z;
  ray.tnear = 0;
  ray.tfar = tMax;
  ray.mask = 0xFFFFFFFFu;
  ray.flags = 0;
  ray.time = 0;
  rtcOccluded1(rtc_->scene, &ctx, &ray);
  return ray.tfar < 0;  // Embree sets tfar to -inf on a hit
}

}  // namespace nestlight::gi
