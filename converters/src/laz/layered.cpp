// LASzip's layered chunked compressor (compressor 3) for LAS 1.4 point formats 6-10: the POINT14,
// RGB14, RGBNIR14, BYTE14 and WAVEPACKET14 items, version 3 (and version 4, which differs only
// at scanner-channel switches, see below).
//
// Isenburg, "LASzip: lossless compression of LiDAR data", Photogrammetric Engineering & Remote
// Sensing 79(2), 2013, describes the prediction scheme; the layered variant for LAS 1.4 exists
// only as code, so the LASzip 3 reference implementation (lasreaditemcompressed_v3/v4,
// lasreadpoint, laszip_common_v3) is the specification this follows bit for bit. Written here by
// hand because Debian packages neither LASzip nor LAZperf.
//
// A chunk is
//   - the first point's record, raw (all items, in item order);
//   - u32: the number of points in the chunk (the first one included);
//   - for each item in order, the byte size (u32) of each of its layers: POINT14 has nine
//     (channel/returns/XY, Z, classification, flags, intensity, scan angle, user data, point
//     source, GPS time), RGB14 one, RGBNIR14 two (RGB, NIR), BYTE14 one per byte, WAVEPACKET14
//     one;
//   - the layers' bytes, in the same order, each an arithmetic stream of its own.
// A layer of 0 bytes means its field does not change in the chunk: the decoder keeps the last
// value. Every item keeps four "contexts" (model sets and last values), one per scanner channel;
// POINT14 follows the channel, and tells the other items which context to use.
//
// Two quirks of version 3 are part of the format (its encoder has them too, so files depend on
// them), and are what version 4 changed:
//   - POINT14 reports the channel to the other items only on a point where the channel switched;
//     on every other point they are told context 0;
//   - an item that switches to a context it already used in this chunk predicts that one point
//     from the last values of the context it leaves (and stores the result there).
//
// Differences from the reference decoder, none of which changes the decoded values of a valid
// chunk: every size is checked against the chunk before use, and a chunk whose point count
// disagrees with the chunk table is an error; GPS time's sequence switch loops with a bound
// instead of recursing; arithmetic that overflows in the reference wraps unsigned here; models
// are allocated once per decoder and reset when a context first uses them after its
// initialisation (what the reference resets at the initialisation); a chunk of one point is
// its raw record whatever its layers hold (the reference would still start the first stream).
#include "laz/layered.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/common.h"
#include "laz/format.h"

namespace nestlight::laz {
namespace {

using namespace layered;

// ---- layers ---------------------------------------------------------------------------------

struct Layer {
  std::string name;  // for errors: "POINT14 layer 'Z'"
  ArithmeticDecoder dec;
  size_t sizeField = 0;         // offset of its u32 size in the chunk
  size_t offset = 0, size = 0;  // its bytes in the chunk
  bool active = false;          // has bytes in this chunk (else its field keeps its last value)
};

// ---- secondary items --------------------------------------------------------------------------

// An item after POINT14, and how it follows POINT14's scanner channel.
struct Secondary {
  ItemType type;
  size_t offset;      // in the record
  size_t size;        // bytes
  size_t firstLayer;  // index into the decoder's layers
  bool switchFixed;   // version 4: a switch to a used context predicts from that context
  uint32_t current = 0;
  std::array<std::unique_ptr<RgbContext>, 4> rgb;
  std::array<std::unique_ptr<WaveContext>, 4> wave;
  std::array<std::unique_ptr<ByteContext>, 4> bytes;
};

class LayeredDecoder final : public ChunkDecoder {
 public:
  explicit LayeredDecoder(const LaszipInfo& info) : recordSize_(info.recordSize()) {
    if (info.items.empty() || info.items[0].type != ItemType::Point14 || info.items[0].size != 30)
      throw DecodeError(0, "the layered LASzip compressor needs POINT14 (30 bytes) as first item");
    point14V4_ = checkVersion(info.items[0]);
    static const char* const kPointLayers[9] = {
        "channel/returns/XY", "Z",         "classification", "flags",   "intensity",
        "scan angle",         "user data", "point source",   "GPS time"};
    for (const char* n : kPointLayers) addLayer(std::string("POINT14 layer '") + n + "'");
    size_t offset = 30;
    for (size_t i = 1; i < info.items.size(); ++i) {
      const Item& it = info.items[i];
      const bool v4 = checkVersion(it);
      Secondary s{it.type, offset, it.size, layers_.size(), v4, 0, {}, {}, {}};
      const std::string name = itemName(it.type);
      switch (it.type) {
        case ItemType::Rgb14:
          if (it.size != 6) throw badSize(it, 6);
          addLayer(name + " layer 'RGB'");
          break;
        case ItemType::RgbNir14:
          if (it.size != 8) throw badSize(it, 8);
          addLayer(name + " layer 'RGB'");
          addLayer(name + " layer 'NIR'");
          break;
        case ItemType::WavePacket14:
          if (it.size != 29) throw badSize(it, 29);
          addLayer(name + " layer 'wave packet'");
          break;
        case ItemType::Byte14:
          if (it.size == 0) throw badSize(it, 1);
          for (size_t b = 0; b < it.size; ++b)
            addLayer(name + " (item " + std::to_string(i + 1) + ") layer 'byte " +
                     std::to_string(b + 1) + "'");
          break;
        default:
          throw DecodeError(0, "LASzip item " + itemName(it.type) +
                                   " cannot follow POINT14 in the layered compressor");
      }
      secondary_.push_back(std::move(s));
      offset += it.size;
    }
  }

  PointCount countPoints(const uint8_t* data, size_t size, uint32_t most, uint8_t*) override {
    PointCount r;
    if (most == 0 || size < recordSize_ + 4) return r;
    r.least = r.upTo = std::min(get<uint32_t>(data + recordSize_), most);
    return r;
  }

  size_t decode(const uint8_t* data, size_t size, uint32_t count, uint8_t* out) override {
    if (count == 0) return 0;
    const size_t rs = recordSize_;
    if (size < rs)
      throw DecodeError(0, "chunk of " + std::to_string(size) +
                               " bytes is too short for its first point (" + std::to_string(rs) +
                               " bytes raw)");
    std::memcpy(out, data, rs);
    size_t at = rs;
    if (size - at < 4)
      throw DecodeError(at,
                        "chunk ends before its point count (" + std::to_string(size) + " bytes)");
    const uint32_t inner = get<uint32_t>(data + at);
    // More than asked for is fine (the header declares fewer points than the chunks hold, and
    // is trusted): the layers are independent, so the first `count` points decode alone.
    if (inner < count)
      throw DecodeError(at, "chunk says it holds " + std::to_string(inner) +
                                " points, the chunk table " + std::to_string(count));
    at += 4;

    // Layer sizes, then the layers back to back; each must lie inside the chunk.
    const size_t fields = layers_.size();
    if ((size - at) / 4 < fields)
      throw DecodeError(at + (size - at) / 4 * 4, "chunk ends inside its table of layer sizes (" +
                                                      std::to_string(fields) + " sizes from byte " +
                                                      std::to_string(at) + ", chunk of " +
                                                      std::to_string(size) + " bytes)");
    size_t pos = at + 4 * fields;
    for (size_t i = 0; i < fields; ++i) {
      Layer& l = layers_[i];
      l.sizeField = at + 4 * i;
      l.size = get<uint32_t>(data + l.sizeField);
      l.offset = pos;
      if (l.size > size - pos)
        throw DecodeError(l.sizeField, l.name + " of " + std::to_string(l.size) +
                                           " bytes from byte " + std::to_string(pos) +
                                           " runs past the end of the chunk (" +
                                           std::to_string(size) + " bytes)");
      pos += l.size;
    }
    const size_t used = pos;
    if (count == 1) return used;  // the raw first point is the whole chunk

    for (size_t i = 0; i < fields; ++i) {
      Layer& l = layers_[i];
      // The channel/returns/XY layer is always decoded (every point has x and y); the others
      // only when they have bytes.
      l.active = l.size > 0 || i == 0;
      if (l.active) l.dec.init(data + l.offset, data + l.offset + l.size);
    }

    // POINT14 first for all points, then each other item: the items' layers are independent
    // streams, and the context an item follows is recoverable from the POINT14 records.
    decodePoint14(out, count);
    for (Secondary& s : secondary_) {
      switch (s.type) {
        case ItemType::Rgb14:
        case ItemType::RgbNir14:
          decodeRgb(s, out, count);
          break;
        case ItemType::WavePacket14:
          decodeWave(s, out, count);
          break;
        default:
          decodeBytes(s, out, count);
          break;
      }
    }

    for (const Layer& l : layers_)
      if (l.active && l.dec.overrun())
        throw DecodeError(l.offset + l.size,
                          l.name + " (" + std::to_string(l.size) + " bytes from byte " +
                              std::to_string(l.offset) + ") ends before the chunk's " +
                              std::to_string(count) +
                              " points are decoded: " + std::to_string(l.dec.overrun()) +
                              " bytes missing (truncated or damaged compressed data)");
    return used;
  }

 private:
  static bool checkVersion(const Item& it) {
    // LASzip reads version 2 (written by lasproto) as 3; version 4 fixes the context switch.
    if (it.version == 2 || it.version == 3) return false;
    if (it.version == 4) return true;
    throw DecodeError(0, "LASzip item " + itemName(it.type) + " version " +
                             std::to_string(it.version) + " is not supported");
  }
  static DecodeError badSize(const Item& it, size_t want) {
    return DecodeError(0, "LASzip item " + itemName(it.type) + " has size " +
                              std::to_string(it.size) + ", not " + std::to_string(want));
  }
  void addLayer(std::string name) {
    layers_.emplace_back();
    layers_.back().name = std::move(name);
  }

  // A damaged stream decodes garbage but stays in bounds; stop early once a stream ran dry
  // instead of decoding the rest of a large chunk from zeros.
  void checkDry(const Layer& l, uint32_t p, uint32_t count) const {
    if (l.dec.overrun() > 64)
      throw DecodeError(l.offset + l.size, l.name + " (" + std::to_string(l.size) +
                                               " bytes) ends at point " + std::to_string(p + 1) +
                                               " of " + std::to_string(count) +
                                               " (truncated or damaged compressed data)");
  }

  void decodePoint14(uint8_t* out, uint32_t count) {
    const size_t rs = recordSize_;
    ArithmeticDecoder& xy = layers_[0].dec;
    ArithmeticDecoder& zDec = layers_[1].dec;
    ArithmeticDecoder& classDec = layers_[2].dec;
    ArithmeticDecoder& flagsDec = layers_[3].dec;
    ArithmeticDecoder& intensityDec = layers_[4].dec;
    ArithmeticDecoder& angleDec = layers_[5].dec;
    ArithmeticDecoder& userDec = layers_[6].dec;
    ArithmeticDecoder& sourceDec = layers_[7].dec;
    const bool hasZ = layers_[1].active, hasClass = layers_[2].active, hasFlags = layers_[3].active,
               hasIntensity = layers_[4].active, hasAngle = layers_[5].active,
               hasUser = layers_[6].active, hasSource = layers_[7].active,
               hasGps = layers_[8].active;

    Point14 first;
    first.unpack(out);
    uint32_t cur = 0;
    Point14Context* c = startChunk(pctx_, first, cur);

    for (uint32_t p = 1; p < count; ++p) {
      // Which fields change, in the context of the last point's return.
      const uint32_t lpr = lastReturnContext(c->last);
      const uint32_t changed =
          xy.decodeSymbol(fresh(c->changed[lpr], c->pending, Point14Context::kChanged + lpr));
      if (changed & 64) {  // the scanner channel switched: code 0-2 means +1..+3
        const uint32_t next = (cur +
                               xy.decodeSymbol(fresh(c->scannerChannel, c->pending,
                                                     Point14Context::kScannerChannel)) +
                               1) &
                              3;
        Point14Context& nc = pointContext(pctx_, next);
        if (!nc.used) nc.init(c->last);  // a new channel starts from the point before
        cur = next;
        c = &nc;
        c->last.channel = uint8_t(next);
      }
      const bool sourceChange = changed & 32, gpsChange = changed & 16, angleChange = changed & 8;
      Point14& last = c->last;

      uint32_t n = last.numberOfReturns;
      if (changed & 4) {
        n = xy.decodeSymbol(lazyModel(c->numberOfReturns[n], c->freshNumberOfReturns, n, 16));
        last.numberOfReturns = uint8_t(n);
      }
      uint32_t r = last.returnNumber;
      switch (changed & 3) {
        case 0:
          break;
        case 1:
          r = (r + 1) & 15;
          break;
        case 2:
          r = (r + 15) & 15;
          break;
        default:
          if (gpsChange)  // a new pulse: the return number itself
            r = xy.decodeSymbol(lazyModel(c->returnNumber[r], c->freshReturnNumber, r, 16));
          else  // same pulse: a step of 2 to 14
            r = (r +
                 xy.decodeSymbol(fresh(c->returnNumberGpsSame, c->pending,
                                       Point14Context::kReturnNumberGpsSame)) +
                 2) &
                15;
          break;
      }
      last.returnNumber = uint8_t(r);

      const uint32_t m = kReturnMap6[n][r];
      const uint32_t level = cappedReturnLevel(n, r);
      const uint32_t cpr = (r == 1 ? 1u : 0u) | (r >= n ? 2u : 0u);
      const uint32_t single = n == 1 ? 1u : 0u;
      const uint32_t mctx = (m << 1) | (gpsChange ? 1u : 0u);

      // x and y: differences to the last point, predicted by the median of recent ones; y's
      // model is chosen by how large x's correction was.
      int32_t diff = fresh(c->dx, c->pending, Point14Context::kDx)
                         .decompress(xy, c->medianX[mctx].get(), single);
      last.x += uint32_t(diff);
      c->medianX[mctx].add(diff);
      uint32_t k = c->dx.k();
      diff = fresh(c->dy, c->pending, Point14Context::kDy)
                 .decompress(xy, c->medianY[mctx].get(), single + (k < 20 ? (k & ~1u) : 20));
      last.y += uint32_t(diff);
      c->medianY[mctx].add(diff);

      if (hasZ) {  // z: the last z of the same return depth, model by x's and y's corrections
        k = (c->dx.k() + c->dy.k()) / 2;
        last.z = uint32_t(
            fresh(c->z, c->pending, Point14Context::kZ)
                .decompress(zDec, int32_t(c->lastZ[level]), single + (k < 18 ? (k & ~1u) : 18)));
        c->lastZ[level] = last.z;
      }
      if (hasClass) {
        const uint32_t ctx = ((last.classification & 0x1Fu) << 1) + (cpr == 3 ? 1u : 0u);
        last.classification = uint8_t(classDec.decodeSymbol(
            lazyModel(c->classification[ctx], c->freshClassification, ctx, 256)));
      }
      if (hasFlags) {
        const uint32_t ctx =
            (uint32_t(last.edge) << 5) | (uint32_t(last.scanDirection) << 4) | last.classFlags;
        const uint32_t f = flagsDec.decodeSymbol(lazyModel(c->flags[ctx], c->freshFlags, ctx, 64));
        last.edge = (f >> 5) & 1;
        last.scanDirection = (f >> 4) & 1;
        last.classFlags = f & 15;
      }
      if (hasIntensity) {  // the last intensity of the same return kind and GPS change
        const uint32_t ctx = (cpr << 1) | (gpsChange ? 1u : 0u);
        const auto v = uint16_t(fresh(c->intensity, c->pending, Point14Context::kIntensity)
                                    .decompress(intensityDec, c->lastIntensity[ctx], cpr));
        c->lastIntensity[ctx] = v;
        last.intensity = v;
      }
      if (hasAngle && angleChange)
        last.scanAngle =
            uint16_t(fresh(c->scanAngle, c->pending, Point14Context::kScanAngle)
                         .decompress(angleDec, int16_t(last.scanAngle), gpsChange ? 1u : 0u));
      if (hasUser) {
        const uint32_t ctx = last.userData / 4u;
        last.userData =
            uint8_t(userDec.decodeSymbol(lazyModel(c->userData[ctx], c->freshUserData, ctx, 256)));
      }
      if (hasSource && sourceChange)
        last.pointSource = uint16_t(fresh(c->pointSource, c->pending, Point14Context::kPointSource)
                                        .decompress(sourceDec, last.pointSource));
      if (hasGps && gpsChange) {
        decodeGpsTime(*c);
        last.gpsTime = c->gpsTime[c->gpsLast];
      }

      last.pack(out + size_t(p) * rs);
      last.gpsTimeChanged = gpsChange;
      if ((p & 1023) == 0) checkDry(layers_[0], p, count);
    }
  }

  // Times are coded as integer differences of the f64's bits to the last time of the current
  // sequence; a sequence switch is followed by the code for the switched-to sequence, which the
  // encoder only emits once per point (so two rounds suffice; more means a damaged stream).
  void decodeGpsTime(Point14Context& c) {
    ArithmeticDecoder& dec = layers_[8].dec;
    fresh(c.gpsMulti, c.pending, Point14Context::kGpsMulti);
    fresh(c.gps0Diff, c.pending, Point14Context::kGps0Diff);
    fresh(c.gps, c.pending, Point14Context::kGps);
    for (int round = 0; round < 4; ++round) {
      const uint32_t s = c.gpsLast;
      if (c.gpsDiff[s] == 0) {
        const uint32_t multi = dec.decodeSymbol(c.gps0Diff);
        if (multi == 0) {  // the difference fits 32 bits
          c.gpsDiff[s] = c.gps.decompress(dec, 0, 0);
          c.gpsTime[s] += uint64_t(int64_t(c.gpsDiff[s]));
          c.gpsExtreme[s] = 0;
          return;
        }
        if (multi == 1) {  // a full new time opens the next sequence
          fullGpsTime(c, dec);
          return;
        }
        c.gpsLast = (s + multi - 1) & 3;
        continue;
      }
      const uint32_t multi = dec.decodeSymbol(c.gpsMulti);
      if (multi == 1) {
        c.gpsTime[s] += uint64_t(int64_t(c.gps.decompress(dec, c.gpsDiff[s], 1)));
        c.gpsExtreme[s] = 0;
        return;
      }
      if (multi < kGpsCodeFull) {
        // The reference multiplies in int32 and relies on wrap-around; so does this, unsigned.
        auto times = [&](int32_t f) { return int32_t(uint32_t(f) * uint32_t(c.gpsDiff[s])); };
        int32_t d;
        bool extreme = false;
        if (multi == 0) {
          d = c.gps.decompress(dec, 0, 7);
          extreme = true;
        } else if (multi < kGpsMulti) {
          d = c.gps.decompress(dec, times(int32_t(multi)), multi < 10 ? 2 : 3);
        } else if (multi == kGpsMulti) {
          d = c.gps.decompress(dec, times(int32_t(kGpsMulti)), 4);
          extreme = true;
        } else {
          const int32_t f = int32_t(kGpsMulti) - int32_t(multi);  // -1 .. -10
          if (f > kGpsMultiMinus) {
            d = c.gps.decompress(dec, times(f), 5);
          } else {
            d = c.gps.decompress(dec, times(kGpsMultiMinus), 6);
            extreme = true;
          }
        }
        // After more than three outliers in a row, the outlier becomes the new step.
        if (extreme && ++c.gpsExtreme[s] > 3) {
          c.gpsDiff[s] = d;
          c.gpsExtreme[s] = 0;
        }
        c.gpsTime[s] += uint64_t(int64_t(d));
        return;
      }
      if (multi == kGpsCodeFull) {
        fullGpsTime(c, dec);
        return;
      }
      c.gpsLast = (s + multi - kGpsCodeFull) & 3;
    }
    throw DecodeError(layers_[8].offset, layers_[8].name +
                                             " switches time sequence more than the encoder "
                                             "does (damaged compressed data)");
  }
  static void fullGpsTime(Point14Context& c, ArithmeticDecoder& dec) {
    c.gpsNext = (c.gpsNext + 1) & 3;
    const auto high =
        uint32_t(c.gps.decompress(dec, int32_t(uint32_t(c.gpsTime[c.gpsLast] >> 32)), 8));
    c.gpsTime[c.gpsNext] = (uint64_t(high) << 32) | dec.readInt();
    c.gpsLast = c.gpsNext;
    c.gpsDiff[c.gpsLast] = 0;
    c.gpsExtreme[c.gpsLast] = 0;
  }

  void decodeRgb(Secondary& s, uint8_t* out, uint32_t count) {
    const size_t rs = recordSize_;
    const bool nir = s.type == ItemType::RgbNir14;
    Layer& rgbLayer = layers_[s.firstLayer];
    ArithmeticDecoder& rgbDec = rgbLayer.dec;
    const bool hasRgb = rgbLayer.active;
    ArithmeticDecoder* nirDec = nir ? &layers_[s.firstLayer + 1].dec : nullptr;
    const bool hasNir = nir && layers_[s.firstLayer + 1].active;

    auto init = [&](uint32_t c, const std::array<uint16_t, 4>& from) { initRgb(s.rgb, c, from); };
    s.current = itemContext0(out);
    startRgbChunk(s.rgb, s.current, out + s.offset, nir);

    for (uint32_t p = 1; p < count; ++p) {
      uint16_t* last =
          follow<RgbContext, std::array<uint16_t, 4>>(
              s.rgb, s.current, itemContext(out, recordSize_, p, point14V4_), s.switchFixed, init)
              ->data();
      RgbContext& c = *s.rgb[s.current];
      uint8_t* item = out + size_t(p) * rs + s.offset;
      uint16_t v[3];
      if (hasRgb) {
        // Which bytes change (bit 6: the colour is not grey); red's low and high bytes are
        // differences, green and blue are predicted from red's change, clamped to a byte.
        const uint32_t sym = rgbDec.decodeSymbol(fresh(c.rgbUsed, c.pending, 0));
        auto corr = [&](uint32_t i) {
          return rgbDec.decodeSymbol(fresh(c.rgbDiff[i], c.pending, 1 + i));
        };
        const uint32_t lo0 = last[0] & 255u, hi0 = last[0] >> 8;
        const uint32_t lo1 = last[1] & 255u, hi1 = last[1] >> 8;
        const uint32_t lo2 = last[2] & 255u, hi2 = last[2] >> 8;
        const uint32_t rl = sym & 1 ? low8(corr(0) + lo0) : lo0;
        const uint32_t rh = sym & 2 ? low8(corr(1) + hi0) : hi0;
        v[0] = uint16_t(rl | (rh << 8));
        if (sym & 64) {
          int32_t d = int32_t(rl) - int32_t(lo0);
          uint32_t gl = lo1, bl = lo2, gh = hi1, bh = hi2;
          if (sym & 4) gl = low8(corr(2) + clamp8(d + int32_t(lo1)));
          if (sym & 16) {
            d = (d + (int32_t(gl) - int32_t(lo1))) / 2;  // C division: truncates toward 0
            bl = low8(corr(4) + clamp8(d + int32_t(lo2)));
          }
          d = int32_t(rh) - int32_t(hi0);
          if (sym & 8) gh = low8(corr(3) + clamp8(d + int32_t(hi1)));
          if (sym & 32) {
            d = (d + (int32_t(gh) - int32_t(hi1))) / 2;
            bh = low8(corr(5) + clamp8(d + int32_t(hi2)));
          }
          v[1] = uint16_t(gl | (gh << 8));
          v[2] = uint16_t(bl | (bh << 8));
        } else {
          v[1] = v[2] = v[0];
        }
        last[0] = v[0];
        last[1] = v[1];
        last[2] = v[2];
      } else {
        v[0] = last[0];
        v[1] = last[1];
        v[2] = last[2];
      }
      put(item, v[0]);
      put(item + 2, v[1]);
      put(item + 4, v[2]);
      if (nir) {
        if (hasNir) {
          const uint32_t sym = nirDec->decodeSymbol(fresh(c.nirUsed, c.pending, 7));
          const uint32_t lo = last[3] & 255u, hi = last[3] >> 8;
          auto corr = [&](uint32_t i) {
            return nirDec->decodeSymbol(fresh(c.nirDiff[i], c.pending, 8 + i));
          };
          const uint32_t nl = sym & 1 ? low8(corr(0) + lo) : lo;
          const uint32_t nh = sym & 2 ? low8(corr(1) + hi) : hi;
          last[3] = uint16_t(nl | (nh << 8));
        }
        put(item + 6, last[3]);
      }
      if ((p & 1023) == 0) checkDry(rgbLayer, p, count);
    }
  }

  void decodeWave(Secondary& s, uint8_t* out, uint32_t count) {
    const size_t rs = recordSize_;
    Layer& layer = layers_[s.firstLayer];
    ArithmeticDecoder& dec = layer.dec;
    const bool has = layer.active;

    auto init = [&](uint32_t c, const std::array<uint8_t, 29>& from) {
      if (!s.wave[c]) s.wave[c] = std::make_unique<WaveContext>();
      s.wave[c]->init(from.data());
    };
    for (auto& c : s.wave)
      if (c) c->used = false;
    std::array<uint8_t, 29> first;
    std::memcpy(first.data(), out + s.offset, 29);
    s.current = itemContext0(out);
    init(s.current, first);

    for (uint32_t p = 1; p < count; ++p) {
      uint8_t* last =
          follow<WaveContext, std::array<uint8_t, 29>>(
              s.wave, s.current, itemContext(out, recordSize_, p, point14V4_), s.switchFixed, init)
              ->data();
      WaveContext& c = *s.wave[s.current];
      uint8_t* item = out + size_t(p) * rs + s.offset;
      if (!has) {
        // The reference leaves the item as the previous point's (its buffer is reused).
        std::memcpy(item, item - rs, 29);
        continue;
      }
      // Descriptor index u8, then offset u64, packet size u32, return point and x/y/z f32.
      item[0] = uint8_t(dec.decodeSymbol(fresh(c.packetIndex, c.pending, 0)));
      const uint64_t lastOffset = get<uint64_t>(last + 1);
      const uint32_t lastSize = get<uint32_t>(last + 9);
      c.lastOffsetSym =
          dec.decodeSymbol(fresh(c.offsetSym[c.lastOffsetSym], c.pending, 1 + c.lastOffsetSym));
      uint64_t offset;
      switch (c.lastOffsetSym) {
        case 0:
          offset = lastOffset;
          break;  // same packet
        case 1:
          offset = lastOffset + lastSize;
          break;  // the next packet
        case 2:   // a coded difference
          c.lastOffsetDiff = fresh(c.offsetDiff, c.pending, 5).decompress(dec, c.lastOffsetDiff);
          offset = lastOffset + uint64_t(int64_t(c.lastOffsetDiff));
          break;
        default:
          offset = dec.readInt64();
          break;  // raw
      }
      put(item + 1, offset);
      put(item + 9, uint32_t(fresh(c.packetSize, c.pending, 6).decompress(dec, int32_t(lastSize))));
      put(item + 13, fresh(c.returnPoint, c.pending, 7).decompress(dec, get<int32_t>(last + 13)));
      IntegerDecoder& xyz = fresh(c.xyz, c.pending, 8);
      for (uint32_t a = 0; a < 3; ++a)
        put(item + 17 + 4 * a, xyz.decompress(dec, get<int32_t>(last + 17 + 4 * a), a));
      std::memcpy(last, item, 29);
      if ((p & 1023) == 0) checkDry(layer, p, count);
    }
  }

  void decodeBytes(Secondary& s, uint8_t* out, uint32_t count) {
    const size_t rs = recordSize_, n = s.size;
    Layer* layers = layers_.data() + s.firstLayer;
    active_.clear();
    for (size_t i = 0; i < n; ++i)
      if (layers[i].active) active_.push_back(uint32_t(i));

    auto init = [&](uint32_t c, const std::vector<uint8_t>& from) {
      if (!s.bytes[c]) s.bytes[c] = std::make_unique<ByteContext>(n);
      s.bytes[c]->init(from.data());
    };
    for (auto& c : s.bytes)
      if (c) c->used = false;
    first_.assign(out + s.offset, out + s.offset + n);
    s.current = itemContext0(out);
    init(s.current, first_);

    for (uint32_t p = 1; p < count; ++p) {
      uint8_t* last =
          follow<ByteContext, std::vector<uint8_t>>(
              s.bytes, s.current, itemContext(out, recordSize_, p, point14V4_), s.switchFixed, init)
              ->data();
      ByteContext& c = *s.bytes[s.current];
      uint8_t* item = out + size_t(p) * rs + s.offset;
      // Bytes without a layer keep their last value; the others add a coded difference.
      for (uint32_t i : active_)
        last[i] = uint8_t(last[i] + layers[i].dec.decodeSymbol(c.byteModel(i)));
      std::memcpy(item, last, n);
    }
  }

  size_t recordSize_;
  bool point14V4_ = false;
  std::vector<Layer> layers_;  // POINT14's nine, then each other item's, in item order
  std::array<std::unique_ptr<Point14Context>, 4> pctx_;
  std::vector<Secondary> secondary_;
  std::vector<uint32_t> active_;  // scratch: the BYTE14 bytes with a layer in this chunk
  std::vector<uint8_t> first_;    // scratch: the BYTE14 bytes of the first point
};

}  // namespace

std::unique_ptr<ChunkDecoder> makeLayeredDecoder(const LaszipInfo& info) {
  return std::make_unique<LayeredDecoder>(info);
}

}  // namespace nestlight::laz
