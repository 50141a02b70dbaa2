// LASzip's layered chunked compressor (compressor 3), encoding side: LAS 1.4 point formats 6-8 as
// POINT14, RGB14, RGBNIR14 and BYTE14 items of version 3, for LAZ output of the formats the LAS
// writer chooses when legacy formats cannot hold the points.
//
// Isenburg, "LASzip: lossless compression of LiDAR data", Photogrammetric Engineering & Remote
// Sensing 79(2), 2013, describes the prediction scheme; the layered variant exists only as the
// LASzip 3 reference implementation (laswriteitemcompressed_v3, laszip_common_v3). This encoder
// is the inverse of laz_layered.cpp, which decodes the reference's files bit for bit: the same
// contexts and models (laz_layered.h) updated in the same order, so what it writes decodes with
// any LASzip 3 reader. Written by hand because Debian packages neither LASzip nor LAZperf.
//
// Choices that are the encoder's (any of them decodes the same): every layer is written, even one
// whose field never changes in the chunk (the reference drops those, saving a few bytes a chunk);
// a return number that is neither the last one nor one step from it is coded as in the reference;
// GPS times are coded as the nearest multiple of the last difference, as the reference does.
#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/common.h"
#include "laz/format.h"
#include "laz/layered.h"
#include "nestlight/octree/error.h"

namespace nestlight::laz {
namespace {

using namespace layered;

// An item after POINT14 and its contexts (see the decoder's Secondary).
struct SecondaryItem {
  ItemType type;
  size_t offset, size, firstLayer;
  uint32_t current = 0;
  std::array<std::unique_ptr<RgbContext>, 4> rgb;
  std::array<std::unique_ptr<ByteContext>, 4> bytes;
};

class LayeredEncoder final : public ChunkEncoder {
 public:
  explicit LayeredEncoder(const LaszipInfo& info) : recordSize_(info.recordSize()) {
    NL_CHECK(!info.items.empty() && info.items[0].type == ItemType::Point14 &&
             info.items[0].size == 30 && info.items[0].version == 3);
    layers_ = 9;
    size_t offset = 30;
    for (size_t i = 1; i < info.items.size(); ++i) {
      const Item& it = info.items[i];
      NL_CHECK(it.version == 3);
      SecondaryItem s{it.type, offset, it.size, layers_, 0, {}, {}};
      if (it.type == ItemType::Rgb14) {
        NL_CHECK(it.size == 6);
        layers_ += 1;
      } else if (it.type == ItemType::RgbNir14) {
        NL_CHECK(it.size == 8);
        layers_ += 2;
      } else {
        NL_CHECK_MSG(it.type == ItemType::Byte14 && it.size > 0,
                     "no layered encoder for " + itemName(it.type));
        layers_ += it.size;
      }
      secondary_.push_back(std::move(s));
      offset += it.size;
    }
    NL_CHECK(offset == recordSize_);
  }

  void encode(const uint8_t* records, size_t count, std::vector<uint8_t>& out) override {
    NL_CHECK(count >= 1 && count <= UINT32_MAX);
    out.assign(records, records + recordSize_);
    uint8_t n[4];
    put<uint32_t>(n, uint32_t(count));
    out.insert(out.end(), n, n + 4);
    streams_.resize(layers_);
    encoders_.clear();
    encoders_.reserve(layers_);
    for (auto& s : streams_) {
      s.clear();
      encoders_.emplace_back(s);
    }
    if (count > 1) {
      encodePoint14(records, uint32_t(count));
      for (SecondaryItem& s : secondary_)
        if (s.type == ItemType::Byte14)
          encodeBytes(s, records, uint32_t(count));
        else
          encodeRgb(s, records, uint32_t(count));
      for (auto& e : encoders_) e.done();
      dropConstantLayers(records, uint32_t(count));
    }  // a chunk of one point is its raw record; its layers are empty
    for (const auto& s : streams_) {
      put<uint32_t>(n, uint32_t(s.size()));
      out.insert(out.end(), n, n + 4);
    }
    for (const auto& s : streams_) out.insert(out.end(), s.begin(), s.end());
  }

 private:
  // A field that keeps the first point's value through the chunk needs no layer: the decoder
  // skips an empty layer and keeps the last value (the reference drops these too).
  void dropConstantLayers(const uint8_t* records, uint32_t count) {
    const size_t rs = recordSize_;
    auto constant = [&](size_t offset, size_t bytes, uint8_t mask = 0xFF) {
      for (uint32_t p = 1; p < count; ++p)
        for (size_t b = 0; b < bytes; ++b)
          if ((records[size_t(p) * rs + offset + b] ^ records[offset + b]) & mask) return false;
      return true;
    };
    // POINT14's layers after channel/returns/XY: Z, classification, flags (not the channel
    // bits, which the XY layer codes), intensity, scan angle, user data, point source, GPS time.
    const struct {
      size_t layer, offset, bytes;
      uint8_t mask;
    } fields[] = {{1, 8, 4, 0xFF},  {2, 16, 1, 0xFF}, {3, 15, 1, 0xCF}, {4, 12, 2, 0xFF},
                  {5, 18, 2, 0xFF}, {6, 17, 1, 0xFF}, {7, 20, 2, 0xFF}, {8, 22, 8, 0xFF}};
    for (const auto& f : fields)
      if (constant(f.offset, f.bytes, f.mask)) streams_[f.layer].clear();
    for (const SecondaryItem& s : secondary_) {
      if (s.type == ItemType::Byte14) {
        for (size_t i = 0; i < s.size; ++i)
          if (constant(s.offset + i, 1)) streams_[s.firstLayer + i].clear();
        continue;
      }
      if (constant(s.offset, 6)) streams_[s.firstLayer].clear();
      if (s.type == ItemType::RgbNir14 && constant(s.offset + 6, 2))
        streams_[s.firstLayer + 1].clear();
    }
  }

  // How the return number follows the last one: 0 the same, 1 one more, 2 one less, 3 other.
  static uint32_t returnCode(uint32_t last, uint32_t r) {
    if (r == last) return 0;
    if (r == ((last + 1) & 15)) return 1;
    if (r == ((last + 15) & 15)) return 2;
    return 3;
  }

  void encodePoint14(const uint8_t* records, uint32_t count) {
    const size_t rs = recordSize_;
    ArithmeticEncoder& xy = encoders_[0];
    ArithmeticEncoder& zEnc = encoders_[1];
    ArithmeticEncoder& classEnc = encoders_[2];
    ArithmeticEncoder& flagsEnc = encoders_[3];
    ArithmeticEncoder& intensityEnc = encoders_[4];
    ArithmeticEncoder& angleEnc = encoders_[5];
    ArithmeticEncoder& userEnc = encoders_[6];
    ArithmeticEncoder& sourceEnc = encoders_[7];

    Point14 first;
    first.unpack(records);
    uint32_t cur = 0;
    Point14Context* c = startChunk(pctx_, first, cur);

    for (uint32_t p = 1; p < count; ++p) {
      Point14 pt;
      pt.unpack(records + size_t(p) * rs);
      // The changed-field symbol is coded in the current context, from its last point's return;
      // the changes it names are those against the context the point goes to (the one it
      // switches to keeps its own last values, a new one starts from the current one's).
      const uint32_t lpr = lastReturnContext(c->last);
      const uint32_t target = pt.channel;
      const Point14* ref = &c->last;
      if (target != cur && pctx_[target] && pctx_[target]->used) ref = &pctx_[target]->last;
      const bool gpsChange = pt.gpsTime != ref->gpsTime;
      const uint32_t changed = (target != cur ? 64u : 0u) |
                               (pt.pointSource != ref->pointSource ? 32u : 0u) |
                               (gpsChange ? 16u : 0u) | (pt.scanAngle != ref->scanAngle ? 8u : 0u) |
                               (pt.numberOfReturns != ref->numberOfReturns ? 4u : 0u) |
                               returnCode(ref->returnNumber, pt.returnNumber);
      xy.encodeSymbol(fresh(c->changed[lpr], c->pending, Point14Context::kChanged + lpr), changed);
      if (changed & 64) {
        xy.encodeSymbol(fresh(c->scannerChannel, c->pending, Point14Context::kScannerChannel),
                        (target - cur - 1) & 3);
        Point14Context& nc = pointContext(pctx_, target);
        if (!nc.used) nc.init(c->last);
        cur = target;
        c = &nc;
        c->last.channel = uint8_t(target);
      }
      Point14& last = c->last;

      if (changed & 4) {
        const uint32_t n = last.numberOfReturns;
        xy.encodeSymbol(lazyModel(c->numberOfReturns[n], c->freshNumberOfReturns, n, 16),
                        pt.numberOfReturns);
        last.numberOfReturns = pt.numberOfReturns;
      }
      if ((changed & 3) == 3) {
        const uint32_t r = last.returnNumber;
        if (gpsChange)
          xy.encodeSymbol(lazyModel(c->returnNumber[r], c->freshReturnNumber, r, 16),
                          pt.returnNumber);
        else
          xy.encodeSymbol(
              fresh(c->returnNumberGpsSame, c->pending, Point14Context::kReturnNumberGpsSame),
              ((pt.returnNumber - r) & 15) - 2);
      }
      last.returnNumber = pt.returnNumber;

      const uint32_t n = last.numberOfReturns, r = last.returnNumber;
      const uint32_t m = kReturnMap6[n][r];
      const uint32_t level = cappedReturnLevel(n, r);
      const uint32_t cpr = (r == 1 ? 1u : 0u) | (r >= n ? 2u : 0u);
      const uint32_t single = n == 1 ? 1u : 0u;
      const uint32_t mctx = (m << 1) | (gpsChange ? 1u : 0u);

      int32_t diff = int32_t(pt.x - last.x);
      fresh(c->dx, c->pending, Point14Context::kDx)
          .compress(xy, c->medianX[mctx].get(), diff, single);
      last.x = pt.x;
      c->medianX[mctx].add(diff);
      uint32_t k = c->dx.k();
      diff = int32_t(pt.y - last.y);
      fresh(c->dy, c->pending, Point14Context::kDy)
          .compress(xy, c->medianY[mctx].get(), diff, single + (k < 20 ? (k & ~1u) : 20));
      last.y = pt.y;
      c->medianY[mctx].add(diff);

      k = (c->dx.k() + c->dy.k()) / 2;
      fresh(c->z, c->pending, Point14Context::kZ)
          .compress(zEnc, int32_t(c->lastZ[level]), int32_t(pt.z),
                    single + (k < 18 ? (k & ~1u) : 18));
      last.z = pt.z;
      c->lastZ[level] = pt.z;

      {
        const uint32_t ctx = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
        classEnc.encodeSymbol(lazyModel(c->classification[ctx], c->freshClassification, ctx, 256),
                              pt.classification);
        last.classification = pt.classification;
      }
      {
        const uint32_t ctx =
            (uint32_t(last.edge) << 5) | (uint32_t(last.scanDirection) << 4) | last.classFlags;
        flagsEnc.encodeSymbol(
            lazyModel(c->flags[ctx], c->freshFlags, ctx, 64),
            (uint32_t(pt.edge) << 5) | (uint32_t(pt.scanDirection) << 4) | pt.classFlags);
        last.edge = pt.edge;
        last.scanDirection = pt.scanDirection;
        last.classFlags = pt.classFlags;
      }
      {
        const uint32_t ctx = (cpr << 1) | (gpsChange ? 1u : 0u);
        fresh(c->intensity, c->pending, Point14Context::kIntensity)
            .compress(intensityEnc, c->lastIntensity[ctx], pt.intensity, cpr);
        c->lastIntensity[ctx] = pt.intensity;
        last.intensity = pt.intensity;
      }
      if (changed & 8) {
        fresh(c->scanAngle, c->pending, Point14Context::kScanAngle)
            .compress(angleEnc, int16_t(last.scanAngle), int16_t(pt.scanAngle),
                      gpsChange ? 1u : 0u);
        last.scanAngle = pt.scanAngle;
      }
      {
        const uint32_t ctx = last.userData / 4u;
        userEnc.encodeSymbol(lazyModel(c->userData[ctx], c->freshUserData, ctx, 256), pt.userData);
        last.userData = pt.userData;
      }
      if (changed & 32) {
        fresh(c->pointSource, c->pending, Point14Context::kPointSource)
            .compress(sourceEnc, last.pointSource, pt.pointSource);
        last.pointSource = pt.pointSource;
      }
      if (gpsChange) {
        encodeGpsTime(*c, pt.gpsTime);
        last.gpsTime = pt.gpsTime;
      }
      last.gpsTimeChanged = gpsChange;
    }
  }

  // The inverse of the decoder's decodeGpsTime: a difference that fits 32 bits is coded against
  // the nearest multiple of the sequence's last difference; otherwise another remembered
  // sequence the time is near, or a full new time that opens the next sequence.
  void encodeGpsTime(Point14Context& c, uint64_t t) {
    ArithmeticEncoder& enc = encoders_[8];
    fresh(c.gpsMulti, c.pending, Point14Context::kGpsMulti);
    fresh(c.gps0Diff, c.pending, Point14Context::kGps0Diff);
    fresh(c.gps, c.pending, Point14Context::kGps);
    auto fits = [&](uint32_t s) {
      const int64_t d = int64_t(t - c.gpsTime[s]);
      return d == int64_t(int32_t(d));
    };
    auto near = [&](uint32_t s) -> uint32_t {  // another sequence within 32 bits: 1-3, or 0
      for (uint32_t i = 1; i < 4; ++i)
        if (fits((s + i) & 3)) return i;
      return 0;
    };
    for (int round = 0; round < 2; ++round) {
      const uint32_t s = c.gpsLast;
      if (c.gpsDiff[s] == 0) {
        if (fits(s)) {
          const auto d = int32_t(int64_t(t - c.gpsTime[s]));
          enc.encodeSymbol(c.gps0Diff, 0);
          c.gps.compress(enc, 0, d, 0);
          c.gpsDiff[s] = d;
          c.gpsTime[s] = t;
          c.gpsExtreme[s] = 0;
          return;
        }
        if (const uint32_t i = near(s); i && round == 0) {
          enc.encodeSymbol(c.gps0Diff, i + 1);
          c.gpsLast = (s + i) & 3;
          continue;
        }
        enc.encodeSymbol(c.gps0Diff, 1);
        fullGpsTime(c, enc, t);
        return;
      }
      if (fits(s)) {
        const auto d = int32_t(int64_t(t - c.gpsTime[s]));
        const int32_t lastDiff = c.gpsDiff[s];
        auto times = [&](int32_t f) { return int32_t(uint32_t(f) * uint32_t(lastDiff)); };
        const float ratio = std::clamp(float(d) / float(lastDiff), -20.0f, 1000.0f);
        const int32_t multi = ratio >= 0 ? int32_t(ratio + 0.5f) : int32_t(ratio - 0.5f);
        bool extreme = false;
        if (multi == 1) {
          enc.encodeSymbol(c.gpsMulti, 1);
          c.gps.compress(enc, lastDiff, d, 1);
          c.gpsExtreme[s] = 0;
        } else if (multi > 1 && multi < int32_t(kGpsMulti)) {
          enc.encodeSymbol(c.gpsMulti, uint32_t(multi));
          c.gps.compress(enc, times(multi), d, multi < 10 ? 2 : 3);
        } else if (multi >= int32_t(kGpsMulti)) {
          enc.encodeSymbol(c.gpsMulti, kGpsMulti);
          c.gps.compress(enc, times(int32_t(kGpsMulti)), d, 4);
          extreme = true;
        } else if (multi < 0 && multi > kGpsMultiMinus) {
          enc.encodeSymbol(c.gpsMulti, uint32_t(int32_t(kGpsMulti) - multi));
          c.gps.compress(enc, times(multi), d, 5);
        } else if (multi < 0) {
          enc.encodeSymbol(c.gpsMulti, uint32_t(int32_t(kGpsMulti) - kGpsMultiMinus));
          c.gps.compress(enc, times(kGpsMultiMinus), d, 6);
          extreme = true;
        } else {
          enc.encodeSymbol(c.gpsMulti, 0);
          c.gps.compress(enc, 0, d, 7);
          extreme = true;
        }
        if (extreme && ++c.gpsExtreme[s] > 3) {
          c.gpsDiff[s] = d;
          c.gpsExtreme[s] = 0;
        }
        c.gpsTime[s] = t;
        return;
      }
      if (const uint32_t i = near(s); i && round == 0) {
        enc.encodeSymbol(c.gpsMulti, kGpsCodeFull + i);
        c.gpsLast = (s + i) & 3;
        continue;
      }
      enc.encodeSymbol(c.gpsMulti, kGpsCodeFull);
      fullGpsTime(c, enc, t);
      return;
    }
    NL_CHECK_MSG(false, "GPS time sequence switched twice");  // near() guarantees a fit
  }
  static void fullGpsTime(Point14Context& c, ArithmeticEncoder& enc, uint64_t t) {
    c.gpsNext = (c.gpsNext + 1) & 3;
    c.gps.compress(enc, int32_t(uint32_t(c.gpsTime[c.gpsLast] >> 32)), int32_t(uint32_t(t >> 32)),
                   8);
    enc.writeInt(uint32_t(t));
    c.gpsTime[c.gpsNext] = t;
    c.gpsLast = c.gpsNext;
    c.gpsDiff[c.gpsLast] = 0;
    c.gpsExtreme[c.gpsLast] = 0;
  }

  void encodeRgb(SecondaryItem& s, const uint8_t* records, uint32_t count) {
    const size_t rs = recordSize_;
    const bool nir = s.type == ItemType::RgbNir14;
    ArithmeticEncoder& rgbEnc = encoders_[s.firstLayer];
    ArithmeticEncoder* nirEnc = nir ? &encoders_[s.firstLayer + 1] : nullptr;
    auto init = [&](uint32_t c, const std::array<uint16_t, 4>& from) { initRgb(s.rgb, c, from); };
    s.current = itemContext0(records);
    startRgbChunk(s.rgb, s.current, records + s.offset, nir);

    for (uint32_t p = 1; p < count; ++p) {
      uint16_t* last = follow<RgbContext, std::array<uint16_t, 4>>(
                           s.rgb, s.current, itemContext(records, rs, p, false), false, init)
                           ->data();
      RgbContext& c = *s.rgb[s.current];
      const uint8_t* item = records + size_t(p) * rs + s.offset;
      const uint16_t v[3] = {get<uint16_t>(item), get<uint16_t>(item + 2), get<uint16_t>(item + 4)};
      auto lo = [](uint32_t x) { return int32_t(x & 255u); };
      auto hi = [](uint32_t x) { return int32_t(x >> 8); };
      // Bit 6: not grey, then green and blue change bits; without it green and blue are red.
      const bool colour = v[1] != v[0] || v[2] != v[0];
      uint32_t sym = (lo(v[0]) != lo(last[0]) ? 1u : 0u) | (hi(v[0]) != hi(last[0]) ? 2u : 0u);
      if (colour)
        sym |= 64u | (lo(v[1]) != lo(last[1]) ? 4u : 0u) | (hi(v[1]) != hi(last[1]) ? 8u : 0u) |
               (lo(v[2]) != lo(last[2]) ? 16u : 0u) | (hi(v[2]) != hi(last[2]) ? 32u : 0u);
      rgbEnc.encodeSymbol(fresh(c.rgbUsed, c.pending, 0), sym);
      auto corr = [&](uint32_t i, int32_t value) {
        rgbEnc.encodeSymbol(fresh(c.rgbDiff[i], c.pending, 1 + i), uint32_t(value) & 255u);
      };
      if (sym & 1) corr(0, lo(v[0]) - lo(last[0]));
      if (sym & 2) corr(1, hi(v[0]) - hi(last[0]));
      if (sym & 64) {
        int32_t d = lo(v[0]) - lo(last[0]);
        if (sym & 4) corr(2, lo(v[1]) - clamp8(d + lo(last[1])));
        if (sym & 16) {
          d = (d + (lo(v[1]) - lo(last[1]))) / 2;  // C division, as the decoder's
          corr(4, lo(v[2]) - clamp8(d + lo(last[2])));
        }
        d = hi(v[0]) - hi(last[0]);
        if (sym & 8) corr(3, hi(v[1]) - clamp8(d + hi(last[1])));
        if (sym & 32) {
          d = (d + (hi(v[1]) - hi(last[1]))) / 2;
          corr(5, hi(v[2]) - clamp8(d + hi(last[2])));
        }
      }
      last[0] = v[0];
      last[1] = v[1];
      last[2] = v[2];
      if (nir) {
        const uint16_t w = get<uint16_t>(item + 6);
        const uint32_t nsym = (lo(w) != lo(last[3]) ? 1u : 0u) | (hi(w) != hi(last[3]) ? 2u : 0u);
        nirEnc->encodeSymbol(fresh(c.nirUsed, c.pending, 7), nsym);
        if (nsym & 1)
          nirEnc->encodeSymbol(fresh(c.nirDiff[0], c.pending, 8),
                               uint32_t(lo(w) - lo(last[3])) & 255u);
        if (nsym & 2)
          nirEnc->encodeSymbol(fresh(c.nirDiff[1], c.pending, 9),
                               uint32_t(hi(w) - hi(last[3])) & 255u);
        last[3] = w;
      }
    }
  }

  void encodeBytes(SecondaryItem& s, const uint8_t* records, uint32_t count) {
    const size_t rs = recordSize_, n = s.size;
    auto init = [&](uint32_t c, const std::vector<uint8_t>& from) {
      if (!s.bytes[c]) s.bytes[c] = std::make_unique<ByteContext>(n);
      s.bytes[c]->init(from.data());
    };
    for (auto& c : s.bytes)
      if (c) c->used = false;
    const std::vector<uint8_t> first(records + s.offset, records + s.offset + n);
    s.current = itemContext0(records);
    init(s.current, first);
    for (uint32_t p = 1; p < count; ++p) {
      uint8_t* last = follow<ByteContext, std::vector<uint8_t>>(
                          s.bytes, s.current, itemContext(records, rs, p, false), false, init)
                          ->data();
      ByteContext& c = *s.bytes[s.current];
      const uint8_t* item = records + size_t(p) * rs + s.offset;
      for (size_t i = 0; i < n; ++i) {
        encoders_[s.firstLayer + i].encodeSymbol(c.byteModel(i), uint8_t(item[i] - last[i]));
        last[i] = item[i];
      }
    }
  }

  size_t recordSize_;
  size_t layers_ = 0;
  std::array<std::unique_ptr<Point14Context>, 4> pctx_;
  std::vector<SecondaryItem> secondary_;
  std::vector<std::vector<uint8_t>> streams_;  // one per layer
  std::vector<ArithmeticEncoder> encoders_;    // writing into streams_
};

}  // namespace

std::unique_ptr<ChunkEncoder> makeLayeredEncoder(const LaszipInfo& info) {
  return std::make_unique<LayeredEncoder>(info);
}

}  // namespace nestlight::laz
