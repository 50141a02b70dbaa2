#include "nestlight/gi/shared/morton.h"

#include <array>

#include "nestlight/octree/error.h"
#include "nestlight/octree/node_key.h"

namespace nestlight::gi {

uint64_t mortonCode(uint32_t x, uint32_t y, uint32_t z) {
  NL_CHECK(x <= kMortonAxisMax && y <= kMortonAxisMax && z <= kMortonAxisMax);
  return mortonEncode21(x, y, z);
}

void radixSortPairs(std::vector<uint64_t>& keys, std::vector<uint32_t>& values) {
  NL_CHECK(keys.size() == values.size());
  const size_t n = keys.size();
  if (n < 2) return;
  // Histograms of all eight bytes in one pass over the keys.
  std::array<std::array<size_t, 256>, 8> count{};
  for (uint64_t k : keys)
    for (int b = 0; b < 8; ++b) count[b][(k >> (8 * b)) & 0xff]++;
  std::vector<uint64_t> k2(n);
  std::vector<uint32_t> v2(n);
  for (int b = 0; b < 8; ++b) {
    auto& c = count[b];
    bool shared = false;
    for (size_t d = 0; d < 256; ++d)
      if (c[d] == n) shared = true;  // every key has this byte: the pass would not move anything
    if (shared) continue;
    size_t sum = 0;
    for (auto& x : c) {
      const size_t t = x;
      x = sum;
      sum += t;
    }
    for (size_t i = 0; i < n; ++i) {
      const size_t dst = c[(keys[i] >> (8 * b)) & 0xff]++;
      k2[dst] = keys[i];
      v2[dst] = values[i];
    }
    keys.swap(k2);
    values.swap(v2);
  }
}

}  // namespace nestlight::gi
