// Item decoders of LASzip's pointwise compressors and what they share. Private to
// converters/src: laz_pointwise.cpp (version 2 items and the chunk) and laz_pointwise_v1.cpp
// (version 1 items).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/common.h"
#include "laz/format.h"

namespace nestlight::laz {

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

// Symbol models created on first use and reset for every chunk: the reference creates them
// lazily and re-initialises the existing ones per chunk, which decodes the same.
class LazyModels {
 public:
  explicit LazyModels(uint32_t symbols) : symbols_(symbols) {}
  SymbolModel& operator[](size_t i) {
    if (!models_[i]) models_[i] = std::make_unique<SymbolModel>(symbols_, false);  // reset below
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
  // Reads this item of one point of each of two chunks: this decoder's with `a`, `twin`'s (an
  // item decoder of the same type) with `b`. Items that interleave the two streams symbol by
  // symbol override it; the two chains of interval arithmetic then overlap in the processor.
  virtual void readPair(ItemDecoder& twin, ArithmeticDecoder& a, uint8_t* outA,
                        ArithmeticDecoder& b, uint8_t* outB) {
    read(a, outA);
    twin.read(b, outB);
  }
};

// The state of the version 2 coders, shared by the decoders (laz_pointwise.cpp) and the encoders
// (laz_writer.cpp), which inherit it: their models must update in lock-step, so they are one
// definition.
struct Point10V2State {
  uint8_t last_[20] = {};
  Median5 xMedian_[16], yMedian_[16];
  uint16_t lastIntensity_[16] = {};
  int32_t lastHeight_[8] = {};
  SymbolModel changed_{64};
  IntegerDecoder intensity_{16, 4};
  SymbolModel scanAngle_[2] = {SymbolModel(256), SymbolModel(256)};
  IntegerDecoder pointSource_{16};
  LazyModels bitByte_{256}, classification_{256}, userData_{256};
  IntegerDecoder dx_{32, 2}, dy_{32, 22}, dz_{32, 20};

  void reset(const uint8_t* first) {
    for (int i = 0; i < 16; ++i) {
      xMedian_[i] = Median5();
      yMedian_[i] = Median5();
      lastIntensity_[i] = 0;
      lastHeight_[i / 2] = 0;
    }
    changed_.reset();
    intensity_.reset();
    scanAngle_[0].reset();
    scanAngle_[1].reset();
    pointSource_.reset();
    bitByte_.reset();
    classification_.reset();
    userData_.reset();
    dx_.reset();
    dy_.reset();
    dz_.reset();
    std::memcpy(last_, first, 20);
  }
};

struct GpsTime11V2State {
  static constexpr int32_t kMulti = 500;
  static constexpr int32_t kMultiMinus = -10;
  static constexpr int32_t kMultiUnchanged = kMulti - kMultiMinus + 1;
  static constexpr int32_t kMultiCodeFull = kMulti - kMultiMinus + 2;
  static constexpr int32_t kMultiTotal = kMulti - kMultiMinus + 6;

  uint32_t last_ = 0, next_ = 0;  // four interleaved time sequences
  uint64_t time_[4] = {};
  int32_t lastDiff_[4] = {};
  int32_t extreme_[4] = {};
  SymbolModel multi_{kMultiTotal};
  SymbolModel zeroDiff_{6};
  IntegerDecoder ic_{32, 9};

  void reset(const uint8_t* first) {
    last_ = next_ = 0;
    for (int i = 0; i < 4; ++i) lastDiff_[i] = extreme_[i] = 0, time_[i] = 0;
    multi_.reset();
    zeroDiff_.reset();
    ic_.reset();
    time_[0] = get<uint64_t>(first);
  }
  // A difference far from the predicted multiple: after four in a row it becomes the new step.
  void countExtreme(int32_t diff) {
    if (++extreme_[last_] > 3) {
      lastDiff_[last_] = diff;
      extreme_[last_] = 0;
    }
  }
};

struct Rgb12V2State {
  uint16_t last_[3] = {};
  SymbolModel byteUsed_{128};
  SymbolModel diff_[6] = {SymbolModel(256), SymbolModel(256), SymbolModel(256),
                          SymbolModel(256), SymbolModel(256), SymbolModel(256)};
  void reset(const uint8_t* first) {
    byteUsed_.reset();
    for (auto& m : diff_) m.reset();
    for (int c = 0; c < 3; ++c) last_[c] = get<uint16_t>(first + 2 * c);
  }
};

struct ByteV2State {
  std::vector<uint8_t> last_;
  std::vector<SymbolModel> models_;  // one per byte
  explicit ByteV2State(size_t n) : last_(n) {
    models_.reserve(n);
    for (size_t i = 0; i < n; ++i) models_.emplace_back(256);
  }
  void reset(const uint8_t* first) {
    for (auto& m : models_) m.reset();
    std::memcpy(last_.data(), first, last_.size());
  }
};

// Version 1 items (LASzip 1.x): POINT10, GPSTIME11, RGB12, BYTE; nullptr for others.
std::unique_ptr<ItemDecoder> makeItemV1(const Item& item);

}  // namespace nestlight::laz
