// Gradient-domain in-fill of HDR colour on a point cloud's k-nearest-neighbour graph: Sabbadin,
// Palma, Banterle, Boubekeur and Cignoni, "High Dynamic Range Point Clouds for Real-Time
// Relighting" (2019), section 4.2, eq. 3; the gradient-domain formulation is that of Pérez,
// Gangnet and Blake, "Poisson Image Editing" (2003), on a graph instead of a pixel grid.
//
// Our reading of eq. 3, needed to solve it with conjugate gradients: the k-nearest-neighbour
// relation is not symmetric, and eq. 3 written with N_p = kNN(p) gives a matrix that is not
// symmetric either. We symmetrise the graph (p and q are neighbours when q is among the k nearest
// of p or p among the k nearest of q), so that the system is the graph Laplacian restricted to the
// targets plus a Dirichlet term per valid neighbour: symmetric, and positive definite on every
// connected group of targets that touches at least one valid point. The groups that touch none
// (islands) would make it singular; they are found beforehand and left out of the solve. The
// solution then minimises the sum, over the edges that touch a target, of
// ((H(p) - H(q)) - (L(p) - L(q)))^2: the least-squares gradient match of Poisson image editing.
// Symmetrising only adds edges, so a point keeps all its k nearest; it also lets a tight cluster
// of coincident targets reach the valid points whose neighbourhoods contain it.
#include "nestlight/gi/hdr/poisson_infill.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <cmath>
#include <glm/common.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <nanoflann.hpp>
#include <numeric>
#include <stdexcept>
#include <vector>

namespace nestlight::gi::hdr {

namespace {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// Below the luminance of the darkest non-black colour a 16-bit linear LDR encoding can hold
// (pure blue at 1/65535: about 1.1e-6), L's chromaticity is noise; Luminance mode then gives the
// solved luminance as grey instead of amplifying that noise by Y_H / Y_L.
constexpr double kTinyLuminance = 1e-7;

bool isFinite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// The included points' positions, copied contiguously for the tree (better locality than
// indirection through the caller's arrays, and only finite ones).
struct Cloud {
  std::vector<float> xyz;
  size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  float kdtree_get_pt(uint32_t i, size_t dim) const { return xyz[3 * size_t(i) + dim]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud,
                                                 3, uint32_t>;

// The k nearest other than the query point itself. Skipping the query by index, rather than
// asking for k + 1 and dropping the nearest, is what keeps coincident points right: among more
// than k + 1 points at distance 0 the query need not come first, or at all.
class NearestExceptSelf {
 public:
  NearestExceptSelf(uint32_t self, size_t capacity, uint32_t* index, float* dist)
      : self_(self), capacity_(capacity), index_(index), dist_(dist) {}

  size_t size() const { return count_; }
  bool full() const { return count_ == capacity_; }
  // The capacity is at least 1 here (k >= 1 is checked, and a lone point builds no graph); the
  // test keeps the class safe on its own and GCC from warning of a read of slot -1.
  float worstDist() const {
    if (capacity_ == 0) return 0.0f;
    return full() ? dist_[capacity_ - 1] : std::numeric_limits<float>::max();
  }
  // nanoflann caches worstDist per leaf, so candidates no better than the current worst can
  // still arrive here.
  bool addPoint(float d, uint32_t i) {
    if (i == self_ || capacity_ == 0) return true;
    if (full() && !(d < dist_[capacity_ - 1])) return true;
    size_t j = full() ? capacity_ - 1 : count_++;
    for (; j > 0 && dist_[j - 1] > d; --j) {
      dist_[j] = dist_[j - 1];
      index_[j] = index_[j - 1];
    }
    dist_[j] = d;
    index_[j] = i;
    return true;
  }

 private:
  uint32_t self_;
  size_t capacity_;
  uint32_t* index_;
  float* dist_;
  size_t count_ = 0;
};

// Rows of the targets in the symmetrised graph: neighbours as indices of included points,
// sorted, without repeats.
struct TargetGraph {
  std::vector<uint64_t> start;  // per target row, into neighbours; one more than rows
  std::vector<uint32_t> neighbours;
};

TargetGraph targetGraph(const Tree& tree, const Cloud& cloud,
                        const std::vector<uint32_t>& targetRow, size_t targetCount, int k) {
  const size_t n = cloud.kdtree_get_point_count();
  const size_t kk = std::min<size_t>(size_t(k), n - 1);
  // Every directed kNN edge p -> q that touches a target adds q to p's row and p to q's row;
  // edges between valid points play no part in the system and are never stored.
  tbb::enumerable_thread_specific<std::vector<uint64_t>> local;
  const auto query = [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint64_t>& pairs = local.local();
    std::vector<uint32_t> index(kk);
    std::vector<float> dist(kk);
    for (size_t p = r.begin(); p < r.end(); ++p) {
      NearestExceptSelf result(uint32_t(p), kk, index.data(), dist.data());
      tree.findNeighbors(result, &cloud.xyz[3 * p], nanoflann::SearchParams());
      const uint32_t rowP = targetRow[p];
      for (size_t j = 0; j < result.size(); ++j) {
        const uint32_t q = index[j];
        if (rowP != kNone) pairs.push_back(uint64_t(rowP) << 32 | q);
        if (targetRow[q] != kNone) pairs.push_back(uint64_t(targetRow[q]) << 32 | uint32_t(p));
      }
    }
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), query);

  TargetGraph g;
  g.start.assign(targetCount + 1, 0);
  for (const std::vector<uint64_t>& pairs : local)
    for (uint64_t e : pairs) g.start[(e >> 32) + 1]++;
  std::partial_sum(g.start.begin(), g.start.end(), g.start.begin());
  g.neighbours.resize(g.start.back());
  {
    std::vector<uint64_t> fill(g.start.begin(), g.start.end() - 1);
    for (std::vector<uint64_t>& pairs : local) {
      for (uint64_t e : pairs) g.neighbours[fill[e >> 32]++] = uint32_t(e);
      std::vector<uint64_t>().swap(pairs);
    }
  }
  // Sort and drop repeats (an edge found from both ends), then close the gaps.
  std::vector<uint64_t> unique(targetCount);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, targetCount, 4096),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t t = r.begin(); t < r.end(); ++t) {
                        auto b = g.neighbours.begin() + ptrdiff_t(g.start[t]);
                        auto e = g.neighbours.begin() + ptrdiff_t(g.start[t + 1]);
                        std::sort(b, e);
                        unique[t] = uint64_t(std::unique(b, e) - b);
                      }
                    });
  uint64_t out = 0;
  for (size_t t = 0; t < targetCount; ++t) {
    const uint64_t from = g.start[t];
    g.start[t] = out;
    for (uint64_t j = 0; j < unique[t]; ++j) g.neighbours[out++] = g.neighbours[from + j];
  }
  g.start[targetCount] = out;
  g.neighbours.resize(out);
  g.neighbours.shrink_to_fit();
  return g;
}

// 21 bits per axis of a position normalised to [0, 1].
uint64_t morton(const glm::dvec3& u) {
  const auto spread = [](double v) {
    uint64_t x = uint64_t(std::clamp(v, 0.0, 1.0) * double((1u << 21) - 1));
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
  };
  return spread(u.x) | spread(u.y) << 1 | spread(u.z) << 2;
}

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t a) {
  while (parent[a] != a) {
    parent[a] = parent[parent[a]];
    a = parent[a];
  }
  return a;
}

using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Lets the channels' solvers, run concurrently, share one factorisation: Eigen's solvers own
// their preconditioner and would each factorise the same matrix again. Applying a preconditioner
// (solve) is const, so sharing it across threads is safe.
template <class Preconditioner>
class SharedPreconditioner {
 public:
  void share(const Preconditioner& p) { shared_ = &p; }
  template <class Matrix>
  SharedPreconditioner& analyzePattern(const Matrix&) {
    return *this;
  }
  template <class Matrix>
  SharedPreconditioner& factorize(const Matrix&) {
    return *this;
  }
  template <class Matrix>
  SharedPreconditioner& compute(const Matrix&) {
    return *this;
  }
  template <class Rhs>
  auto solve(const Eigen::MatrixBase<Rhs>& b) const {
    return shared_->solve(b);
  }
  Eigen::ComputationInfo info() const { return Eigen::Success; }

 private:
  const Preconditioner* shared_ = nullptr;
};

template <class Preconditioner>
void solveChannels(const SpMat& a, const Preconditioner& preconditioner, const Eigen::MatrixXd& b,
                   Eigen::MatrixXd& x, const InfillOptions& options, InfillStats& stats) {
  struct Outcome {
    Eigen::Index iterations = 0;
    double error = 0;
    bool converged = false;
  };
  std::array<Outcome, 3> outcome;
  tbb::parallel_for(0, int(b.cols()), [&](int c) {
    Eigen::ConjugateGradient<SpMat, Eigen::Lower | Eigen::Upper,
                             SharedPreconditioner<Preconditioner>>
        cg;
    cg.preconditioner().share(preconditioner);
    cg.setTolerance(options.tolerance);
    cg.setMaxIterations(options.maxIterations);
    cg.compute(a);
    x.col(c) = cg.solveWithGuess(b.col(c), x.col(c));
    outcome[size_t(c)] = {cg.iterations(), cg.error(), cg.info() == Eigen::Success};
  });
  for (int c = 0; c < int(b.cols()); ++c) {
    stats.cgIterations = std::max(stats.cgIterations, uint64_t(outcome[size_t(c)].iterations));
    stats.cgError = std::max(stats.cgError, outcome[size_t(c)].error);
    stats.converged = stats.converged && outcome[size_t(c)].converged;
  }
}

void solve(const SpMat& a, const Eigen::MatrixXd& b, Eigen::MatrixXd& x,
           const InfillOptions& options, InfillStats& stats) {
  if (options.preconditioner == InfillPreconditioner::IncompleteCholesky) {
    // No fill-reducing reordering: the unknowns are already in Morton order, and on our
    // benchmark (100,000 unknowns in one hole) AMD's reordering cost a third more iterations, each
    // slower, than keeping that spatial order.
    Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::NaturalOrdering<int>> ic;
    ic.compute(a);
    if (ic.info() == Eigen::Success) return solveChannels(a, ic, b, x, options, stats);
    // Incomplete factorisations can break down; Jacobi cannot.
  }
  Eigen::DiagonalPreconditioner<double> jacobi;
  jacobi.compute(a);
  solveChannels(a, jacobi, b, x, options, stats);
}

// A target that cannot be solved for gets islandScale * L (0 when L is not finite).
struct Fallback {
  std::span<const glm::vec3> ldr;
  std::span<glm::vec3> hdr;
  float islandScale;
  std::vector<InfillOutcome>* outcome;
  void operator()(size_t i) const {
    hdr[i] = isFinite(ldr[i]) ? islandScale * ldr[i] : glm::vec3(0.0f);
    if (outcome) (*outcome)[i] = InfillOutcome::Island;
  }
};

// The points that take part, numbered compactly; targets also numbered as rows.
struct Included {
  std::vector<uint32_t> original;     // per included point: the caller's index
  std::vector<uint32_t> targetRow;    // per included point: its row, or kNone when valid
  std::vector<uint32_t> targetPoint;  // per row: the included point
  Cloud cloud;
};

// Included points, numbered compactly in Morton order: neighbours then sit close in memory,
// both for the tree's queries and for the matrix's rows, whatever order the caller's points
// come in (a shuffled cloud otherwise takes twice as long to query and to solve).
Included includePoints(std::span<const glm::vec3> positions, std::span<const glm::vec3> ldr,
                       std::span<const glm::vec3> hdr, std::span<const InfillRole> role,
                       const Fallback& fallback, InfillStats& stats) {
  const size_t total = positions.size();
  Included in;
  std::vector<uint32_t>& original = in.original;
  original.reserve(total);
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (size_t i = 0; i < total; ++i) {
    const bool target = role[i] == InfillRole::Target;
    stats.targets += target;
    if (!isFinite(positions[i]) || !isFinite(ldr[i]) || (!target && !isFinite(hdr[i]))) {
      stats.nonFiniteInputs++;
      if (target) {
        stats.excludedTargets++;
        fallback(i);
      }
      continue;
    }
    original.push_back(uint32_t(i));
    lo = glm::min(lo, positions[i]);
    hi = glm::max(hi, positions[i]);
  }
  {
    std::vector<uint64_t> code(original.size());
    const glm::dvec3 extent = glm::max(glm::dvec3(hi) - glm::dvec3(lo), glm::dvec3(1e-30));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, original.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t p = r.begin(); p < r.end(); ++p) {
                          const glm::dvec3 u =
                              (glm::dvec3(positions[original[p]]) - glm::dvec3(lo)) / extent;
                          code[p] = morton(u);
                        }
                      });
    std::vector<uint32_t> order(original.size());
    std::iota(order.begin(), order.end(), 0u);
    tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return code[a] != code[b] ? code[a] < code[b] : a < b;
    });
    for (uint32_t& o : order) o = original[o];
    original.swap(order);
  }
  in.cloud.xyz.resize(3 * original.size());
  for (size_t p = 0; p < original.size(); ++p)
    for (int a = 0; a < 3; ++a) in.cloud.xyz[3 * p + size_t(a)] = positions[original[p]][a];
  const size_t n = original.size();
  in.targetRow.assign(n, kNone);
  for (size_t p = 0; p < n; ++p) {
    if (role[original[p]] != InfillRole::Target) continue;
    in.targetRow[p] = uint32_t(in.targetPoint.size());
    in.targetPoint.push_back(uint32_t(p));
  }
  return in;
}

// The system's unknowns: per target row its unknown (kNone for an island's), and per unknown
// its row. Connected groups of targets; a group with no valid neighbour anywhere is an island,
// left out of the solve because it would make the matrix singular.
struct Unknowns {
  std::vector<uint32_t> unknown;
  std::vector<uint32_t> unknownRow;
};

Unknowns findIslands(const TargetGraph& graph, const Included& in, const Fallback& fallback,
                     InfillStats& stats) {
  const size_t targets = in.targetPoint.size();
  std::vector<uint32_t> parent(targets);
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<uint8_t> touchesValid(targets, 0);
  for (size_t t = 0; t < targets; ++t) {
    for (uint64_t j = graph.start[t]; j < graph.start[t + 1]; ++j) {
      const uint32_t u = in.targetRow[graph.neighbours[j]];
      if (u == kNone) {
        touchesValid[t] = 1;
      } else {
        const uint32_t ra = findRoot(parent, uint32_t(t)), rb = findRoot(parent, u);
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
  }
  for (size_t t = 0; t < targets; ++t) {
    const uint32_t r = findRoot(parent, uint32_t(t));
    touchesValid[r] |= touchesValid[t];
  }
  Unknowns u;
  u.unknown.assign(targets, kNone);
  for (size_t t = 0; t < targets; ++t) {
    const uint32_t r = findRoot(parent, uint32_t(t));
    if (touchesValid[r]) {
      u.unknown[t] = uint32_t(u.unknownRow.size());
      u.unknownRow.push_back(uint32_t(t));
    } else {
      stats.islands += r == t;  // roots are the smallest row of their group
      stats.islandPoints++;
      fallback(in.original[in.targetPoint[t]]);
    }
  }
  return u;
}

// The matrix, built compressed: column j holds -1 at every target neighbour and the degree on
// the diagonal. Rows follow the included points' order, so each column comes out sorted.
SpMat assembleMatrix(const TargetGraph& graph, const Included& in, const Unknowns& un) {
  const size_t m = un.unknownRow.size();
  uint64_t nonZeros = 0;
  for (uint32_t t : un.unknownRow) {
    nonZeros++;
    for (uint64_t j = graph.start[t]; j < graph.start[t + 1]; ++j)
      nonZeros += in.targetRow[graph.neighbours[j]] != kNone;
  }
  if (nonZeros > uint64_t(std::numeric_limits<int>::max()))
    throw std::invalid_argument("poissonInfill: system too large");
  SpMat a(static_cast<Eigen::Index>(m), static_cast<Eigen::Index>(m));
  a.resizeNonZeros(Eigen::Index(nonZeros));
  int* outer = a.outerIndexPtr();
  int* inner = a.innerIndexPtr();
  double* value = a.valuePtr();
  int at = 0;
  for (size_t col = 0; col < m; ++col) {
    outer[col] = at;
    const uint32_t t = un.unknownRow[col];
    bool diagonal = false;
    const auto putDiagonal = [&] {
      inner[at] = int(col);
      value[at++] = double(graph.start[t + 1] - graph.start[t]);
      diagonal = true;
    };
    for (uint64_t j = graph.start[t]; j < graph.start[t + 1]; ++j) {
      const uint32_t u = in.targetRow[graph.neighbours[j]];
      if (u == kNone) continue;
      const int row = int(un.unknown[u]);
      if (!diagonal && row > int(col)) putDiagonal();
      inner[at] = row;
      value[at++] = -1.0;
    }
    if (!diagonal) putDiagonal();
  }
  outer[m] = at;
  return a;
}

// One channel of a colour as the system sees it: the channel itself, or the luminance.
struct Channels {
  bool rgb;
  int count() const { return rgb ? 3 : 1; }
  double operator()(const glm::vec3& c, int ch) const {
    return rgb ? double(c[ch]) : infillLuminance(c);
  }
};

// Right-hand sides and the first guess. The guess is L plus the mean offset H - L of the valid
// neighbours, the solution when H differs from L by a constant (the system only sees
// gradients); it changes where CG starts, not where it stops.
void assembleRhs(const TargetGraph& graph, const Included& in, const Unknowns& un,
                 std::span<const glm::vec3> ldr, std::span<const glm::vec3> hdr,
                 const Channels& channel, Eigen::MatrixXd& b, Eigen::MatrixXd& x) {
  const size_t m = un.unknownRow.size();
  const int channels = channel.count();
  b.resize(Eigen::Index(m), channels);
  x.resize(Eigen::Index(m), channels);
  std::array<double, 3> offsetSum{0, 0, 0};
  uint64_t offsetCount = 0;
  for (size_t col = 0; col < m; ++col) {
    const uint32_t t = un.unknownRow[col];
    const size_t p = in.original[in.targetPoint[t]];
    const double degree = double(graph.start[t + 1] - graph.start[t]);
    for (int ch = 0; ch < channels; ++ch) b(Eigen::Index(col), ch) = degree * channel(ldr[p], ch);
    for (uint64_t j = graph.start[t]; j < graph.start[t + 1]; ++j) {
      const uint32_t q = in.original[graph.neighbours[j]];
      const bool valid = in.targetRow[graph.neighbours[j]] == kNone;
      for (int ch = 0; ch < channels; ++ch) {
        b(Eigen::Index(col), ch) -= channel(ldr[q], ch);
        if (!valid) continue;
        b(Eigen::Index(col), ch) += channel(hdr[q], ch);
        offsetSum[size_t(ch)] += channel(hdr[q], ch) - channel(ldr[q], ch);
      }
      offsetCount += valid;
    }
  }
  for (size_t col = 0; col < m; ++col) {
    const size_t p = in.original[in.targetPoint[un.unknownRow[col]]];
    for (int ch = 0; ch < channels; ++ch)
      x(Eigen::Index(col), ch) = channel(ldr[p], ch) + offsetSum[size_t(ch)] / double(offsetCount);
  }
}

// Back to colours, with the guards: finite, non-negative.
void writeBack(const Eigen::MatrixXd& x, const Included& in, const Unknowns& un, bool rgb,
               std::span<const glm::vec3> ldr, std::span<glm::vec3> hdr, const Fallback& fallback,
               InfillStats& stats) {
  for (size_t col = 0; col < un.unknownRow.size(); ++col) {
    const size_t p = in.original[in.targetPoint[un.unknownRow[col]]];
    glm::dvec3 h;
    if (rgb) {
      h = glm::dvec3(x(Eigen::Index(col), 0), x(Eigen::Index(col), 1), x(Eigen::Index(col), 2));
    } else {
      const double y = x(Eigen::Index(col), 0);
      const double yl = infillLuminance(ldr[p]);
      h = yl > kTinyLuminance ? glm::dvec3(ldr[p]) * (y / yl) : glm::dvec3(y);
    }
    glm::vec3 out(h);
    if (!isFinite(out)) {
      stats.nonFiniteResults++;
      fallback(p);
      continue;
    }
    if (out.x < 0 || out.y < 0 || out.z < 0) {
      stats.clampedNegative++;
      out = glm::max(out, glm::vec3(0.0f));
    }
    hdr[p] = out;
  }
}

}  // namespace

InfillStats poissonInfill(std::span<const glm::vec3> positions, std::span<const glm::vec3> ldr,
                          std::span<glm::vec3> hdr, std::span<const InfillRole> role,
                          const InfillOptions& options, std::vector<InfillOutcome>* outcome) {
  const size_t total = positions.size();
  if (ldr.size() != total || hdr.size() != total || role.size() != total)
    throw std::invalid_argument("poissonInfill: spans of different lengths");
  if (total >= size_t(kNone)) throw std::invalid_argument("poissonInfill: too many points");
  if (options.k < 1 || !(options.tolerance >= 0) || options.maxIterations < 1)
    throw std::invalid_argument("poissonInfill: options out of range");

  InfillStats stats;
  if (outcome) {
    outcome->assign(total, InfillOutcome::NotTarget);
    for (size_t i = 0; i < total; ++i)
      if (role[i] == InfillRole::Target) (*outcome)[i] = InfillOutcome::Solved;
  }
  const Fallback fallback{ldr, hdr, options.islandScale, outcome};

  Included in = includePoints(positions, ldr, hdr, role, fallback, stats);
  const size_t targets = in.targetPoint.size();
  if (targets == 0) return stats;
  if (in.original.size() == 1) {  // a lone target: no graph at all, an island of one
    stats.islands = stats.islandPoints = 1;
    fallback(in.original[0]);
    return stats;
  }

  TargetGraph graph;
  {
    const Tree tree(3, in.cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    graph = targetGraph(tree, in.cloud, in.targetRow, targets, options.k);
  }
  std::vector<float>().swap(in.cloud.xyz);

  const Unknowns un = findIslands(graph, in, fallback, stats);
  stats.solved = un.unknownRow.size();
  if (un.unknownRow.empty()) return stats;

  const SpMat a = assembleMatrix(graph, in, un);
  const Channels channel{options.mode == InfillMode::Rgb};
  Eigen::MatrixXd b, x;
  assembleRhs(graph, in, un, ldr, hdr, channel, b, x);
  std::vector<uint64_t>().swap(graph.start);
  std::vector<uint32_t>().swap(graph.neighbours);

  solve(a, b, x, options, stats);
  writeBack(x, in, un, channel.rgb, ldr, hdr, fallback, stats);
  return stats;
}

}  // namespace nestlight::gi::hdr
