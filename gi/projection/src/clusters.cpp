// Equal-count clusters by median splits: Maletz, Wang and Bowers, "Importance-Driven Point
// Projection for GPU-based Final Gathering" (2011), section 4.1 (their GPU segmented sort; here
// std::nth_element per node, the nodes of a level in parallel).
#include "nestlight/gi/projection/clusters.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <glm/glm.hpp>

#include "nestlight/octree/error.h"

namespace nestlight::gi::projection {

Clusters buildClusters(const std::vector<glm::vec3>& position, uint32_t clusters) {
  NL_CHECK(clusters > 0 && std::has_single_bit(clusters));
  Clusters c;
  c.requested = clusters;
  c.order.reserve(position.size());
  for (uint32_t i = 0; i < position.size(); ++i) {
    const glm::vec3& p = position[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))
      c.order.push_back(i);
    else
      c.rejected++;
  }
  const uint32_t n = uint32_t(c.order.size());
  c.count = std::min(clusters, std::max(1u, std::bit_floor(std::max(n, 1u))));
  // Level by level: the ranges of a level are cut at their middle rank; after log2(count)
  // levels each is a cluster. Ranges split as n / 2^level, so sizes differ by one at most.
  std::vector<uint32_t> bounds{0, n};
  for (uint32_t ranges = 1; ranges < c.count; ranges *= 2) {
    std::vector<uint32_t> next(2 * ranges + 1);
    tbb::parallel_for(uint32_t(0), ranges, [&](uint32_t r) {
      const uint32_t lo = bounds[r], hi = bounds[r + 1], mid = lo + (hi - lo) / 2;
      glm::vec3 a(INFINITY), b(-INFINITY);
      for (uint32_t k = lo; k < hi; ++k) {
        a = glm::min(a, position[c.order[k]]);
        b = glm::max(b, position[c.order[k]]);
      }
      const glm::vec3 e = b - a;
      const int axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
      std::nth_element(c.order.begin() + lo, c.order.begin() + mid, c.order.begin() + hi,
                       [&](uint32_t i, uint32_t j) {
                         const float pi = position[i][axis], pj = position[j][axis];
                         return pi < pj || (pi == pj && i < j);
                       });
      next[2 * r] = lo;
      next[2 * r + 1] = mid;
    });
    next[2 * ranges] = n;
    bounds.swap(next);
  }
  c.first = std::move(bounds);
  return c;
}

}  // namespace nestlight::gi::projection
