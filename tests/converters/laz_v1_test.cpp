// LASzip version 1 items (LASzip 1.x files: POINT10, GPSTIME11, RGB12, BYTE v1) through the
// pointwise chunk decoder. No LASzip 1.x file is at hand, so this file carries an encoder for
// each item, written from the reference writer (laswriteitemcompressed_v1, LASzip 1.x/2.x), and
// checks that decoding inverts it byte for byte on synthetic scans. Because encoder and decoder
// come from the same hand, some checks do not use the encoder at all: a stream of zero bytes
// (every model's first symbol) must repeat the first point, and short streams built from the
// coder's primitives by following the reference step by step must decode to the stated points.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/common.h"
#include "laz/format.h"
#include "laz/items.h"

namespace laz = nestlight::laz;

namespace {

using laz::get;  // little-endian field access (laz/common.h)
using laz::put;

// ---- the encoders (LASzip's version 1 writer) -------------------------------------------------

class ItemEncoder {
 public:
  virtual ~ItemEncoder() = default;
  virtual void init(const uint8_t* first) = 0;
  virtual void write(laz::ArithmeticEncoder& enc, const uint8_t* item) = 0;
};

class Point10Enc final : public ItemEncoder {
 public:
  void init(const uint8_t* first) override { std::memcpy(last_, first, 20); }
  void write(laz::ArithmeticEncoder& enc, const uint8_t* item) override {
    // The median of the last three differences, by sorting a copy (the decoder uses min/max).
    auto median = [](const int32_t* v) {
      int32_t s[3] = {v[0], v[1], v[2]};
      std::sort(s, s + 3);
      return s[1];
    };
    const int32_t dx = int32_t(get<uint32_t>(item) - get<uint32_t>(last_));
    const int32_t dy = int32_t(get<uint32_t>(item + 4) - get<uint32_t>(last_ + 4));
    dx_.compress(enc, median(lastDx_), dx, 0);
    uint32_t k = dx_.k();
    dy_.compress(enc, median(lastDy_), dy, std::min(k, 19u));
    k = (k + dy_.k()) / 2;
    dz_.compress(enc, get<int32_t>(last_ + 8), get<int32_t>(item + 8), std::min(k, 19u));
    const uint32_t changed = (get<uint16_t>(item + 12) != get<uint16_t>(last_ + 12)) << 5 |
                             (item[14] != last_[14]) << 4 | (item[15] != last_[15]) << 3 |
                             (item[16] != last_[16]) << 2 | (item[17] != last_[17]) << 1 |
                             (get<uint16_t>(item + 18) != get<uint16_t>(last_ + 18));
    enc.encodeSymbol(changed_, changed);
    if (changed & 32) intensity_.compress(enc, get<uint16_t>(last_ + 12), get<uint16_t>(item + 12));
    if (changed & 16) enc.encodeSymbol(bitByte_[last_[14]], item[14]);
    if (changed & 8) enc.encodeSymbol(classification_[last_[15]], item[15]);
    if (changed & 4) scanAngle_.compress(enc, last_[16], item[16], k < 3 ? 1 : 0);
    if (changed & 2) enc.encodeSymbol(userData_[last_[17]], item[17]);
    if (changed & 1)
      pointSource_.compress(enc, get<uint16_t>(last_ + 18), get<uint16_t>(item + 18));
    lastDx_[slot_] = dx;
    lastDy_[slot_] = dy;
    slot_ = (slot_ + 1) % 3;
    std::memcpy(last_, item, 20);
  }

 private:
  uint8_t last_[20] = {};
  int32_t lastDx_[3] = {}, lastDy_[3] = {};
  int slot_ = 0;
  laz::IntegerDecoder dx_{32, 1}, dy_{32, 20}, dz_{32, 20};
  laz::IntegerDecoder intensity_{16, 1}, scanAngle_{8, 2}, pointSource_{16, 1};
  laz::SymbolModel changed_{64};
  laz::LazyModels bitByte_{256}, classification_{256}, userData_{256};
};

class GpsTimeEnc final : public ItemEncoder {
 public:
  void init(const uint8_t* first) override { last_ = get<int64_t>(first); }
  void write(laz::ArithmeticEncoder& enc, const uint8_t* item) override {
    const int64_t now = get<int64_t>(item);
    const bool same = now == last_;
    const int64_t diff64 = int64_t(uint64_t(now) - uint64_t(last_));
    const bool fits = diff64 == int64_t(int32_t(diff64));
    const int32_t diff = int32_t(diff64);
    if (lastDiff_ == 0) {
      if (same) {
        enc.encodeSymbol(zeroDiff_, 0);
      } else if (fits) {
        enc.encodeSymbol(zeroDiff_, 1);
        ic_.compress(enc, 0, diff, 0);
        lastDiff_ = diff;
      } else {
        enc.encodeSymbol(zeroDiff_, 2);
        writeInt64(enc, uint64_t(now));
      }
    } else if (same) {
      enc.encodeSymbol(multi_, 511);
    } else if (!fits) {
      enc.encodeSymbol(multi_, 510);
      writeInt64(enc, uint64_t(now));
    } else {
      // The reference rounds the ratio in single precision and clamps it to 0..509.
      const float q = float(diff) / float(lastDiff_) + 0.5f;
      const uint32_t multi = q >= 509.0f ? 509u : (q < 1.0f ? 0u : uint32_t(q));
      enc.encodeSymbol(multi_, multi);
      if (multi == 1) {
        ic_.compress(enc, lastDiff_, diff, 1);
        lastDiff_ = diff;
        extreme_ = 0;
      } else if (multi == 0) {
        ic_.compress(enc, lastDiff_ / 4, diff, 2);
        countExtreme(diff);
      } else {
        const int32_t pred = int32_t(multi * uint32_t(lastDiff_));
        ic_.compress(enc, pred, diff, multi < 10 ? 3 : multi < 50 ? 4 : 5);
        if (multi == 509) countExtreme(diff);
      }
    }
    last_ = now;
  }

 private:
  static void writeInt64(laz::ArithmeticEncoder& enc, uint64_t v) {
    enc.writeInt(uint32_t(v));
    enc.writeInt(uint32_t(v >> 32));
  }
  void countExtreme(int32_t diff) {
    if (++extreme_ > 3) {
      lastDiff_ = diff;
      extreme_ = 0;
    }
  }
  int64_t last_ = 0;
  int32_t lastDiff_ = 0, extreme_ = 0;
  laz::SymbolModel multi_{512}, zeroDiff_{3};
  laz::IntegerDecoder ic_{32, 6};
};

class Rgb12Enc final : public ItemEncoder {
 public:
  void init(const uint8_t* first) override { std::memcpy(last_, first, 6); }
  void write(laz::ArithmeticEncoder& enc, const uint8_t* item) override {
    uint32_t used = 0;
    for (int i = 0; i < 6; ++i) used |= uint32_t(item[i] != last_[i]) << i;
    enc.encodeSymbol(used_, used);
    for (uint32_t i = 0; i < 6; ++i)
      if (used >> i & 1) ic_.compress(enc, last_[i], item[i], i);
    std::memcpy(last_, item, 6);
  }

 private:
  uint8_t last_[6] = {};
  laz::SymbolModel used_{64};
  laz::IntegerDecoder ic_{8, 6};
};

class ByteEnc final : public ItemEncoder {
 public:
  explicit ByteEnc(size_t n) : last_(n), ic_(8, uint32_t(n)) {}
  void init(const uint8_t* first) override { std::memcpy(last_.data(), first, last_.size()); }
  void write(laz::ArithmeticEncoder& enc, const uint8_t* item) override {
    for (uint32_t i = 0; i < last_.size(); ++i) ic_.compress(enc, last_[i], item[i], i);
    std::memcpy(last_.data(), item, last_.size());
  }

 private:
  std::vector<uint8_t> last_;
  laz::IntegerDecoder ic_;
};

std::unique_ptr<ItemEncoder> makeEncoder(const laz::Item& it) {
  switch (it.type) {
    case laz::ItemType::Point10:
      return std::make_unique<Point10Enc>();
    case laz::ItemType::GpsTime11:
      return std::make_unique<GpsTimeEnc>();
    case laz::ItemType::Rgb12:
      return std::make_unique<Rgb12Enc>();
    case laz::ItemType::Byte:
      return std::make_unique<ByteEnc>(it.size);
    default:
      return nullptr;
  }
}

laz::LaszipInfo infoOf(const std::vector<laz::Item>& items) {
  laz::LaszipInfo info;
  info.compressor = laz::Compressor::Pointwise;  // LASzip 1.x: one stream, no chunk table
  info.versionMajor = 1;
  info.versionMinor = 2;
  info.chunkSize = laz::kVariableChunkSize;
  info.items = items;
  return info;
}

// One chunk as the decoder expects it: the first record raw, then the arithmetic stream of the
// others (fresh models, as at every chunk start).
std::vector<uint8_t> encodeChunk(const laz::LaszipInfo& info, const std::vector<uint8_t>& records) {
  const size_t rs = info.recordSize();
  const size_t count = records.size() / rs;
  std::vector<uint8_t> out(records.begin(), records.begin() + ptrdiff_t(rs));
  std::vector<std::unique_ptr<ItemEncoder>> encs;
  std::vector<size_t> offsets;
  size_t at = 0;
  for (const laz::Item& it : info.items) {
    encs.push_back(makeEncoder(it));
    offsets.push_back(at);
    encs.back()->init(records.data() + at);
    at += it.size;
  }
  laz::ArithmeticEncoder enc(out);
  for (size_t p = 1; p < count; ++p)
    for (size_t i = 0; i < encs.size(); ++i)
      encs[i]->write(enc, records.data() + p * rs + offsets[i]);
  enc.done();
  return out;
}

// ---- synthetic scans ------------------------------------------------------------------------

// An airborne-like scan: pulses of 1-3 returns along scan lines (x steps, y per line), ground
// height walking with buildings, intensities per return, a few classes, scan angle following
// the line, flight lines with their own source id and a jump in time; colours in runs of gray,
// 8-bit-scaled and 16-bit colour; extra bytes with a counter, a constant and noise.
std::vector<uint8_t> synthesise(const laz::LaszipInfo& info, size_t count, uint64_t seed,
                                double t0) {
  std::mt19937_64 rng(seed);
  auto uni = [&](int lo, int hi) { return int(std::uniform_int_distribution<int>(lo, hi)(rng)); };
  auto chance = [&](double p) { return std::uniform_real_distribution<double>(0, 1)(rng) < p; };
  const size_t rs = info.recordSize();
  std::vector<uint8_t> out(rs * count);
  int32_t x = uni(-100000, 100000), y = uni(-100000, 100000), ground = uni(0, 50000);
  int32_t z = ground;
  uint16_t intensity = uint16_t(uni(0, 4000)), source = uint16_t(uni(1, 30));
  uint8_t cls = 2, user = 0, dir = 0, edge = 0;
  int n = 1, r = 1, column = 0;
  double t = t0, step = 1.0e-5;
  uint16_t rgb[3] = {uint16_t(uni(0, 65535)), uint16_t(uni(0, 65535)), uint16_t(uni(0, 65535))};
  int colourMode = 0;
  uint8_t counter = uint8_t(seed);
  for (size_t p = 0; p < count; ++p) {
    uint8_t* rec = out.data() + p * rs;
    if (r >= n) {  // a new pulse
      n = chance(0.7) ? 1 : uni(2, 3);
      r = 1;
      edge = 0;
      if (++column == 400) {  // next scan line: back across, one step forward
        column = 0;
        x -= 400 * 25;
        y += 35;
        dir ^= 1;
        edge = 1;
      }
      x += 25 + uni(-4, 4);
      y += uni(-1, 1);
      if (chance(0.002)) x += uni(-2000000, 2000000);  // a stray far point
      ground += uni(-8, 8);
      z = ground + (chance(0.05) ? uni(2000, 9000) : 0);
      // Time: mostly the regular pulse rate, sometimes gaps of a few to hundreds of pulses, a
      // step back, or a new flight line (a jump too large for 32 bits, new source id).
      double dt = step;
      if (chance(0.05)) dt = step * uni(2, 9);
      if (chance(0.02)) dt = step * uni(10, 60);
      if (chance(0.005)) dt = step * uni(500, 3000);
      if (chance(0.005)) dt = -step * uni(1, 5);
      if (chance(0.0015)) {
        dt = 1800.0 + uni(0, 600);
        source = uint16_t(source + 1);
      }
      if (!chance(0.01)) t += dt;  // else a repeated time stamp
      if (chance(0.01)) step *= 1.0 + uni(-100, 100) / 1000.0;
    } else {
      ++r;
      x += uni(-2, 2);
      y += uni(-2, 2);
      z -= uni(100, 2500);
    }
    // Intensity: a third unchanged, mostly small changes, sometimes anything.
    if (chance(0.66))
      intensity = chance(0.03) ? uint16_t(uni(0, 65535)) : uint16_t(intensity + uni(-60, 60));
    if (chance(0.06)) {
      static constexpr uint8_t kClasses[] = {1, 2, 3, 4, 5, 6, 7, 9, 17};
      cls = kClasses[uni(0, 8)];
    }
    if (chance(0.01)) user = uint8_t(uni(0, 255));
    const int8_t angle = int8_t(std::clamp(-30 + column * 60 / 400 + (dir ? 0 : 1), -90, 90));
    put<int32_t>(rec, x);
    put<int32_t>(rec + 4, y);
    put<int32_t>(rec + 8, z);
    put<uint16_t>(rec + 12, intensity);
    rec[14] = uint8_t(r | n << 3 | dir << 6 | edge << 7);
    rec[15] = cls;
    rec[16] = uint8_t(angle);
    rec[17] = user;
    put<uint16_t>(rec + 18, source);
    // The other items at their offsets.
    if (chance(0.005)) colourMode = uni(0, 4);
    switch (colourMode) {
      case 0: {  // gray, 8 bits scaled to 16 (both bytes equal)
        if (chance(0.5)) {
          const uint16_t g = uint16_t(std::clamp(int(rgb[0] >> 8) + uni(-6, 6), 0, 255) * 257);
          rgb[0] = rgb[1] = rgb[2] = g;
        }
        break;
      }
      case 1:  // 16-bit colour walking in every byte
        for (auto& c : rgb) c = uint16_t(c + uni(-300, 300));
        break;
      case 2:
        break;  // a run of one colour
      case 3:   // only the low bytes move
        for (auto& c : rgb) c = uint16_t((c & 0xFF00) | uint8_t(c + uni(-3, 3)));
        break;
      default:  // 8-bit colour shifted up (low bytes zero)
        for (auto& c : rgb) c = uint16_t(std::clamp(int(c >> 8) + uni(-10, 10), 0, 255) << 8);
        break;
    }
    size_t at = 0;
    for (const laz::Item& it : info.items) {
      uint8_t* f = rec + at;
      switch (it.type) {
        case laz::ItemType::GpsTime11:
          put<double>(f, t);
          break;
        case laz::ItemType::Rgb12:
          for (int c = 0; c < 3; ++c) put<uint16_t>(f + 2 * c, rgb[c]);
          break;
        case laz::ItemType::Byte:
          for (size_t b = 0; b < it.size; ++b) {
            switch (b % 4) {
              case 0:
                f[b] = counter;
                break;
              case 1:
                f[b] = 0x5A;
                break;
              case 2:
                f[b] = chance(0.2) ? uint8_t(uni(0, 255)) : uint8_t(p > 0 ? rec[b + at - rs] : 0);
                break;
              default:
                f[b] = cls;
                break;
            }
          }
          ++counter;
          break;
        default:
          break;
      }
      at += it.size;
    }
  }
  return out;
}

// Index of the first differing record, or -1.
long firstDiff(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, size_t rs) {
  const size_t n = std::min(a.size(), b.size()) / rs;
  for (size_t p = 0; p < n; ++p)
    if (std::memcmp(a.data() + p * rs, b.data() + p * rs, rs) != 0) return long(p);
  return a.size() == b.size() ? -1 : long(n);
}

laz::Item item(laz::ItemType t, uint16_t size) {
  return {t, size, 1};
}
const laz::Item kPoint10 = item(laz::ItemType::Point10, 20);
const laz::Item kGps = item(laz::ItemType::GpsTime11, 8);
const laz::Item kRgb = item(laz::ItemType::Rgb12, 6);

struct Layout {
  const char* name;
  std::vector<laz::Item> items;
};

std::vector<Layout> layouts() {
  return {
      {"Format0", {kPoint10}},
      {"Format1", {kPoint10, kGps}},
      {"Format2", {kPoint10, kRgb}},
      {"Format3", {kPoint10, kGps, kRgb}},
      {"Format0Extra1", {kPoint10, item(laz::ItemType::Byte, 1)}},
      {"Format1Extra3", {kPoint10, kGps, item(laz::ItemType::Byte, 3)}},
      {"Format3Extra7", {kPoint10, kGps, kRgb, item(laz::ItemType::Byte, 7)}},
  };
}

class LazV1Formats : public testing::TestWithParam<Layout> {};

// Chunks in a row through one decoder object (its models and state must start afresh at each
// chunk): two of thousands of points, then one of two points, byte for byte.
TEST_P(LazV1Formats, DecodingInvertsTheReferenceEncoderOverTwoChunks) {
  const laz::LaszipInfo info = infoOf(GetParam().items);
  const size_t rs = info.recordSize();
  auto decoder = laz::makePointwiseDecoder(info);
  const struct {
    size_t count;
    uint64_t seed;
    double t0;
  } chunks[] = {{3000, 11, 320000.5}, {4500, 12, 2.7e8}, {2, 13, 1000.0}};
  for (const auto& c : chunks) {
    const std::vector<uint8_t> points = synthesise(info, c.count, c.seed, c.t0);
    const std::vector<uint8_t> chunk = encodeChunk(info, points);
    std::vector<uint8_t> out(points.size(), 0xCD);
    const size_t used = decoder->decode(chunk.data(), chunk.size(), uint32_t(c.count), out.data());
    EXPECT_EQ(firstDiff(out, points, rs), -1) << "chunk of seed " << c.seed;
    EXPECT_LE(used, chunk.size());
    EXPECT_GE(used + 4, chunk.size()) << "the decoder stops within the encoder's padding";
    // Compression happened (the scans are realistic, not noise).
    if (c.count > 1000) {
      EXPECT_LT(chunk.size(), points.size() / 2) << chunk.size();
    }
  }
}

TEST_P(LazV1Formats, TruncatedChunksThrowAndGarbageStaysInBounds) {
  const laz::LaszipInfo info = infoOf(GetParam().items);
  const size_t rs = info.recordSize();
  const std::vector<uint8_t> points = synthesise(info, 2000, 21, 5000.0);
  const std::vector<uint8_t> chunk = encodeChunk(info, points);
  auto decoder = laz::makePointwiseDecoder(info);
  std::vector<uint8_t> out(points.size());
  for (size_t keep : {size_t(0), rs - 1, rs, rs + 3, rs + (chunk.size() - rs) / 3, chunk.size() / 2,
                      chunk.size() - 16}) {
    std::vector<uint8_t> cut(chunk.begin(), chunk.begin() + ptrdiff_t(keep));
    EXPECT_THROW(decoder->decode(cut.data(), cut.size(), 2000, out.data()), laz::DecodeError)
        << "kept " << keep << " of " << chunk.size();
  }
  // The decoder is still good after the errors.
  EXPECT_NO_THROW(decoder->decode(chunk.data(), chunk.size(), 2000, out.data()));
  EXPECT_EQ(firstDiff(out, points, rs), -1);

  // Garbage: random bytes (and damaged real streams) decode or throw DecodeError, nothing else.
  std::mt19937_64 rng(99);
  for (int round = 0; round < 40; ++round) {
    std::vector<uint8_t> junk;
    if (round % 2) {
      junk = chunk;
      for (int f = 0; f < 1 + round; ++f)
        junk[rs + rng() % (junk.size() - rs)] ^= uint8_t(1 + rng() % 255);
    } else {
      junk.resize(rs + 16 + rng() % 4000);
      for (auto& b : junk) b = uint8_t(rng());
      if (round % 4 == 2) std::fill(junk.begin() + ptrdiff_t(rs), junk.end(), 0xFF);
    }
    try {
      decoder->decode(junk.data(), junk.size(), 2000, out.data());
    } catch (const laz::DecodeError&) {
    }
    EXPECT_EQ(std::memcmp(out.data(), junk.data(), rs), 0) << "the first point is stored raw";
  }
}

INSTANTIATE_TEST_SUITE_P(LazV1, LazV1Formats, testing::ValuesIn(layouts()),
                         [](const testing::TestParamInfo<Layout>& i) {
                           return std::string(i.param.name);
                         });

// ---- checks that do not use the encoder above --------------------------------------------------

// A stream of zero bytes makes the decoder take every model's first symbol: k = 0 with a zero
// corrector bit (difference 0 to the prediction, which starts at the last value, or at the zero
// median of x/y differences), no changed fields, no changed colour bytes, time "unchanged". So
// every point repeats the first, whatever its bytes.
TEST(LazV1, ZeroStreamRepeatsTheFirstPoint) {
  const laz::LaszipInfo info = infoOf({kPoint10, kGps, kRgb, item(laz::ItemType::Byte, 5)});
  const size_t rs = info.recordSize();
  std::vector<uint8_t> chunk(rs + 8192, 0);
  for (size_t i = 0; i < rs; ++i) chunk[i] = uint8_t(i * 37 + 200);
  std::vector<uint8_t> out(1000 * rs);
  auto decoder = laz::makePointwiseDecoder(info);
  const size_t used = decoder->decode(chunk.data(), chunk.size(), 1000, out.data());
  for (size_t p = 0; p < 1000; ++p)
    ASSERT_EQ(std::memcmp(out.data() + p * rs, chunk.data(), rs), 0) << "point " << p;
  EXPECT_LT(used, chunk.size());
}

// An unchanged point is cheap: nine adaptive models are in play (k of x, y and z and their
// zero-corrector bits, the change flags, the time's zero-difference symbol, the colour flags),
// each always sees its first symbol, so after the models have learnt that (a few hundred
// symbols at several bits each) a point costs a small fraction of a bit.
TEST(LazV1, IdenticalPointsCostFewBits) {
  const laz::LaszipInfo info = infoOf({kPoint10, kGps, kRgb});
  const size_t rs = info.recordSize();
  std::vector<uint8_t> points = synthesise(info, 1, 5, 1234.5);
  const std::vector<uint8_t> one = points;
  for (int i = 1; i < 1000; ++i) points.insert(points.end(), one.begin(), one.end());
  std::vector<uint8_t> chunk = encodeChunk(info, points);
  EXPECT_TRUE(std::equal(one.begin(), one.end(), chunk.begin())) << "the first point is stored raw";
  const size_t stream1000 = chunk.size() - rs;
  for (int i = 0; i < 9000; ++i) points.insert(points.end(), one.begin(), one.end());
  const size_t stream10000 = encodeChunk(info, points).size() - rs;
  EXPECT_LT(stream1000, 1000u * rs / 100) << "under 1% of the raw points, learning included";
  EXPECT_LT(stream10000 - stream1000, 9000u / 8 / 8)
      << "once learnt, under an eighth of a bit a point";
  std::vector<uint8_t> out(1000 * rs);
  laz::makePointwiseDecoder(info)->decode(chunk.data(), chunk.size(), 1000, out.data());
  EXPECT_TRUE(std::equal(out.begin(), out.end(), points.begin()));
}

// A stream spelt out from the coder's primitives, following the reference reader step by step
// (not through the encoder classes), with every context worked out by hand: the field order, k
// of x choosing y's context and the mean k choosing z's and the scan angle's, the median of the
// last three x differences, the first intensity as a prediction, models chosen by the previous
// byte, the time's multiplier symbols (a multiple, "same", raw in low-high order, below zero),
// colour bytes in record order, extra bytes each against their previous value.
TEST(LazV1, HandBuiltStreamDecodesAsTheReferenceReads) {
  const laz::LaszipInfo info = infoOf({kPoint10, kGps, kRgb, item(laz::ItemType::Byte, 2)});
  const size_t rs = info.recordSize();
  ASSERT_EQ(rs, 36u);
  std::vector<std::array<uint8_t, 36>> expect(7);
  uint8_t* p = expect[0].data();
  put<int32_t>(p, 1000);
  put<int32_t>(p + 4, -2000);
  put<int32_t>(p + 8, 300);
  put<uint16_t>(p + 12, 100);
  p[14] = 1 | 1 << 3;
  p[15] = 2;
  p[16] = uint8_t(int8_t(-5));
  p[17] = 7;
  put<uint16_t>(p + 18, 42);
  put<int64_t>(p + 20, 1000000);
  put<uint16_t>(p + 28, 0x1234);
  put<uint16_t>(p + 30, 0x5678);
  put<uint16_t>(p + 32, 0x9ABC);
  p[34] = 10;
  p[35] = 250;
  const uint64_t rawTime = (uint64_t(1) << 40) + 12345;

  std::vector<uint8_t> chunk(expect[0].begin(), expect[0].end());
  {
    laz::ArithmeticEncoder enc(chunk);
    laz::IntegerDecoder dx(32, 1), dy(32, 20), dz(32, 20), inten(16, 1), angle(8, 2), source(16, 1);
    laz::SymbolModel changed(64), bitByte9(256), class2(256);
    laz::SymbolModel multi(512), zero(3);
    laz::IntegerDecoder time(32, 6), rgb(8, 6), bytes(8, 2);
    laz::SymbolModel used(64);
    // Point 2: x + 5 against the zero median (corrector 5: k = 3), y the same in context 3,
    // z + 4 in context (3 + 0) / 2 = 1; intensity 100 -> 90, class 2 -> 6. Time + 100 after a
    // zero difference: symbol 1 of the 3-symbol model, the difference against 0 in context 0.
    // Green's high byte 0x56 -> 0x57 (bit 3, context 3). Extra byte 0: 10 -> 11.
    dx.compress(enc, 0, 5, 0);
    dy.compress(enc, 0, 0, 3);
    dz.compress(enc, 300, 304, 1);
    enc.encodeSymbol(changed, 32 | 8);
    inten.compress(enc, 100, 90, 0);
    enc.encodeSymbol(class2, 6);
    enc.encodeSymbol(zero, 1);
    time.compress(enc, 0, 100, 0);
    enc.encodeSymbol(used, 1 << 3);
    rgb.compress(enc, 0x56, 0x57, 3);
    bytes.compress(enc, 10, 11, 0);
    bytes.compress(enc, 250, 250, 1);
    // Point 3: x + 7 against the median of {5, 0, 0} = 0 (k = 3), y - 1 in context 3 (k = 1),
    // z the same in context (3 + 1) / 2 = 2; return byte 9 -> 17 (model of 9), scan angle
    // 251 -> 252 in context 1 (mean k 2 < 3). Time + 300: multiplier 3 (context 3). Extra byte
    // 1: 250 -> 0.
    dx.compress(enc, 0, 7, 0);
    dy.compress(enc, 0, -1, 3);
    dz.compress(enc, 304, 304, 2);
    enc.encodeSymbol(changed, 16 | 4);
    enc.encodeSymbol(bitByte9, 17);
    angle.compress(enc, 251, 252, 1);
    enc.encodeSymbol(multi, 3);
    time.compress(enc, 300, 300, 3);
    enc.encodeSymbol(used, 0);
    bytes.compress(enc, 11, 11, 0);
    bytes.compress(enc, 250, 0, 1);
    // Point 4: nothing moves; x against the median of {5, 7, 0} = 5 (corrector -5, k = 3), y in
    // context 3 (k = 0), z in context 1. Time the same: symbol 511.
    dx.compress(enc, 5, 0, 0);
    dy.compress(enc, 0, 0, 3);
    dz.compress(enc, 304, 304, 1);
    enc.encodeSymbol(changed, 0);
    enc.encodeSymbol(multi, 511);
    enc.encodeSymbol(used, 0);
    bytes.compress(enc, 11, 11, 0);
    bytes.compress(enc, 0, 0, 1);
    // Point 5: x + 5 against the median of {5, 7, 0} = 5 (k = 0): y and z in context 0; point
    // source 42 -> 43. Time 2^40 + 12345: symbol 510 and 64 raw bits, low half first. All six
    // colour bytes change.
    dx.compress(enc, 5, 5, 0);
    dy.compress(enc, 0, 0, 0);
    dz.compress(enc, 304, 304, 0);
    enc.encodeSymbol(changed, 1);
    source.compress(enc, 42, 43, 0);
    enc.encodeSymbol(multi, 510);
    enc.writeInt(uint32_t(rawTime));
    enc.writeInt(uint32_t(rawTime >> 32));
    enc.encodeSymbol(used, 63);
    const uint8_t before[6] = {0x34, 0x12, 0x78, 0x57, 0xBC, 0x9A},
                  after[6] = {0x35, 0x13, 0x77, 0x56, 0xFF, 0x00};
    for (uint32_t i = 0; i < 6; ++i) rgb.compress(enc, before[i], after[i], i);
    bytes.compress(enc, 11, 11, 0);
    bytes.compress(enc, 0, 0, 1);
    // Point 6: x against the median of {5, 7, 0} = 5 again (the slot of point 3's 7 is next).
    // The raw time left the reference difference at 100: + 97 is multiplier 1 (context 1).
    dx.compress(enc, 5, 0, 0);
    dy.compress(enc, 0, 0, 3);
    dz.compress(enc, 304, 304, 1);
    enc.encodeSymbol(changed, 0);
    enc.encodeSymbol(multi, 1);
    time.compress(enc, 100, 97, 1);
    enc.encodeSymbol(used, 0);
    bytes.compress(enc, 11, 11, 0);
    bytes.compress(enc, 0, 0, 1);
    // Point 7: x differences {5, 0, 0}: median 0 (k = 0). Time - 50: multiplier 0, predicted
    // by a quarter of the difference 97, i.e. 24, in context 2.
    dx.compress(enc, 0, 0, 0);
    dy.compress(enc, 0, 0, 0);
    dz.compress(enc, 304, 304, 0);
    enc.encodeSymbol(changed, 0);
    enc.encodeSymbol(multi, 0);
    time.compress(enc, 24, -50, 2);
    enc.encodeSymbol(used, 0);
    bytes.compress(enc, 11, 11, 0);
    bytes.compress(enc, 0, 0, 1);
    enc.done();
  }
  expect[1] = expect[0];
  p = expect[1].data();
  put<int32_t>(p, 1005);
  put<int32_t>(p + 8, 304);
  put<uint16_t>(p + 12, 90);
  p[15] = 6;
  put<int64_t>(p + 20, 1000100);
  put<uint16_t>(p + 30, 0x5778);
  p[34] = 11;
  expect[2] = expect[1];
  p = expect[2].data();
  put<int32_t>(p, 1012);
  put<int32_t>(p + 4, -2001);
  p[14] = 1 | 2 << 3;
  p[16] = uint8_t(int8_t(-4));
  put<int64_t>(p + 20, 1000400);
  p[35] = 0;
  expect[3] = expect[2];
  expect[4] = expect[3];
  p = expect[4].data();
  put<int32_t>(p, 1017);
  put<uint16_t>(p + 18, 43);
  put<uint64_t>(p + 20, rawTime);
  put<uint16_t>(p + 28, 0x1335);
  put<uint16_t>(p + 30, 0x5677);
  put<uint16_t>(p + 32, 0x00FF);
  expect[5] = expect[4];
  put<uint64_t>(expect[5].data() + 20, rawTime + 97);
  expect[6] = expect[5];
  put<uint64_t>(expect[6].data() + 20, rawTime + 97 - 50);

  std::vector<uint8_t> out(7 * rs);
  laz::makePointwiseDecoder(info)->decode(chunk.data(), chunk.size(), 7, out.data());
  for (size_t i = 0; i < 7; ++i)
    EXPECT_EQ(std::memcmp(out.data() + i * rs, expect[i].data(), rs), 0) << "point " << i + 1;
  // The encoder classes produce the very same stream from the points.
  std::vector<uint8_t> points;
  for (const auto& e : expect) points.insert(points.end(), e.begin(), e.end());
  EXPECT_EQ(encodeChunk(info, points), chunk);
}

TEST(LazV1, WavePacketsAndMismatchedItemsAreNotSupported) {
  EXPECT_EQ(laz::makeItemV1({laz::ItemType::WavePacket13, 29, 1}), nullptr);
  EXPECT_EQ(laz::makeItemV1({laz::ItemType::Point14, 30, 1}), nullptr);
  EXPECT_EQ(laz::makeItemV1({laz::ItemType::Point10, 20, 2}), nullptr);
  EXPECT_NE(laz::makeItemV1(kPoint10), nullptr);
  EXPECT_THROW(
      laz::makePointwiseDecoder(infoOf({kPoint10, kGps, item(laz::ItemType::WavePacket13, 29)})),
      laz::DecodeError);
}

// Extreme values: coordinate differences that wrap 32 bits (the corrector of INT32_MIN
// included), intensities and sources jumping across the 16-bit fold, scan angles across the
// sign, times stepping by the largest 32-bit differences and just beyond.
TEST(LazV1, ExtremeValuesRoundTrip) {
  const laz::LaszipInfo info = infoOf({kPoint10, kGps, kRgb, item(laz::ItemType::Byte, 2)});
  const size_t rs = info.recordSize();
  std::mt19937_64 rng(7);
  const int32_t xs[] = {INT32_MIN, INT32_MAX, 0, -1, 1, INT32_MIN + 1, INT32_MAX - 1};
  const int64_t dts[] = {
      INT32_MAX, INT32_MIN,       1, -1, 0, int64_t(INT32_MAX) + 1, int64_t(INT32_MIN) - 1, 3,
      1000000,   1000000 * 509LL, -7};
  std::vector<uint8_t> points(3000 * rs);
  int64_t t = 0;
  for (size_t i = 0; i < 3000; ++i) {
    uint8_t* r = points.data() + i * rs;
    for (int f = 0; f < 3; ++f) put<int32_t>(r + 4 * f, rng() % 3 ? xs[rng() % 7] : int32_t(rng()));
    put<uint16_t>(r + 12, uint16_t(rng() % 2 ? 0 : 65535 - rng() % 3));
    r[14] = uint8_t(rng());
    r[15] = uint8_t(rng() % 2 ? 0 : 255);
    r[16] = uint8_t(rng() % 2 ? 0x80 : 0x7F);
    r[17] = uint8_t(rng());
    put<uint16_t>(r + 18, uint16_t(rng() % 2 ? 0 : 0xFFFF));
    // The first steps: the same time, then a jump beyond 32 bits while no difference is known
    // yet (raw after the zero-difference symbol), then the same again.
    const int64_t dt = i == 2 ? int64_t(1) << 40 : i < 4 ? 0 : dts[rng() % 11];
    t = int64_t(uint64_t(t) + uint64_t(dt));
    put<int64_t>(r + 20, t);
    for (int b = 28; b < 36; ++b) r[b] = uint8_t(rng() % 2 ? 0 : 255);
  }
  const std::vector<uint8_t> chunk = encodeChunk(info, points);
  std::vector<uint8_t> out(points.size());
  laz::makePointwiseDecoder(info)->decode(chunk.data(), chunk.size(), 3000, out.data());
  EXPECT_EQ(firstDiff(out, points, rs), -1);
}

}  // namespace
