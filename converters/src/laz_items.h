// Item decoders of LASzip's pointwise compressors and what they share. Private to
// converters/src: laz_pointwise.cpp (version 2 items and the chunk) and laz_pointwise_v1.cpp
// (version 1 items).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <memory>

#include "laz_arithmetic.h"
#include "laz_format.h"

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

// Context of the x/y/intensity models by (number of returns, return number): 0-14 for the
// valid combinations, the rest for files that number returns from 0 or swap the two fields.
constexpr uint8_t kReturnMap[8][8] = {
    {15, 14, 13, 12, 11, 10, 9, 8},  {14, 0, 1, 3, 6, 10, 10, 9},
    {13, 1, 2, 4, 7, 11, 11, 10},    {12, 3, 4, 5, 8, 12, 12, 11},
    {11, 6, 7, 8, 9, 13, 13, 12},    {10, 10, 11, 12, 13, 14, 14, 13},
    {9, 10, 11, 12, 13, 14, 15, 14}, {8, 9, 10, 11, 12, 13, 14, 15}};
// Context of the height model: the distance between return number and number of returns.
constexpr uint8_t returnLevel(uint32_t n, uint32_t r) {
  return static_cast<uint8_t>(n > r ? n - r : r - n);
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

// Symbol models created on first use and reset for every chunk: the reference creates them
// lazily and re-initialises the existing ones per chunk, which decodes the same.
class LazyModels {
 public:
  explicit LazyModels(uint32_t symbols) : symbols_(symbols) {}
  SymbolModel& operator[](size_t i) {
    if (!models_[i]) models_[i] = std::make_unique<SymbolModel>(symbols_);
    if (generation_[i] != current_) {
      models_[i]->reset();
      generation_[i] = current_;
    }
    return *models_[i];
  }
  void reset() { ++current_; }

 private:
  uint32_t symbols_;
  uint32_t current_ = 1;
  std::array<std::unique_ptr<SymbolModel>, 256> models_;
  std::array<uint32_t, 256> generation_{};
};

// One item (a field group of the record) of a pointwise-compressed point.
class ItemDecoder {
 public:
  virtual ~ItemDecoder() = default;
  // Starts a chunk whose first record (this item's bytes) is `first`.
  virtual void init(const uint8_t* first) = 0;
  virtual void read(ArithmeticDecoder& dec, uint8_t* out) = 0;
};

// Version 1 items (LASzip 1.x): POINT10, GPSTIME11, RGB12, BYTE; nullptr for others.
std::unique_ptr<ItemDecoder> makeItemV1(const Item& item);

}  // namespace nestlight::laz
