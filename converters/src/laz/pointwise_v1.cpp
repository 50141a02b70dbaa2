// LASzip's version 1 items (the pointwise compressor of LASzip 1.x files): POINT10, GPSTIME11,
// RGB12 and BYTE. The chunk framing (first record raw, then one arithmetic stream) and the
// version 2 items live in laz_pointwise.cpp, which asks makeItemV1 for these.
//
// Isenburg, "LASzip: lossless compression of LiDAR data", Photogrammetric Engineering & Remote
// Sensing 79(2), 2013, describes the scheme; the bit-exact definition is the LASzip reference
// implementation 1.x/2.x (lasreaditemcompressed_v1 and its writer), which is the format's
// specification. Written here by hand because Debian packages neither LASzip nor LAZperf.
//
// Version 1 is the simpler, older predictor: no return-number contexts, x and y predicted from
// the median of the last three differences, z from the last z, every other field from its own
// previous value with one integer corrector (or a symbol model chosen by the previous value).
// A decoder must replay the encoder's model updates exactly, so model sizes, contexts and the
// order in which fields are coded below are the format. Where the reference computes with signed
// overflow on a damaged stream, this code wraps unsigned, which gives the same bytes on valid
// streams (where the reference's arithmetic does not overflow, or wraps the same on its
// two's-complement targets). Every context index is bounded by construction (an 8-bit previous
// value, a clamped k, a symbol of a finite model), and no item recurses, so garbage input
// decodes to garbage in bounds and in time linear in the point count.
#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/format.h"
#include "laz/items.h"

namespace nestlight::laz {
namespace {

// Median of three: the reference spells it out as a comparison tree, which always picks the
// middle value (ties give equal values), so any exact median decodes the same.
int32_t median3(const int32_t v[3]) {
  return std::max(std::min(v[0], v[1]), std::min(std::max(v[0], v[1]), v[2]));
}

inline int32_t wrapAdd(int32_t a, int32_t b) {
  return static_cast<int32_t>(static_cast<uint32_t>(a) + static_cast<uint32_t>(b));
}

// ---- POINT10 (20 bytes: x y z i32, intensity u16, return byte, classification, scan angle,
// user data u8, point source u16) ------------------------------------------------------------

class Point10V1 final : public ItemDecoder {
 public:
  void init(const uint8_t* first) override {
    for (int i = 0; i < 3; ++i) lastDx_[i] = lastDy_[i] = 0;
    slot_ = 0;
    dx_.reset();
    dy_.reset();
    dz_.reset();
    intensity_.reset();
    scanAngle_.reset();
    pointSource_.reset();
    changed_.reset();
    bitByte_.reset();
    classification_.reset();
    userData_.reset();
    // Unlike version 2, the first point's intensity is the prediction as it is.
    std::memcpy(last_, first, 20);
  }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    // Coordinates come first, before the "what changed" symbol: x against the median of the last
    // three x differences (one context), y likewise with the number of corrector bits of x as
    // context, z against the last z with the mean of both as context.
    const int32_t dx = dx_.decompress(dec, median3(lastDx_));
    uint32_t k = dx_.k();
    const int32_t dy = dy_.decompress(dec, median3(lastDy_), k < 19 ? k : 19);
    // The mean uses the unclamped k of x; it also picks the scan angle's context below.
    k = (k + dy_.k()) / 2;
    const int32_t z = dz_.decompress(dec, get<int32_t>(last_ + 8), k < 19 ? k : 19);
    put<int32_t>(last_, wrapAdd(get<int32_t>(last_), dx));
    put<int32_t>(last_ + 4, wrapAdd(get<int32_t>(last_ + 4), dy));
    put<int32_t>(last_ + 8, z);

    // Six flags, one per remaining field (bit 5 intensity ... bit 0 point source). Each field is
    // coded from its own previous value only, so updating last_ in place is safe.
    const uint32_t changed = dec.decodeSymbol(changed_);
    if (changed & 32)
      put<uint16_t>(last_ + 12,
                    static_cast<uint16_t>(intensity_.decompress(dec, get<uint16_t>(last_ + 12))));
    if (changed & 16) last_[14] = static_cast<uint8_t>(dec.decodeSymbol(bitByte_[last_[14]]));
    if (changed & 8) last_[15] = static_cast<uint8_t>(dec.decodeSymbol(classification_[last_[15]]));
    // The scan angle is predicted from its previous byte read unsigned (0-255); the 8-bit
    // corrector wraps modulo 256, so the sign of the rank does not matter.
    if (changed & 4) last_[16] = static_cast<uint8_t>(scanAngle_.decompress(dec, last_[16], k < 3));
    if (changed & 2) last_[17] = static_cast<uint8_t>(dec.decodeSymbol(userData_[last_[17]]));
    if (changed & 1)
      put<uint16_t>(last_ + 18,
                    static_cast<uint16_t>(pointSource_.decompress(dec, get<uint16_t>(last_ + 18))));

    // The differences are remembered as decoded (the wrapped coordinate difference).
    lastDx_[slot_] = dx;
    lastDy_[slot_] = dy;
    slot_ = slot_ == 2 ? 0 : slot_ + 1;
    std::memcpy(out, last_, 20);
  }

 private:
  uint8_t last_[20] = {};
  int32_t lastDx_[3] = {}, lastDy_[3] = {};
  int slot_ = 0;
  IntegerDecoder dx_{32, 1}, dy_{32, 20}, dz_{32, 20};
  IntegerDecoder intensity_{16, 1}, scanAngle_{8, 2}, pointSource_{16, 1};
  SymbolModel changed_{64};
  // One 256-symbol model per previous value, made when first needed (as the reference does).
  LazyModels bitByte_{256}, classification_{256}, userData_{256};
};

// ---- GPSTIME11 (8 bytes: a double, coded as its 64-bit pattern) -----------------------------

class GpsTime11V1 final : public ItemDecoder {
  // Symbols of the multiplier model: 0 (smaller than half the last difference, or negative),
  // 1-508 (about that many times the last difference), 509 (that many or more), 510 (a time
  // more than 32 bits away, stored raw) and 511 (the same time again).
  static constexpr uint32_t kMultiMax = 512;
  static constexpr uint32_t kMultiExtreme = kMultiMax - 3;
  static constexpr uint32_t kMultiRaw = kMultiMax - 2;

 public:
  void init(const uint8_t* first) override {
    lastDiff_ = 0;
    extremeCount_ = 0;
    multi_.reset();
    zeroDiff_.reset();
    ic_.reset();
    time_ = get<uint64_t>(first);
  }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    if (lastDiff_ == 0) {
      // After a zero difference (or at the start): 0 the same time, 1 a 32-bit difference that
      // becomes the reference difference, 2 a raw time (the reference difference stays zero).
      const uint32_t sym = dec.decodeSymbol(zeroDiff_);
      if (sym == 1) {
        lastDiff_ = ic_.decompress(dec, 0, 0);
        time_ += static_cast<uint64_t>(static_cast<int64_t>(lastDiff_));
      } else if (sym == 2) {
        time_ = dec.readInt64();
      }
    } else {
      const uint32_t multi = dec.decodeSymbol(multi_);
      if (multi < kMultiRaw) {
        int32_t diff;
        if (multi == 1) {
          // The common case: about the last difference, which it then replaces.
          diff = ic_.decompress(dec, lastDiff_, 1);
          lastDiff_ = diff;
          extremeCount_ = 0;
        } else if (multi == 0) {
          // Predicted as a quarter of the last difference (C division, toward zero); after more
          // than three such points in a row the reference difference follows them.
          diff = ic_.decompress(dec, lastDiff_ / 4, 2);
          countExtreme(diff);
        } else {
          // multi times the last difference (32-bit product, wrapping like the reference's),
          // with a context per magnitude band.
          const int32_t pred = static_cast<int32_t>(multi * static_cast<uint32_t>(lastDiff_));
          diff = ic_.decompress(dec, pred, multi < 10 ? 3 : (multi < 50 ? 4 : 5));
          if (multi == kMultiExtreme) countExtreme(diff);
        }
        time_ += static_cast<uint64_t>(static_cast<int64_t>(diff));
      } else if (multi == kMultiRaw) {
        time_ = dec.readInt64();
      }
      // 511: unchanged.
    }
    put<uint64_t>(out, time_);
  }

 private:
  void countExtreme(int32_t diff) {
    if (++extremeCount_ > 3) {
      lastDiff_ = diff;
      extremeCount_ = 0;
    }
  }

  uint64_t time_ = 0;
  int32_t lastDiff_ = 0;
  int32_t extremeCount_ = 0;
  SymbolModel multi_{kMultiMax};
  SymbolModel zeroDiff_{3};
  IntegerDecoder ic_{32, 6};
};

// ---- RGB12 (6 bytes: red, green, blue u16) --------------------------------------------------

class Rgb12V1 final : public ItemDecoder {
 public:
  void init(const uint8_t* first) override {
    byteUsed_.reset();
    ic_.reset();
    std::memcpy(last_, first, 6);
  }

  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    // One flag per byte (bit i for byte i of the little-endian record: red low, red high, green
    // low, ...); each changed byte is coded against its previous value with context i. Unlike
    // version 2 there is no prediction across channels, so bytes are independent.
    const uint32_t used = dec.decodeSymbol(byteUsed_);
    for (uint32_t i = 0; i < 6; ++i)
      if (used & (1u << i)) last_[i] = static_cast<uint8_t>(ic_.decompress(dec, last_[i], i));
    std::memcpy(out, last_, 6);
  }

 private:
  uint8_t last_[6] = {};
  SymbolModel byteUsed_{64};
  IntegerDecoder ic_{8, 6};
};

// ---- BYTE (extra bytes, any count) ----------------------------------------------------------

class ByteV1 final : public ItemDecoder {
 public:
  explicit ByteV1(size_t n) : last_(n), ic_(8, static_cast<uint32_t>(n)) {}
  void init(const uint8_t* first) override {
    ic_.reset();
    std::memcpy(last_.data(), first, last_.size());
  }
  void read(ArithmeticDecoder& dec, uint8_t* out) override {
    // Every byte, changed or not, against its previous value with its own context.
    for (size_t i = 0; i < last_.size(); ++i)
      last_[i] = static_cast<uint8_t>(ic_.decompress(dec, last_[i], static_cast<uint32_t>(i)));
    std::memcpy(out, last_.data(), last_.size());
  }

 private:
  std::vector<uint8_t> last_;
  IntegerDecoder ic_;
};

}  // namespace

std::unique_ptr<ItemDecoder> makeItemV1(const Item& item) {
  if (item.version != 1) return nullptr;
  switch (item.type) {
    case ItemType::Point10:
      if (item.size == 20) return std::make_unique<Point10V1>();
      break;
    case ItemType::GpsTime11:
      if (item.size == 8) return std::make_unique<GpsTime11V1>();
      break;
    case ItemType::Rgb12:
      if (item.size == 6) return std::make_unique<Rgb12V1>();
      break;
    case ItemType::Byte:
      if (item.size > 0) return std::make_unique<ByteV1>(item.size);
      break;
    default:
      break;  // WAVEPACKET13 and the rest: not handled (the caller reports it)
  }
  return nullptr;
}

}  // namespace nestlight::laz
