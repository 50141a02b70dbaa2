#pragma once

#include <cstdint>
#include <glm/vec3.hpp>
#include <vector>

namespace nestlight::gi::projection {

// The point set's clusters (Maletz, Wang and Bowers 2011, section 4.1): a k-d tree of median
// splits, each on the longest axis of its points' bounding box, down to `clusters` leaves of
// equal count (+-1). Splits go by rank, not by value, so ties at the median (a million
// coincident points) still split evenly, and every point lands in exactly one cluster.
struct Clusters {
  // Point indices ordered cluster by cluster: cluster k is order[first[k] .. first[k + 1]).
  std::vector<uint32_t> order;
  std::vector<uint32_t> first;  // clusters + 1 entries
  // Clusters made: `requested`, or the largest power of two not above the finite points'
  // count (fewer points than clusters), 1 for none.
  uint32_t count = 0;
  uint32_t requested = 0;
  uint64_t rejected = 0;  // non-finite positions, in no cluster
};

// `clusters` must be a power of two (the parameters say so to the user).
Clusters buildClusters(const std::vector<glm::vec3>& position, uint32_t clusters);

}  // namespace nestlight::gi::projection
