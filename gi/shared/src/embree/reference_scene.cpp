// Scan points as oriented discs, meshes as triangles, in one Embree 3 scene (Embree's
// RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT and RTC_GEOMETRY_TYPE_TRIANGLE). Disc radii close the
// sampled surface whatever its sampling (issue 30): each disc covers its Voronoi cell in its
// tangent plane, the hole-free condition of splats (Zwicker, Pfister, van Baar, Gross, "Surface
// Splatting", 2001) met exactly rather than by a spacing estimate; the surfel view of points
// is paper 004 section 6.
#include "nestlight/gi/shared/reference_scene.h"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nanoflann.hpp>
#include <numbers>
#include <tuple>

#include "nestlight/gi/scan_colour.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::gi {
namespace {

constexpr size_t kBytesPerDisc =
    sizeof(glm::vec4) + sizeof(glm::vec3) + sizeof(Rgb) + sizeof(float);
// Neighbours of a disc's thickness, and the spacing that sizes a disc where its cell is open.
constexpr int kRadiusNeighbours = 8;
// Neighbours that bound a disc's cell: a Poisson-process sample's cells have 6 sides on average
// and up to about 12, which 24 neighbours hold except at a surface's boundary; a cell not
// settled with 24 is cut again with 48, then 96 (stripes of a scanner whose lines lie far
// apart).
constexpr size_t kCellNeighbours[] = {24, 48, 96};
// A neighbour belongs to the disc's surface when its normal is within 30 degrees of the disc's
// and it lies within 30 degrees of the disc's plane (seen from the disc's centre): 1 mm of scan
// noise at 1 cm spacing tilts neighbours by 8 degrees, a crease or a thin wall's far side by 90.
constexpr float kSameSurfaceCos = 0.8660254f, kSameSurfaceTan = 0.57735027f;
// Discs cover their cells with a margin: three discs meet at a point at each cell corner (float
// rounding decides there), and where neighbours sit off a disc's plane (scan noise, curvature)
// a ray crossing the seam between two discs at different heights passes under one and over the
// other unless they overlap by the height difference times the tangent of its angle. So the
// radius is 1.2 x the cell's plus 3 x the RMS height of the disc's neighbours over its plane
// (0 on a noiseless plane). Closed boxes of 60,000 random or striped points with 1 and 2 mm of
// noise at 1 cm spacing leak none of 200,000 rays with these; with 1.25 x the cell and no
// height term, 1 to 9 rays at 70 to 82 degrees of incidence leaked (docs/SCENE.md).
constexpr float kCellMargin = 1.2f, kHeightMargin = 3.0f;
// Where a disc's cell stays open (a surface's boundary, with nothing beyond to bound it), its
// radius is at least the rule of earlier versions: 1.5 times half the distance to the 8th
// nearest point, which closes evenly sampled surfaces (Poisson disk: no surface point farther
// than r from a sample, density about 0.7 / r^2, so half the 8th-neighbour distance is about
// r; a square grid of step a: covering radius a / sqrt(2), exactly half the 8th-neighbour
// distance; 1.5 leaves 50% over both).
constexpr float kDiscCoverage = 1.5f;
// No disc is wider than this many times the median 8th-neighbour distance of its neighbours: a
// cell at a surface's boundary reaches about 1.1 of them (the crease or the open rule), a
// scanner's stripes 3 times as far apart as their points about 0.5.
constexpr float kOutlierCap = 3.0f;
// For the cap a neighbour's 8th-neighbour distance is read as the octree's spacing is measured
// (octree/src/spacing.cpp): a point whose 8th neighbour lies more than this many times farther
// than its 2nd implies (on a surface r_k grows as sqrt(k)) sits in a bunch of a few returns (a
// bird, a flying pixel pair beside another), and its bunch's own neighbours measure it. Without
// it two bunches of 4 and 6 returns 0.4 m apart made each other's discs up to 0.49 m wide.
constexpr float kBunchFactor = 3.0f;
// A cell reaching farther than this many times the 8th-neighbour distance is open there: a
// boundary's Voronoi cell runs off the surface between two nearly parallel bisectors. Scanner
// stripes 20 times as far apart as their points still close within it.
constexpr float kOpenBound = 3.0f;
// A crease does not bound a surface whose own points lie beyond it by more than this many
// 8th-neighbour distances (noise moves a surface's points across a crease that is not square).
constexpr float kCreaseTolerance = 0.1f;

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

// A convex polygon in a disc's tangent plane, relative to the disc's centre.
using Polygon = std::vector<glm::vec2>;

// Keeps the part of `poly` where dot(a, x) <= c (one step of Sutherland-Hodgman).
void clipHalfPlane(Polygon& poly, Polygon& scratch, glm::vec2 a, float c) {
  scratch.clear();
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const glm::vec2 p = poly[i], q = poly[(i + 1) % n];
    const float fp = glm::dot(a, p) - c, fq = glm::dot(a, q) - c;
    if (fp <= 0) scratch.push_back(p);
    if ((fp <= 0) != (fq <= 0)) scratch.push_back(p + (fp / (fp - fq)) * (q - p));
  }
  poly.swap(scratch);
}

// How far a cell reaches: its farthest vertex that two constraints make, and whether it still
// touches the bounding square of half-side `bound` it was cut from (open there).
struct CellExtent {
  float radius = 0;
  bool open = false;
  float heightRms = 0;
};
CellExtent extentOf(const Polygon& poly, float bound) {
  CellExtent e;
  for (const glm::vec2& v : poly) {
    if (std::max(std::abs(v.x), std::abs(v.y)) >= 0.999f * bound)
      e.open = true;
    else
      e.radius = std::max(e.radius, glm::length(v));
  }
  return e;
}

// The unit normal of the plane that fits `count` points best (least squares): the eigenvector
// of their covariance with the smallest eigenvalue, from the closed-form eigenvalues of a
// symmetric 3 x 3 matrix (Smith, "Eigenvalues of a symmetric 3 x 3 matrix", 1961) and the
// largest cross product of two rows of C - lambda I. For scans without normals.
glm::vec3 fittedNormal(const glm::vec4* const* pts, size_t count) {
  glm::dvec3 mean(0.0);
  for (size_t i = 0; i < count; ++i) mean += glm::dvec3(*pts[i]);
  mean /= double(std::max<size_t>(count, 1));
  glm::dmat3 c(0.0);
  for (size_t i = 0; i < count; ++i) {
    const glm::dvec3 d = glm::dvec3(*pts[i]) - mean;
    c += glm::outerProduct(d, d);
  }
  const double q = (c[0][0] + c[1][1] + c[2][2]) / 3;
  const double p1 = c[0][1] * c[0][1] + c[0][2] * c[0][2] + c[1][2] * c[1][2];
  const double p2 = (c[0][0] - q) * (c[0][0] - q) + (c[1][1] - q) * (c[1][1] - q) +
                    (c[2][2] - q) * (c[2][2] - q) + 2 * p1;
  const double p = std::sqrt(p2 / 6);
  if (!(p > 0)) return glm::vec3(0, 0, 1);  // isotropic or a single point: no plane
  const glm::dmat3 b = (c - q * glm::dmat3(1.0)) / p;
  const double phi = std::acos(std::clamp(glm::determinant(b) / 2, -1.0, 1.0)) / 3;
  const double smallest = q + 2 * p * std::cos(phi + 2 * std::numbers::pi / 3);
  const glm::dmat3 m = c - smallest * glm::dmat3(1.0);
  glm::dvec3 best(0.0);
  for (int i = 0; i < 3; ++i) {
    const glm::dvec3 x = glm::cross(m[i], m[(i + 1) % 3]);  // rows: m is symmetric
    if (glm::dot(x, x) > glm::dot(best, best)) best = x;
  }
  const double len = glm::length(best);
  return len > 0 ? glm::vec3(best / len) : glm::vec3(0, 0, 1);
}

// Neighbours of one disc, nearest first (its own position among them).
struct Neighbourhood {
  std::vector<uint32_t> idx;
  std::vector<float> d2;
  size_t found = 0;
};

// A neighbour's plane where it meets a disc's tangent plane: g(x) = g0 + a . x, the disc's
// centre on the side g0 gives.
struct Crease {
  glm::vec2 a;
  float g0;
};
struct CellScratch {
  Polygon poly, clipped;
  std::vector<glm::vec2> same;
  std::vector<Crease> creases;
};

// The extent of disc i's cell (see assignDiscRadii): its Voronoi cell among the neighbours on
// its own surface, in its tangent plane, cut by other surfaces' planes where its surface ends
// (a crease). Cut from a square of half-side `bound`: where it still reaches that, it is open.
CellExtent cellOf(size_t i, const std::vector<glm::vec4>& pos, const std::vector<glm::vec3>& normal,
                  bool oriented, const Neighbourhood& nb, float bound, float tolerance,
                  CellScratch& cs) {
  const glm::vec3 p(pos[i]), n = normal[i];
  const Frame f = Frame::fromNormal(n);
  cs.same.clear();
  cs.creases.clear();
  double h2 = 0;
  for (size_t k = 0; k < nb.found; ++k) {
    const uint32_t j = nb.idx[k];
    if (j == i) continue;
    const glm::vec3 w = glm::vec3(pos[j]) - p, nj = normal[j];
    const glm::vec2 u(glm::dot(w, f.s), glm::dot(w, f.t));
    const float c = glm::dot(nj, n);
    if ((oriented ? c : std::abs(c)) >= kSameSurfaceCos &&
        std::abs(glm::dot(w, n)) <= kSameSurfaceTan * glm::length(u)) {
      cs.same.push_back(u);
      h2 += double(glm::dot(w, n)) * glm::dot(w, n);
      continue;
    }
    const Crease crease{{glm::dot(nj, f.s), glm::dot(nj, f.t)}, -glm::dot(nj, w)};
    // Planes within 30 degrees of this one meet it far away or not at all; a plane through
    // the centre leaves no side to keep.
    if (glm::length(crease.a) >= 0.5f && std::abs(crease.g0) > 1e-3f * tolerance)
      cs.creases.push_back(crease);
  }
  Polygon& poly = cs.poly;
  poly = {{-bound, -bound}, {bound, -bound}, {bound, bound}, {-bound, bound}};
  // The perpendicular bisector of i and j in the tangent plane: x . u <= |u|^2 / 2.
  for (const glm::vec2& u : cs.same) clipHalfPlane(poly, cs.clipped, u, 0.5f * glm::dot(u, u));
  // Another surface's plane bounds the cell where this surface ends there (a box's edge): the
  // disc must reach that line, or rays pass the crease; a Voronoi cell at a boundary otherwise
  // runs far off the surface. A plane that the surface's own points cross (a pole standing on
  // a floor: the floor goes on beyond the pole's tangent plane) bounds nothing.
  for (const Crease& c : cs.creases) {
    const float side = c.g0 > 0 ? 1.0f : -1.0f;
    bool crossed = false;
    for (const glm::vec2& u : cs.same) crossed |= side * (c.g0 + glm::dot(c.a, u)) < -tolerance;
    // Shifted out by the tolerance: each noisy neighbour puts the crease elsewhere, and the
    // nearest of them would cut the disc short of the surface's edge.
    if (!crossed) clipHalfPlane(poly, cs.clipped, -side * c.a, side * c.g0 + tolerance);
  }
  CellExtent e = extentOf(poly, bound);
  e.heightRms = cs.same.empty() ? 0.0f : float(std::sqrt(h2 / cs.same.size()));
  return e;
}

void embreeError(void*, RTCError code, const char* message) {
  // Embree reports misuse here; it is a programming error (bad buffers), never user input.
  nestlight::checkFailed(
      "Embree", __FILE__, __LINE__,
      std::string("error ") + std::to_string(int(code)) + ": " + (message ? message : ""));
}

}  // namespace

void assignDiscRadii(std::vector<glm::vec4>& discs, const std::vector<glm::vec3>& normals,
                     float radiusScale) {
  NL_CHECK(normals.empty() || normals.size() == discs.size());
  if (discs.empty()) return;
  // Spacing is measured between distinct positions: coincident copies (merged scans, a
  // million duplicates) neither shrink their neighbours' discs nor degrade the k-d tree.
  DistinctPositions distinct = distinctPositions(discs);
  std::vector<glm::vec4>& unique = distinct.unique;
  DiscAdaptor adaptor{unique};
  DiscTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const bool oriented = !normals.empty();
  std::vector<glm::vec3> normal(unique.size());
  // Pass 1: each position's normal (the scan's, or a plane fitted to its neighbours) and the
  // distance to its 8th nearest neighbour.
  std::vector<float> d8(unique.size(), 0.0f), d8Bunch(unique.size(), 0.0f);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, unique.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        // 8 neighbours for the spacing, 16 for a plane (+1: the point itself).
        const size_t k =
            std::min<size_t>((oriented ? 1 : 2) * kRadiusNeighbours + 1, unique.size());
        std::vector<uint32_t> idx(k);
        std::vector<float> d2(k);
        std::vector<const glm::vec4*> pts(k);
        for (size_t i = r.begin(); i < r.end(); ++i) {
          float q[3] = {unique[i].x, unique[i].y, unique[i].z};
          const size_t found = tree.knnSearch(q, k, idx.data(), d2.data());
          const size_t k8 = std::min<size_t>(kRadiusNeighbours, found - 1);
          d8[i] = std::sqrt(d2[k8]);
          d8Bunch[i] = d8[i];
          // r_j sqrt(8 / j): the j-th neighbour's distance scaled to the 8th's on a surface.
          const auto scaled = [&](size_t j) {
            return std::sqrt(d2[j] * float(kRadiusNeighbours) / float(j));
          };
          if (k8 >= 2 && d8[i] > kBunchFactor * scaled(2)) {
            const float bound = kBunchFactor * scaled(2);
            float bunch = 0;
            for (size_t j = 2; j <= std::min<size_t>(5, k8); ++j)
              if (scaled(j) <= bound) bunch = std::max(bunch, scaled(j));
            d8Bunch[i] = bunch;
          }
          if (oriented) {
            const glm::vec3 n = normals[distinct.firstOf[i]];
            const float len = glm::length(n);
            normal[i] = len > 0 && std::isfinite(len) ? n / len : glm::vec3(0, 0, 1);
          } else {
            for (size_t j = 0; j < found; ++j) pts[j] = &unique[idx[j]];
            normal[i] = fittedNormal(pts.data(), found);
          }
        }
      });
  // Pass 2: each position's cell.
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, unique.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
        Neighbourhood nb;
        nb.idx.resize(kCellNeighbours[2] + 1);
        nb.d2.resize(kCellNeighbours[2] + 1);
        CellScratch cs;
        for (size_t i = r.begin(); i < r.end(); ++i) {
          float q[3] = {unique[i].x, unique[i].y, unique[i].z};
          float radius = 0;
          for (size_t want : kCellNeighbours) {
            const size_t k = std::min(want + 1, unique.size());  // +1: the point itself
            nb.found = tree.knnSearch(q, k, nb.idx.data(), nb.d2.data());
            if (nb.found < 2 || !(d8[i] > 0)) break;  // alone, or among copies: no extent
            const CellExtent cell = cellOf(i, unique, normal, oriented, nb, kOpenBound * d8[i],
                                           kCreaseTolerance * d8[i], cs);
            radius = kCellMargin * cell.radius + kHeightMargin * cell.heightRms;
            // Where the cell stays open (a surface's boundary with nothing beyond), the disc is
            // at least as wide as the rule for evenly sampled surfaces.
            if (cell.open) radius = std::max(radius, kDiscCoverage * 0.5f * d8[i]);
            // A neighbour farther than the last one found cuts only cells that reach beyond
            // half its distance in the plane (30 degrees off it at most): a cell that does is
            // cut again with more neighbours (an uncut cell only overestimates).
            const bool settled = !cell.open && cell.radius <= 0.5f * kSameSurfaceCos *
                                                                  std::sqrt(nb.d2[nb.found - 1]);
            if (settled || k == unique.size()) break;
          }
          // An outlier (a point in the air, a flying pixel) has an open cell sized by its far
          // neighbours: a disc no wider than a few of its neighbours' spacings keeps it from
          // becoming metres wide.
          float nbSpacing[kRadiusNeighbours];
          size_t m = 0;
          for (size_t k = 1; k < nb.found && m < kRadiusNeighbours; ++k)
            nbSpacing[m++] = d8Bunch[nb.idx[k]];
          if (m > 0) {
            std::nth_element(nbSpacing, nbSpacing + m / 2, nbSpacing + m);
            radius = std::min(radius, kOutlierCap * nbSpacing[m / 2]);
          }
          unique[i].w = radiusScale * radius;
        }
      });
  for (size_t i = 0; i < discs.size(); ++i) discs[i].w = unique[distinct.uniqueOf[i]].w;
}

void assignDiscRadii(DiscCloud& cloud, float radiusScale) {
  assignDiscRadii(cloud.discs, cloud.normals, radiusScale);
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
  for (auto& [key, e] : nodes) {
    if (int(key.level) > level || e.numPoints == 0) continue;
    PointBuffer pts = reader.readNode(key);
    colours.linear(key, pts, rgb);
    stats.nodes++;
    for (size_t i = 0; i < pts.size(); ++i) {
      const uint32_t* p = &pts.pos[3 * i];
      // The scene's clipping volumes, tested in the scan's world coordinates (double).
      if (!octree.clipping.empty() && !octree.clipping.keeps(meta.worldPoint(p))) continue;
      glm::dvec3 local = base + glm::dvec3(p[0], p[1], p[2]) *
                                    glm::dvec3(meta.scale.x, meta.scale.y, meta.scale.z);
      cloud.discs.emplace_back(glm::vec3(local), 0.0f);
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
  assignDiscRadii(cloud, octree.radiusScale);
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

SurfaceHit ReferenceScene::discHit(size_t cloud, size_t disc) const {
  NL_CHECK(cloud < clouds_.size() && disc < clouds_[cloud].discs.size());
  const DiscCloud& c = clouds_[cloud];
  SurfaceHit hit;
  hit.kind = SurfaceHit::Kind::Disc;
  hit.position = glm::vec3(c.discs[disc]);
  hit.orientedDisc = !c.normals.empty();
  // A ray-facing disc has no normal of its own: +z stands in (callers choose the side).
  hit.geometricNormal = hit.orientedDisc ? c.normals[disc] : glm::vec3(0, 0, 1);
  hit.shadingNormal = hit.geometricNormal;
  hit.colour = c.colour[disc];
  hit.radius = c.discs[disc].w;
  hit.thickness = c.thickness.empty() ? 0.0f : c.thickness[disc];
  return hit;
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
