#include "nestlight/octree/spacing.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace nestlight {

double medianNeighbourSpacing(const uint32_t* xyz, const uint32_t* indices, size_t n,
                              size_t maxQueries, size_t window) {
  if (n < 2 || maxQueries == 0 || window == 0) return 0;
  auto at = [&](size_t i) { return xyz + 3 * size_t(indices ? indices[i] : i); };
  const size_t queries = std::min(n, maxQueries);
  std::vector<double> spacing;
  spacing.reserve(queries);
  for (size_t q = 0; q < queries; ++q) {
    // Evenly strided over the whole set, so the median speaks for every part of the node.
    const size_t i = q * n / queries;
    const uint32_t* p = at(i);
    const size_t lo = i > window ? i - window : 0, hi = std::min(n, i + window + 1);
    // The kSpacingNeighbours smallest distinct squared distances, ascending.
    std::array<double, kSpacingNeighbours> best;
    best.fill(INFINITY);
    for (size_t j = lo; j < hi; ++j) {
      const uint32_t* o = at(j);
      // Copies of one position (kept when their attributes differ) sort next to each other in
      // Morton order: count each distinct neighbour once.
      if (j > lo) {
        const uint32_t* prev = at(j - 1);
        if (prev[0] == o[0] && prev[1] == o[1] && prev[2] == o[2]) continue;
      }
      const double dx = double(o[0]) - p[0], dy = double(o[1]) - p[1], dz = double(o[2]) - p[2];
      const double d2 = dx * dx + dy * dy + dz * dz;
      if (d2 <= 0 || d2 >= best.back()) continue;  // coincident points are one point on screen
      size_t k = best.size() - 1;
      for (; k > 0 && best[k - 1] > d2; --k) best[k] = best[k - 1];
      best[k] = d2;
    }
    if (!std::isfinite(best.back())) continue;
    // j points within r_j on a surface: pi r_j^2 / j of surface per point.
    auto estimate = [&](int j) { return std::sqrt(best[j - 1] * M_PI / j); };
    double s = estimate(kSpacingNeighbours);
    // A few returns bunched together far from everything else (dust, a bird, a stray reflection:
    // the two "points" above the Takanawa lion are 4 and 6 returns within 1 cm, 0.4 m apart) are
    // no surface sampled at r_k: their k-th neighbour lies in the next bunch. Where the 2nd
    // neighbour says the density is far higher, the bunch's own neighbours count instead.
    const double bound = kClusterRatio * estimate(2);
    if (s > bound) {
      s = estimate(2);
      for (int j = 3; j < kSpacingNeighbours; ++j)
        if (estimate(j) <= bound) s = std::max(s, estimate(j));
    }
    spacing.push_back(s);
  }
  if (spacing.size() < 8) return 0;
  auto mid = spacing.begin() + spacing.size() / 2;
  std::nth_element(spacing.begin(), mid, spacing.end());
  return *mid;
}

double measuredSpacing(const Metadata& meta, uint32_t level, const HierarchyEntry& e) {
  return meta.version >= 2 ? decodeSpacing(e.spacingCode, meta.levelSpacing(level)) : 0.0;
}

}  // namespace nestlight
