// Small facts shared by the LAZ decoders and encoder: little-endian field access, the byte
// arithmetic of LASzip's predictors, and its streaming median. Private to converters/src.
#pragma once

#include <cstdint>
#include <cstring>

namespace nestlight::laz {

template <typename T>
T get(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
template <typename T>
void put(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

inline uint8_t fold8(int32_t v) {
  return static_cast<uint8_t>(v);
}  // wraps like U8_FOLD
inline int32_t clamp8(int32_t v) {
  return v <= 0 ? 0 : (v >= 255 ? 255 : v);
}

// Median of the last five values, updated in O(1) (LASzip's "streaming median").
struct Median5 {
  int32_t v[5] = {0, 0, 0, 0, 0};
  bool high = true;
  int32_t get() const { return v[2]; }
  void add(int32_t x) {
    if (high) {
      if (x < v[2]) {
        v[4] = v[3];
        v[3] = v[2];
        if (x < v[0]) {
          v[2] = v[1];
          v[1] = v[0];
          v[0] = x;
        } else if (x < v[1]) {
          v[2] = v[1];
          v[1] = x;
        } else {
          v[2] = x;
        }
      } else {
        if (x < v[3]) {
          v[4] = v[3];
          v[3] = x;
        } else {
          v[4] = x;
        }
        high = false;
      }
    } else {
      if (v[2] < x) {
        v[0] = v[1];
        v[1] = v[2];
        if (v[4] < x) {
          v[2] = v[3];
          v[3] = v[4];
          v[4] = x;
        } else if (v[3] < x) {
          v[2] = v[3];
          v[3] = x;
        } else {
          v[2] = x;
        }
      } else {
        if (v[1] < x) {
          v[0] = v[1];
          v[1] = x;
        } else {
          v[0] = x;
        }
        high = true;
      }
    }
  }
};

}  // namespace nestlight::laz
