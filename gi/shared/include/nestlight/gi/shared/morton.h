// 64-bit Morton codes (21 bits per axis, 63 used) and a radix sort of them: the first steps of
// the bounding-sphere hierarchy's construction (Sabbadin et al. 2019, section 5.1, after Karras
// 2012). The paper sorts on the GPU (Ha et al. 2009); here each octree node is built on a loader
// thread, so one LSD radix sort per node, on the CPU.
#pragma once

#include <cstdint>
#include <vector>

namespace nestlight::gi {

inline constexpr int kMortonBitsPerAxis = 21;
inline constexpr uint32_t kMortonAxisMax = (1u << kMortonBitsPerAxis) - 1;

// x, y, z in [0, 2^21): their bits interleaved, z lowest (the octree's mortonEncode21, checked).
uint64_t mortonCode(uint32_t x, uint32_t y, uint32_t z);

// Sorts `keys` ascending and applies the same permutation to `values` (stable: equal keys keep
// their order). LSD radix, 8 bits per pass, passes over bytes that every key shares skipped.
void radixSortPairs(std::vector<uint64_t>& keys, std::vector<uint32_t>& values);

}  // namespace nestlight::gi
