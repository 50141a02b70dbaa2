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
#include <array>
#include <cstring>
#include <memory>

#include "laz_arithmetic.h"
#include "laz_format.h"
#include "laz_items.h"

namespace nestlight::laz {
namespace {

// ---- version 2 ---------------------------------------------------------------------------------

class Point10V2 final : public ItemDecoder, private Point10V2State {
 public:
  void init(const uint8_t* first) override {
    reset(first);
    last_[12] = last_[13] = 0;  // the reference predicts the first intensity from zero
  }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    const uint32_t changed = dec.decodeSymbol(changed_);
    uint32_t r, n, m, l;
    if (changed) {
      if (changed & 32) last_[14] = static_cast<uint8_t>(dec.decodeSymbol(bitByte_[last_[14]]));
      r = last_[14] & 7;
      n = (last_[14] >> 3) & 7;
      m = kReturnMap[n][r];
      l = returnLevel(n, r);
      uint16_t intensity;
      if (changed & 16) {
        intensity =
            static_cast<uint16_t>(intensity_.decompress(dec, lastIntensity_[m], m < 3 ? m : 3));
        lastIntensity_[m] = intensity;
      } else {
        intensity = lastIntensity_[m];
      }
      put<uint16_t>(last_ + 12, intensity);
      if (changed & 8)
        last_[15] = static_cast<uint8_t>(dec.decodeSymbol(classification_[last_[15]]));
      if (changed & 4) {
        const uint32_t v = dec.decodeSymbol(scanAngle_[(last_[14] >> 6) & 1]);
        last_[16] = fold8(static_cast<int32_t>(v + last_[16]));
      }
      if (changed & 2) last_[17] = static_cast<uint8_t>(dec.decodeSymbol(userData_[last_[17]]));
      if (changed & 1)
        put<uint16_t>(last_ + 18, static_cast<uint16_t>(
                                      pointSource_.decompress(dec, get<uint16_t>(last_ + 18))));
    } else {
      r = last_[14] & 7;
      n = (last_[14] >> 3) & 7;
      m = kReturnMap[n][r];
      l = returnLevel(n, r);
    }

    int32_t diff = dx_.decompress(dec, xMedian_[m].get(), n == 1);
    put<uint32_t>(last_, get<uint32_t>(last_) + static_cast<uint32_t>(diff));
    xMedian_[m].add(diff);

    uint32_t kBits = dx_.k();
    diff = dy_.decompress(dec, yMedian_[m].get(), (n == 1) + (kBits < 20 ? (kBits & ~1u) : 20));
    put<uint32_t>(last_ + 4, get<uint32_t>(last_ + 4) + static_cast<uint32_t>(diff));
    yMedian_[m].add(diff);

    kBits = (dx_.k() + dy_.k()) / 2;
    const int32_t z =
        dz_.decompress(dec, lastHeight_[l], (n == 1) + (kBits < 18 ? (kBits & ~1u) : 18));
    put<int32_t>(last_ + 8, z);
    lastHeight_[l] = z;
    std::memcpy(out, last_, 20);
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

class Rgb12V2 final : public ItemDecoder, private Rgb12V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    const uint32_t sym = dec.decodeSymbol(byteUsed_);
    uint16_t rgb[3];
    auto low = [](uint16_t v) { return int32_t(v & 0xFF); };
    auto high = [](uint16_t v) { return int32_t(v >> 8); };
    if (sym & 1)
      rgb[0] = fold8(static_cast<int32_t>(dec.decodeSymbol(diff_[0])) + low(last_[0]));
    else
      rgb[0] = last_[0] & 0xFF;
    if (sym & 2)
      rgb[0] |=
          uint16_t(fold8(static_cast<int32_t>(dec.decodeSymbol(diff_[1])) + high(last_[0])) << 8);
    else
      rgb[0] |= last_[0] & 0xFF00;
    if (sym & 64) {
      int32_t diff = low(rgb[0]) - low(last_[0]);
      if (sym & 4)
        rgb[1] =
            fold8(static_cast<int32_t>(dec.decodeSymbol(diff_[2])) + clamp8(diff + low(last_[1])));
      else
        rgb[1] = last_[1] & 0xFF;
      if (sym & 16) {
        const int32_t corr = static_cast<int32_t>(dec.decodeSymbol(diff_[4]));
        diff = (diff + (low(rgb[1]) - low(last_[1]))) / 2;
        rgb[2] = fold8(corr + clamp8(diff + low(last_[2])));
      } else {
        rgb[2] = last_[2] & 0xFF;
      }
      diff = high(rgb[0]) - high(last_[0]);
      if (sym & 8)
        rgb[1] |= uint16_t(
            fold8(static_cast<int32_t>(dec.decodeSymbol(diff_[3])) + clamp8(diff + high(last_[1])))
            << 8);
      else
        rgb[1] |= last_[1] & 0xFF00;
      if (sym & 32) {
        const int32_t corr = static_cast<int32_t>(dec.decodeSymbol(diff_[5]));
        diff = (diff + (high(rgb[1]) - high(last_[1]))) / 2;
        rgb[2] |= uint16_t(fold8(corr + clamp8(diff + high(last_[2]))) << 8);
      } else {
        rgb[2] |= last_[2] & 0xFF00;
      }
    } else {
      rgb[1] = rgb[2] = rgb[0];
    }
    for (int c = 0; c < 3; ++c) {
      put<uint16_t>(out + 2 * c, rgb[c]);
      last_[c] = rgb[c];
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
};

// ---- the chunk ------------------------------------------------------------------------------

class PointwiseDecoder final : public ChunkDecoder {
 public:
  explicit PointwiseDecoder(const LaszipInfo& info) : recordSize_(info.recordSize()) {
    size_t at = 0;
    for (const Item& it : info.items) {
      items_.push_back(makeItem(it));
      offsets_.push_back(at);
      at += it.size;
    }
  }

  size_t decode(const uint8_t* data, size_t size, uint32_t count, uint8_t* out) override {
    if (count == 0) return 0;
    if (size < recordSize_)
      throw DecodeError(0, "chunk of " + std::to_string(size) +
                               " bytes is too short for its first point (" +
                               std::to_string(recordSize_) + " bytes raw)");
    std::memcpy(out, data, recordSize_);
    for (size_t i = 0; i < items_.size(); ++i) items_[i]->init(data + offsets_[i]);
    dec_.init(data + recordSize_, data + size);
    for (uint32_t p = 1; p < count; ++p) {
      uint8_t* rec = out + size_t(p) * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i) items_[i]->read(dec_, rec + offsets_[i]);
      // A damaged stream decodes garbage but stays in bounds; stop early once it ran dry.
      if (dec_.overrun() > 8)
        throw DecodeError(size, "chunk data ends at point " + std::to_string(p + 1) + " of " +
                                    std::to_string(count) +
                                    " (truncated or damaged compressed data)");
    }
    if (dec_.overrun())
      throw DecodeError(size, "chunk data ends " + std::to_string(dec_.overrun()) +
                                  " bytes before its " + std::to_string(count) +
                                  " points are decoded (truncated or damaged compressed data)");
    return recordSize_ + dec_.consumed();
  }

 private:
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

  size_t recordSize_;
  std::vector<std::unique_ptr<ItemDecoder>> items_;
  std::vector<size_t> offsets_;
  ArithmeticDecoder dec_;
};

}  // namespace

std::unique_ptr<ChunkDecoder> makePointwiseDecoder(const LaszipInfo& info) {
  return std::make_unique<PointwiseDecoder>(info);
}

}  // namespace nestlight::laz
