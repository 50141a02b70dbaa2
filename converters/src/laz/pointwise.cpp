// LASzip's pointwise compressors (1: one stream, 2: chunked) for LAS point formats 0-5: the
// POINT10, GPSTIME11, RGB12 and BYTE items, versions 1 and 2.
//
// Isenburg, "LASzip: lossless compression of LiDAR data", Photogrammetric Engineering & Remote
// Sensing 79(2), 2013 (section "Compression": each field predicted from the previous point of the
// same return context, the residual entropy-coded with adaptive models); the bit-exact
// definition is the LASzip reference implementation 2.x (lasreaditemcompressed_v1/v2), which is
// the format's specification. Written here because Debian packages neither LASzip nor LAZperf.
//
// A chunk is the first point's record raw, then one arithmetic stream for the other points. The
// item decoders keep the reference's state and context rules exactly (they must reproduce its
// model updates); where the reference recurses or computes with signed overflow on a damaged
// stream, these loop with a bound and wrap unsigned.
#include <algorithm>
#include <array>
#include <cstring>
#include <memory>

#include "laz/arithmetic.h"
#include "laz/format.h"
#include "laz/items.h"

namespace nestlight::laz {
namespace {

// ---- version 2 ---------------------------------------------------------------------------------

// An item whose point decoding is written once for N chunks (`Item::readLanes<N>`): read() is
// one lane, readPair() two, interleaved symbol by symbol.
template <typename Item>
class LanedItem : public ItemDecoder {
 public:
  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    Item* s[1] = {static_cast<Item*>(this)};
    ArithmeticDecoder* d[1] = {&dec};
    uint8_t* o[1] = {out};
    Item::template readLanes<1>(s, d, o);
  }
  void readPair(ItemDecoder& twin, ArithmeticDecoder& a, uint8_t* outA, ArithmeticDecoder& b,
                uint8_t* outB) override {
    Item* s[2] = {static_cast<Item*>(this), static_cast<Item*>(&twin)};
    ArithmeticDecoder* d[2] = {&a, &b};
    uint8_t* o[2] = {outA, outB};
    Item::template readLanes<2>(s, d, o);
  }
};

class Point10V2 final : public LanedItem<Point10V2>, private Point10V2State {
 public:
  void init(const uint8_t* first) override {
    reset(first);
    last_[12] = last_[13] = 0;  // the reference predicts the first intensity from zero
  }

 private:
  friend class LanedItem<Point10V2>;
  // One point of each of N chunks; every step runs lane by lane (see decompressLanes). Within a
  // lane the order of the fields is the reference's: the changed-field mask, returns, intensity,
  // classification, scan angle, user data, point source, then x, y and z.
  template <size_t N>
  [[gnu::always_inline]] static inline void readLanes(Point10V2* const s[],
                                                      ArithmeticDecoder* const d[],
                                                      uint8_t* const out[]) {
    uint32_t changed[N], n[N], m[N], lv[N], high[N], ctx[N];
    int32_t pred[N], diff[N];
    IntegerDecoder* ic[N];
    for (size_t l = 0; l < N; ++l) changed[l] = d[l]->decodeSymbol(s[l]->changed_);
    for (size_t l = 0; l < N; ++l) {
      Point10V2& p = *s[l];
      if (changed[l] & 32)
        p.last_[14] = static_cast<uint8_t>(d[l]->decodeSymbol(p.bitByte_[p.last_[14]]));
      const uint32_t r = p.last_[14] & 7;
      n[l] = (p.last_[14] >> 3) & 7;
      m[l] = kReturnMap[n[l]][r];
      lv[l] = returnLevel(n[l], r);
    }
    for (size_t l = 0; l < N; ++l)
      if (changed[l] & 16) s[l]->intensity_.readK(*d[l], m[l] < 3 ? m[l] : 3);
    for (size_t l = 0; l < N; ++l)
      if (changed[l] & 16) high[l] = s[l]->intensity_.readHigh(*d[l]);
    for (size_t l = 0; l < N; ++l) {
      Point10V2& p = *s[l];
      ArithmeticDecoder& dec = *d[l];
      if (changed[l] & 16)
        p.lastIntensity_[m[l]] =
            static_cast<uint16_t>(p.intensity_.finish(dec, high[l], p.lastIntensity_[m[l]]));
      put<uint16_t>(p.last_ + 12, p.lastIntensity_[m[l]]);
      if (changed[l] & 8)
        p.last_[15] = static_cast<uint8_t>(dec.decodeSymbol(p.classification_[p.last_[15]]));
      if (changed[l] & 4) {
        const uint32_t v = dec.decodeSymbol(p.scanAngle_[(p.last_[14] >> 6) & 1]);
        p.last_[16] = fold8(static_cast<int32_t>(v + p.last_[16]));
      }
      if (changed[l] & 2)
        p.last_[17] = static_cast<uint8_t>(dec.decodeSymbol(p.userData_[p.last_[17]]));
      if (changed[l] & 1)
        put<uint16_t>(p.last_ + 18, static_cast<uint16_t>(p.pointSource_.decompress(
                                        dec, get<uint16_t>(p.last_ + 18))));
    }

    for (size_t l = 0; l < N; ++l) {
      ic[l] = &s[l]->dx_;
      pred[l] = s[l]->xMedian_[m[l]].get();
      ctx[l] = n[l] == 1;
    }
    IntegerDecoder::decompressLanes<N>(ic, d, pred, ctx, diff);
    for (size_t l = 0; l < N; ++l) {
      Point10V2& p = *s[l];
      put<uint32_t>(p.last_, get<uint32_t>(p.last_) + static_cast<uint32_t>(diff[l]));
      p.xMedian_[m[l]].add(diff[l]);
      const uint32_t kBits = p.dx_.k();
      ic[l] = &p.dy_;
      pred[l] = p.yMedian_[m[l]].get();
      ctx[l] = (n[l] == 1) + (kBits < 20 ? (kBits & ~1u) : 20);
    }
    IntegerDecoder::decompressLanes<N>(ic, d, pred, ctx, diff);
    for (size_t l = 0; l < N; ++l) {
      Point10V2& p = *s[l];
      put<uint32_t>(p.last_ + 4, get<uint32_t>(p.last_ + 4) + static_cast<uint32_t>(diff[l]));
      p.yMedian_[m[l]].add(diff[l]);
      const uint32_t kBits = (p.dx_.k() + p.dy_.k()) / 2;
      ic[l] = &p.dz_;
      pred[l] = p.lastHeight_[lv[l]];
      ctx[l] = (n[l] == 1) + (kBits < 18 ? (kBits & ~1u) : 18);
    }
    IntegerDecoder::decompressLanes<N>(ic, d, pred, ctx, diff);
    for (size_t l = 0; l < N; ++l) {
      Point10V2& p = *s[l];
      put<int32_t>(p.last_ + 8, diff[l]);
      p.lastHeight_[lv[l]] = diff[l];
      std::memcpy(out[l], p.last_, 20);
    }
  }
};

class GpsTime11V2 final : public ItemDecoder, private GpsTime11V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    // A switch to another of the four interleaved sequences is followed by that sequence's own
    // code; the reference recurses for it. Valid streams switch at most once per point, but a
    // damaged one may keep switching: bound it.
    for (int switches = 0; switches < 8; ++switches) {
      if (lastDiff_[last_] == 0) {
        const int32_t multi = static_cast<int32_t>(dec.decodeSymbol(zeroDiff_));
        if (multi == 1) {
          lastDiff_[last_] = ic_.decompress(dec, 0, 0);
          time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(lastDiff_[last_]));
          extreme_[last_] = 0;
        } else if (multi == 2) {
          readFull(dec);
        } else if (multi > 2) {
          last_ = (last_ + static_cast<uint32_t>(multi) - 2) & 3;
          continue;
        }
      } else {
        int32_t multi = static_cast<int32_t>(dec.decodeSymbol(multi_));
        if (multi == 1) {
          time_[last_] +=
              static_cast<uint64_t>(static_cast<int64_t>(ic_.decompress(dec, lastDiff_[last_], 1)));
          extreme_[last_] = 0;
        } else if (multi < kMultiUnchanged) {
          int32_t diff;
          const uint32_t lastDiff = static_cast<uint32_t>(lastDiff_[last_]);
          if (multi == 0) {
            diff = ic_.decompress(dec, 0, 7);
            countExtreme(diff);
          } else if (multi < kMulti) {
            diff =
                ic_.decompress(dec, static_cast<int32_t>(static_cast<uint32_t>(multi) * lastDiff),
                               multi < 10 ? 2 : 3);
          } else if (multi == kMulti) {
            diff = ic_.decompress(dec, static_cast<int32_t>(uint32_t(kMulti) * lastDiff), 4);
            countExtreme(diff);
          } else {
            multi = kMulti - multi;
            if (multi > kMultiMinus) {
              diff = ic_.decompress(
                  dec, static_cast<int32_t>(static_cast<uint32_t>(multi) * lastDiff), 5);
            } else {
              diff = ic_.decompress(
                  dec, static_cast<int32_t>(static_cast<uint32_t>(kMultiMinus) * lastDiff), 6);
              countExtreme(diff);
            }
          }
          time_[last_] += static_cast<uint64_t>(static_cast<int64_t>(diff));
        } else if (multi == kMultiCodeFull) {
          readFull(dec);
        } else if (multi > kMultiCodeFull) {
          last_ = (last_ + static_cast<uint32_t>(multi - kMultiCodeFull)) & 3;
          continue;
        }
      }
      break;
    }
    put<uint64_t>(out, time_[last_]);
  }

 private:
  // A time that differs by more than 32 bits: the high half predicted, the low half raw.
  void readFull(ArithmeticDecoder& dec) {
    next_ = (next_ + 1) & 3;
    const uint32_t high =
        static_cast<uint32_t>(ic_.decompress(dec, static_cast<int32_t>(time_[last_] >> 32), 8));
    time_[next_] = (uint64_t(high) << 32) | dec.readInt();
    last_ = next_;
    lastDiff_[last_] = 0;
    extreme_[last_] = 0;
  }
};

class Rgb12V2 final : public LanedItem<Rgb12V2>, private Rgb12V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

 private:
  friend class LanedItem<Rgb12V2>;
  // The mask of changed bytes, then each byte's difference to its prediction: red low and high,
  // and when green and blue differ from red: green low, blue low, green high, blue high (the
  // reference's order within each lane).
  template <size_t N>
  [[gnu::always_inline]] static inline void readLanes(Rgb12V2* const s[],
                                                      ArithmeticDecoder* const d[],
                                                      uint8_t* const out[]) {
    auto low = [](uint16_t v) { return int32_t(v & 0xFF); };
    auto high = [](uint16_t v) { return int32_t(v >> 8); };
    uint32_t sym[N];
    uint16_t rgb[N][3] = {};
    int32_t diff[N];
    for (size_t l = 0; l < N; ++l) sym[l] = d[l]->decodeSymbol(s[l]->byteUsed_);
    for (size_t l = 0; l < N; ++l) {
      const uint16_t* last = s[l]->last_;
      rgb[l][0] =
          sym[l] & 1
              ? fold8(static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[0])) + low(last[0]))
              : last[0] & 0xFF;
    }
    for (size_t l = 0; l < N; ++l) {
      const uint16_t* last = s[l]->last_;
      rgb[l][0] |=
          sym[l] & 2
              ? uint16_t(
                    fold8(static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[1])) + high(last[0]))
                    << 8)
              : last[0] & 0xFF00;
      if (!(sym[l] & 64)) rgb[l][1] = rgb[l][2] = rgb[l][0];
    }
    for (size_t l = 0; l < N; ++l) {
      if (!(sym[l] & 64)) continue;
      const uint16_t* last = s[l]->last_;
      diff[l] = low(rgb[l][0]) - low(last[0]);
      rgb[l][1] = sym[l] & 4 ? fold8(static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[2])) +
                                     clamp8(diff[l] + low(last[1])))
                             : last[1] & 0xFF;
    }
    for (size_t l = 0; l < N; ++l) {
      if (!(sym[l] & 64)) continue;
      const uint16_t* last = s[l]->last_;
      if (sym[l] & 16) {
        const int32_t corr = static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[4]));
        const int32_t d2 = (diff[l] + (low(rgb[l][1]) - low(last[1]))) / 2;
        rgb[l][2] = fold8(corr + clamp8(d2 + low(last[2])));
      } else {
        rgb[l][2] = last[2] & 0xFF;
      }
      diff[l] = high(rgb[l][0]) - high(last[0]);
    }
    for (size_t l = 0; l < N; ++l) {
      if (!(sym[l] & 64)) continue;
      const uint16_t* last = s[l]->last_;
      rgb[l][1] |= sym[l] & 8
                       ? uint16_t(fold8(static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[3])) +
                                        clamp8(diff[l] + high(last[1])))
                                  << 8)
                       : last[1] & 0xFF00;
    }
    for (size_t l = 0; l < N; ++l) {
      if (!(sym[l] & 64)) continue;
      const uint16_t* last = s[l]->last_;
      if (sym[l] & 32) {
        const int32_t corr = static_cast<int32_t>(d[l]->decodeSymbol(s[l]->diff_[5]));
        const int32_t d2 = (diff[l] + (high(rgb[l][1]) - high(last[1]))) / 2;
        rgb[l][2] |= uint16_t(fold8(corr + clamp8(d2 + high(last[2]))) << 8);
      } else {
        rgb[l][2] |= last[2] & 0xFF00;
      }
    }
    for (size_t l = 0; l < N; ++l)
      for (int c = 0; c < 3; ++c) {
        put<uint16_t>(out[l] + 2 * c, rgb[l][c]);
        s[l]->last_[c] = rgb[l][c];
      }
  }
};

class ByteV2 final : public ItemDecoder, private ByteV2State {
 public:
  explicit ByteV2(size_t n) : ByteV2State(n) {}
  void init(const uint8_t* first) override { reset(first); }
  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    for (size_t i = 0; i < last_.size(); ++i) {
      last_[i] = fold8(int32_t(last_[i]) + static_cast<int32_t>(dec.decodeSymbol(models_[i])));
      out[i] = last_[i];
    }
  }
  void readPair(ItemDecoder& twin, ArithmeticDecoder& a, uint8_t* outA, ArithmeticDecoder& b,
                uint8_t* outB) override {
    ByteV2& t = static_cast<ByteV2&>(twin);
    for (size_t i = 0; i < last_.size(); ++i) {
      last_[i] = fold8(int32_t(last_[i]) + static_cast<int32_t>(a.decodeSymbol(models_[i])));
      t.last_[i] = fold8(int32_t(t.last_[i]) + static_cast<int32_t>(b.decodeSymbol(t.models_[i])));
      outA[i] = last_[i];
      outB[i] = t.last_[i];
    }
  }
};

// ---- the chunk ------------------------------------------------------------------------------

class PointwiseDecoder final : public ChunkDecoder {
 public:
  explicit PointwiseDecoder(const LaszipInfo& info) : info_(info), recordSize_(info.recordSize()) {
    size_t at = 0;
    for (const Item& it : info.items) {
      items_.push_back(makeItem(it));
      offsets_.push_back(at);
      at += it.size;
    }
  }

  size_t decode(const uint8_t* data, size_t size, uint32_t count, uint8_t* out) override {
    if (count == 0) return 0;
    start(data, size, out);
    return run(1, count, out);
  }

  PointCount countPoints(const uint8_t* data, size_t size, uint32_t most,
                         uint8_t* scratch) override {
    PointCount r;
    if (most == 0 || size < recordSize_) return r;
    start(data, size, scratch);
    const size_t stream = size - recordSize_;
    uint32_t p = 1;
    for (; p < most && dec_.consumed() < stream && !dec_.overrun(); ++p) {
      uint8_t* rec = scratch + size_t(p) * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i) items_[i]->read(dec_, rec + offsets_[i]);
    }
    // Ran dry before the stream was used up, or more bytes than `most` points use: damaged.
    if (dec_.overrun() || dec_.consumed() < stream) return r;
    r.least = r.upTo = p;
    // Points past the stream's end that need no new byte are few: a thousand is plenty to say so.
    for (const uint32_t stop = std::min<uint64_t>(most, uint64_t(p) + 1000); p < stop; ++p) {
      uint8_t* rec = scratch + size_t(p) * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i) items_[i]->read(dec_, rec + offsets_[i]);
      if (dec_.overrun()) break;
      r.upTo = p + 1;
    }
    return r;
  }

  // Two chunks in lock step while both have points (items interleave their symbols, see
  // ItemDecoder::readPair), then the rest of the longer one alone. A stream that runs dry sends
  // both chunks back to decode() one by one, which reports exactly where.
  void decodePair(const Job& a, const Job& b, Outcome& ra, Outcome& rb) override {
    if (a.count < 2 || b.count < 2 || a.size < recordSize_ || b.size < recordSize_)
      return ChunkDecoder::decodePair(a, b, ra, rb);
    if (!twin_) twin_ = std::make_unique<PointwiseDecoder>(info_);
    PointwiseDecoder& t = *twin_;
    start(a.data, a.size, a.out);
    t.start(b.data, b.size, b.out);
    const uint32_t common = std::min(a.count, b.count);
    for (uint32_t p = 1; p < common; ++p) {
      uint8_t* recA = a.out + size_t(p) * recordSize_;
      uint8_t* recB = b.out + size_t(p) * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i)
        items_[i]->readPair(*t.items_[i], dec_, recA + offsets_[i], t.dec_, recB + offsets_[i]);
      if (dec_.overrun() > 8 || t.dec_.overrun() > 8) return ChunkDecoder::decodePair(a, b, ra, rb);
    }
    ra.lockstep = rb.lockstep = true;
    finish(a, common, ra);
    t.finish(b, common, rb);
  }

 private:
  // The first record raw, and every item and the arithmetic decoder started on the chunk.
  void start(const uint8_t* data, size_t size, uint8_t* out) {
    if (size < recordSize_)
      throw DecodeError(0, "chunk of " + std::to_string(size) +
                               " bytes is too short for its first point (" +
                               std::to_string(recordSize_) + " bytes raw)");
    std::memcpy(out, data, recordSize_);
    for (size_t i = 0; i < items_.size(); ++i) items_[i]->init(data + offsets_[i]);
    dec_.init(data + recordSize_, data + size);
    size_ = size;
  }

  // Points [from, count) of the started chunk; returns the bytes the chunk used.
  size_t run(uint32_t from, uint32_t count, uint8_t* out) {
    for (uint32_t p = from; p < count; ++p) {
      uint8_t* rec = out + size_t(p) * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i) items_[i]->read(dec_, rec + offsets_[i]);
      // A damaged stream decodes garbage but stays in bounds; stop early once it ran dry.
      if (dec_.overrun() > 8)
        throw DecodeError(size_, "chunk data ends at point " + std::to_string(p + 1) + " of " +
                                     std::to_string(count) +
                                     " (truncated or damaged compressed data)");
    }
    if (dec_.overrun())
      throw DecodeError(size_, "chunk data ends " + std::to_string(dec_.overrun()) +
                                   " bytes before its " + std::to_string(count) +
                                   " points are decoded (truncated or damaged compressed data)");
    return recordSize_ + dec_.consumed();
  }
  void finish(const Job& j, uint32_t from, Outcome& r) {
    try {
      r.used = run(from, j.count, j.out);
    } catch (const DecodeError& e) {
      r.error = e;
    }
  }

  static std::unique_ptr<ItemDecoder> makeItem(const Item& it) {
    if (it.version == 2) {
      switch (it.type) {
        case ItemType::Point10:
          return std::make_unique<Point10V2>();
        case ItemType::GpsTime11:
          return std::make_unique<GpsTime11V2>();
        case ItemType::Rgb12:
          return std::make_unique<Rgb12V2>();
        case ItemType::Byte:
          return std::make_unique<ByteV2>(it.size);
        default:
          break;
      }
    }
    if (it.version == 1)
      if (auto v1 = makeItemV1(it)) return v1;
    throw DecodeError(0, "LASzip item " + itemName(it.type) + " version " +
                             std::to_string(it.version) + " is not supported");
  }

  LaszipInfo info_;
  std::unique_ptr<PointwiseDecoder> twin_;  // the second chunk's items in decodePair
  size_t recordSize_;
  std::vector<std::unique_ptr<ItemDecoder>> items_;
  std::vector<size_t> offsets_;
  ArithmeticDecoder dec_;
  size_t size_ = 0;  // of the started chunk
};

}  // namespace

std::unique_ptr<ChunkDecoder> makePointwiseDecoder(const LaszipInfo& info) {
  return std::make_unique<PointwiseDecoder>(info);
}

}  // namespace nestlight::laz
