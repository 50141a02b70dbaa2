// Inserted meshes as points, so that point-based GI treats them like the scan (Preiner, paper 004,
// section 6: a polygon model takes part in the GI through sample points on its surface).
//
// AreaUniform: the triangle by area (pbrt-v4 A.5, a piecewise-constant distribution over the
// triangles), the point uniform in it (Heitz 2019, sampleUniformTriangle). The triangle choice is
// stratified, u = (i + xi) / count: each triangle still has probability proportional to its
// area, but the counts per triangle vary less than with independent draws.
//
// PoissonDisk: weighted sample elimination (C. Yuksel, "Sample Elimination for Generating Poisson
// Disk Sample Sets", Computer Graphics Forum 34(2), 2015). From 5x as many area-uniform
// candidates, the one whose close neighbours weigh most is removed until `count` remain. Distances
// are Euclidean in world space, as the paper does for surfaces.
//
// worldFromObject is taken as affine (nothing is divided by w). Normals transform by the inverse
// transpose of its linear part, computed as the cofactor matrix times the determinant's sign:
// the same up to a positive factor (normals are normalised anyway), and still defined where the
// matrix is singular. With the sign, a mirror keeps outward normals outward.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <utility>
#include <vector>

#include "nestlight/gi/mesh.h"
#include "nestlight/octree/error.h"

namespace nestlight::gi {
namespace {

// The parameters Yuksel 2015 recommends: alpha = 8, and weight limiting with beta = 0.65 and
// gamma = 1.5.
constexpr size_t kCandidatesPerPoint = 5;
constexpr double kAlpha = 8, kBeta = 0.65, kGamma = 1.5;

struct WorldMesh {
  const TriangleMesh& mesh;
  glm::dmat4 worldFromObject;
  glm::dmat3 normalMatrix;         // sign(det) * cofactor of the linear part
  std::vector<uint32_t> triangle;  // triangles of non-zero world area
  std::vector<float> area;         // their world areas
  double total = 0;

  WorldMesh(const TriangleMesh& m, const glm::mat4& w) : mesh(m), worldFromObject(w) {
    NL_CHECK(m.indices.size() % 3 == 0);
    NL_CHECK(m.normals.empty() || m.normals.size() == m.positions.size());
    NL_CHECK(m.colors.empty() || m.colors.size() == m.positions.size());
    for (uint32_t i : m.indices) NL_CHECK(i < m.positions.size());
    const glm::dmat3 a(worldFromObject);
    // The columns of the cofactor matrix are cross products of the columns of `a`.
    const glm::dmat3 cof(glm::cross(a[1], a[2]), glm::cross(a[2], a[0]), glm::cross(a[0], a[1]));
    normalMatrix = glm::determinant(a) < 0 ? -cof : cof;
    const size_t n = m.triangles();
    for (size_t t = 0; t < n; ++t) {
      const double ar = 0.5 * glm::length(crossWorld(t));
      // Areas beyond float's range cannot weigh a float distribution; such triangles get none.
      if (ar > 0 && ar <= std::numeric_limits<float>::max() && float(ar) > 0) {
        triangle.push_back(uint32_t(t));
        area.push_back(float(ar));
        total += ar;
      }
    }
  }

  glm::dvec3 world(uint32_t v) const {
    return glm::dvec3(worldFromObject * glm::dvec4(glm::dvec3(mesh.positions[v]), 1.0));
  }
  glm::dvec3 corner(size_t t, int k) const { return world(mesh.indices[3 * t + k]); }
  glm::dvec3 crossWorld(size_t t) const {
    const glm::dvec3 a = corner(t, 0);
    return glm::cross(corner(t, 1) - a, corner(t, 2) - a);
  }
};

struct Candidate {
  uint32_t triangle;
  glm::vec3 bary;
  glm::vec3 position;
};

// `n` area-uniform points; the triangle choice stratified (see the top of the file).
std::vector<Candidate> areaUniform(const WorldMesh& w, size_t n, Rng& rng) {
  std::vector<Candidate> out;
  out.reserve(n);
  const Distribution1D pick(w.area);
  for (size_t i = 0; i < n; ++i) {
    const float u = std::min(float((double(i) + rng.uniform()) / double(n)), kOneMinusEpsilon);
    const uint32_t t = w.triangle[size_t(pick.sampleDiscrete(u))];
    const glm::vec3 b = sampleUniformTriangle(rng.uniform2());
    // From a corner along the edges: a point of a plane z = c keeps z = c exactly.
    const glm::dvec3 a = w.corner(t, 0);
    const glm::dvec3 p =
        a + double(b[1]) * (w.corner(t, 1) - a) + double(b[2]) * (w.corner(t, 2) - a);
    out.push_back({t, b, glm::vec3(p)});
  }
  return out;
}

// nanoflann's view of the candidates.
struct Cloud {
  const std::vector<Candidate>* c;
  size_t kdtree_get_point_count() const { return c->size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return (*c)[i].position[int(d)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud,
                                                 3, uint32_t>;

// Calls f(index, squared distance) for every candidate closer than sqrt(r2), the query included.
template <typename F>
struct Within {
  float r2;
  F f;
  bool full() const { return true; }
  float worstDist() const { return r2; }
  bool addPoint(float d2, uint32_t i) {
    if (d2 < r2) f(i, d2);
    return true;
  }
};
template <typename F>
void forNeighbours(const Tree& tree, const glm::vec3& p, float r2, F f) {
  Within<F> within{r2, std::move(f)};
  tree.findNeighbors(within, &p.x, nanoflann::SearchParams());
}

// A max-heap of candidate weights whose entries can be lowered in place.
class EliminationHeap {
 public:
  explicit EliminationHeap(const std::vector<double>& w) : w_(w), at_(w.size()) {
    heap_.resize(w.size());
    for (uint32_t i = 0; i < heap_.size(); ++i) heap_[i] = i, at_[i] = i;
    for (size_t i = heap_.size() / 2; i-- > 0;) down(i);
  }
  uint32_t popMax() {
    const uint32_t top = heap_[0];
    move(heap_.size() - 1, 0);
    heap_.pop_back();
    if (!heap_.empty()) down(0);
    at_[top] = kGone;
    return top;
  }
  bool contains(uint32_t i) const { return at_[i] != kGone; }
  void lower(uint32_t i, double by) {
    w_[i] -= by;
    down(at_[i]);
  }
  size_t size() const { return heap_.size(); }

 private:
  static constexpr uint32_t kGone = std::numeric_limits<uint32_t>::max();
  // Ties go to the lower index, so that equal weights cannot make the result vary.
  bool above(uint32_t a, uint32_t b) const { return w_[a] > w_[b] || (w_[a] == w_[b] && a < b); }
  void move(size_t from, size_t to) {
    heap_[to] = heap_[from];
    at_[heap_[to]] = uint32_t(to);
  }
  void down(size_t i) {
    const uint32_t x = heap_[i];
    const size_t n = heap_.size();
    while (true) {
      size_t c = 2 * i + 1;
      if (c >= n) break;
      if (c + 1 < n && above(heap_[c + 1], heap_[c])) ++c;
      if (!above(heap_[c], x)) break;
      move(c, i);
      i = c;
    }
    heap_[i] = x;
    at_[x] = uint32_t(i);
  }
  std::vector<double> w_;
  std::vector<uint32_t> heap_, at_;
};

std::vector<Candidate> poissonDisk(const WorldMesh& w, size_t n, Rng& rng) {
  if (n > (std::numeric_limits<uint32_t>::max() - 1) / kCandidatesPerPoint)
    throw Error("Poisson-disk sampling of " + std::to_string(n) + " points needs " +
                std::to_string(kCandidatesPerPoint) +
                " times as many candidates, more than 32-bit indices address");
  const size_t m = n * kCandidatesPerPoint;
  std::vector<Candidate> cand = areaUniform(w, m, rng);
  // The largest radius that n disks can have on area A (hexagonal packing), as in the paper.
  const double rMax = std::sqrt(w.total / (2 * std::sqrt(3.0) * double(n)));
  const double dMax = 2 * rMax;
  const double dMin = dMax * (1 - std::pow(double(n) / double(m), kGamma)) * kBeta;
  const auto weight = [&](uint32_t i, uint32_t j) {
    const double d = std::max(double(glm::distance(cand[i].position, cand[j].position)), dMin);
    const double x = 1 - std::min(d / dMax, 1.0);
    const double x2 = x * x, x4 = x2 * x2;
    static_assert(kAlpha == 8);
    return x4 * x4;
  };
  const Cloud cloud{&cand};
  const Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const float r2 = float(dMax * dMax);

  // Every candidate's neighbours, found once (in parallel) and kept for the elimination, which
  // visits them again at each removal: querying the tree there instead made 50,000 points on the
  // bunny take twice as long. Chunks are joined in index order, so the lists do not depend on
  // the threads.
  constexpr size_t kChunk = 4096;
  const size_t chunks = (m + kChunk - 1) / kChunk;
  std::vector<std::vector<uint32_t>> found(chunks), counts(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    for (size_t i = c * kChunk; i < std::min(m, (c + 1) * kChunk); ++i) {
      uint32_t k = 0;
      forNeighbours(tree, cand[i].position, r2, [&](uint32_t j, float) {
        if (j != i) found[c].push_back(j), ++k;
      });
      counts[c].push_back(k);
    }
  });
  std::vector<size_t> first(m + 1, 0);
  std::vector<uint32_t> neighbours;
  for (size_t c = 0, i = 0; c < chunks; ++c) {
    for (uint32_t k : counts[c]) first[i + 1] = first[i] + k, ++i;
    neighbours.insert(neighbours.end(), found[c].begin(), found[c].end());
    std::vector<uint32_t>().swap(found[c]);
  }

  std::vector<double> wsum(m, 0.0);
  tbb::parallel_for(size_t(0), m, [&](size_t i) {
    for (size_t k = first[i]; k < first[i + 1]; ++k) wsum[i] += weight(uint32_t(i), neighbours[k]);
  });
  EliminationHeap heap(wsum);
  while (heap.size() > n) {
    const uint32_t i = heap.popMax();
    for (size_t k = first[i]; k < first[i + 1]; ++k)
      if (const uint32_t j = neighbours[k]; heap.contains(j)) heap.lower(j, weight(i, j));
  }
  std::vector<Candidate> out;
  out.reserve(n);
  for (uint32_t i = 0; i < m; ++i)
    if (heap.contains(i)) out.push_back(cand[i]);
  return out;
}

}  // namespace

double meshArea(const TriangleMesh& mesh, const glm::mat4& worldFromObject) {
  return WorldMesh(mesh, worldFromObject).total;
}

Surfels sampleSurfels(const TriangleMesh& mesh, const glm::mat4& worldFromObject,
                      const SurfelOptions& options) {
  Surfels s;
  const WorldMesh w(mesh, worldFromObject);
  if (options.count == 0 || w.triangle.empty()) return s;
  Rng rng(options.seed);
  const std::vector<Candidate> points = options.method == SurfelSampling::PoissonDisk
                                            ? poissonDisk(w, options.count, rng)
                                            : areaUniform(w, options.count, rng);
  const size_t n = points.size();
  s.positions.reserve(n);
  s.normals.reserve(n);
  s.area.assign(n, float(w.total / double(n)));
  s.albedo.reserve(n);
  s.material.assign(n, options.material);
  for (const Candidate& c : points) {
    const uint32_t* v = &mesh.indices[3 * size_t(c.triangle)];
    s.positions.push_back(c.position);
    glm::dvec3 nrm(0);
    if (!mesh.normals.empty()) {
      const glm::dvec3 obj = double(c.bary[0]) * glm::dvec3(mesh.normals[v[0]]) +
                             double(c.bary[1]) * glm::dvec3(mesh.normals[v[1]]) +
                             double(c.bary[2]) * glm::dvec3(mesh.normals[v[2]]);
      nrm = w.normalMatrix * obj;
    }
    double len = glm::length(nrm);
    if (!(len > 0) || !std::isfinite(len)) {
      const glm::dvec3 a(mesh.positions[v[0]]);
      nrm = w.normalMatrix *
            glm::cross(glm::dvec3(mesh.positions[v[1]]) - a, glm::dvec3(mesh.positions[v[2]]) - a);
      len = glm::length(nrm);
    }
    s.normals.push_back(glm::vec3(nrm / len));
    Rgb albedo = options.baseColor;
    if (!mesh.colors.empty())
      albedo *= c.bary[0] * mesh.colors[v[0]] + c.bary[1] * mesh.colors[v[1]] +
                c.bary[2] * mesh.colors[v[2]];
    s.albedo.push_back(albedo);
  }
  return s;
}

}  // namespace nestlight::gi
