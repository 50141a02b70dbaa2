// Seeds of the reference's random streams, shared by its renders and its bakes.
#pragma once

#include <cstdint>

namespace nestlight::gi {

// splitmix64's finaliser (Steele, Lea and Flood, "Fast Splittable Pseudorandom Number
// Generators", 2014): seeds from neighbouring indices (pixels, points) must not give correlated
// PCG streams.
inline uint64_t splitMix64(uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace nestlight::gi
