// What the layered LASzip compressor's decoder (laz_layered.cpp) and encoder
// (laz_layered_encoder.cpp) share: the record of a LAS 1.4 point as the predictors see it, and the
// per-context model sets and last values of each item. Both sides must update them in lock step,
// so they are one definition. Private to converters/src.
//
// Isenburg, "LASzip: lossless compression of LiDAR data", PE&RS 79(2), 2013; the layered variant
// exists only as the LASzip 3 reference implementation (laszip_common_v3, lasread/
// laswriteitemcompressed_v3), whose rules these follow.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "laz/arithmetic.h"
#include "laz/common.h"

namespace nestlight::laz::layered {

// Byte arithmetic of the colour and extra-byte predictors: sums wrap modulo 256 (values stay in
// 0..510, so the reference's fold is the low byte), predictions clamp to 0..255.
inline uint32_t low8(uint32_t v) {
  return v & 0xFFu;
}

// Context of the x/y models by (number of returns n, return number r): the valid combinations
// (1 <= r <= n) fall into six classes, and the table also maps files that number from 0 or swap
// the fields to distinct contexts.
constexpr uint8_t kReturnMap6[16][16] = {{0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 5, 5, 5, 5, 5},
                                         {1, 0, 1, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3},
                                         {2, 1, 2, 4, 4, 4, 4, 4, 4, 4, 4, 3, 3, 3, 3, 3},
                                         {3, 3, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
                                         {4, 3, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
                                         {5, 3, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4},
                                         {3, 3, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4, 4},
                                         {4, 3, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4},
                                         {4, 3, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4},
                                         {5, 3, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4},
                                         {5, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 4, 4, 4, 4, 4},
                                         {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 4, 4, 4},
                                         {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4, 4},
                                         {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 4},
                                         {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5},
                                         {5, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 4, 5, 5}};
// Context of the height predictor: how deep the return is (|n - r|), capped at 7.
inline uint32_t cappedReturnLevel(uint32_t n, uint32_t r) {
  const uint32_t d = n > r ? n - r : r - n;
  return d < 7 ? d : 7;
}

// A model the reference creates on first use: allocated once per decoder, reset the first time a
// context uses it after (re)initialisation, which is what a freshly created model is.
inline SymbolModel& lazyModel(std::unique_ptr<SymbolModel>& slot, uint64_t& fresh, uint32_t bit,
                              uint32_t symbols) {
  if (!((fresh >> bit) & 1u)) {
    if (slot)
      slot->reset();
    else
      slot = std::make_unique<SymbolModel>(symbols);
    fresh |= uint64_t(1) << bit;
  }
  return *slot;
}

// A model or integer decoder of a context, reset when the context first uses it after its
// (re)initialisation: equivalent to resetting it at the initialisation, but a chunk of a few
// points (COPC) does not pay for resetting the many models it never touches.
template <typename M>
inline M& fresh(M& m, uint32_t& pending, uint32_t bit) {
  if (pending & (1u << bit)) {
    m.reset();
    pending &= ~(1u << bit);
  }
  return m;
}

inline std::vector<SymbolModel> models(size_t n, uint32_t symbols) {
  std::vector<SymbolModel> v;
  v.reserve(n);
  for (size_t i = 0; i < n; ++i) v.emplace_back(symbols);
  return v;
}

// ---- POINT14 ---------------------------------------------------------------------------------

// The fields of a LAS 1.4 point record (bytes 0-29 of formats 6-10) as the predictors see them.
struct Point14 {
  uint32_t x = 0, y = 0, z = 0;  // unsigned: differences wrap like the reference's
  uint16_t intensity = 0;
  uint8_t returnNumber = 0, numberOfReturns = 0;  // 4 bits each
  uint8_t classFlags = 0, channel = 0, scanDirection = 0, edge = 0;
  uint8_t classification = 0, userData = 0;
  uint16_t scanAngle = 0, pointSource = 0;  // scan angle: the i16's bits
  uint64_t gpsTime = 0;                     // the f64's bits
  bool gpsTimeChanged = false;              // of this point (a context of the next one)

  void unpack(const uint8_t* r) {
    x = get<uint32_t>(r);
    y = get<uint32_t>(r + 4);
    z = get<uint32_t>(r + 8);
    intensity = get<uint16_t>(r + 12);
    returnNumber = r[14] & 15;
    numberOfReturns = r[14] >> 4;
    classFlags = r[15] & 15;
    channel = (r[15] >> 4) & 3;
    scanDirection = (r[15] >> 6) & 1;
    edge = r[15] >> 7;
    classification = r[16];
    userData = r[17];
    scanAngle = get<uint16_t>(r + 18);
    pointSource = get<uint16_t>(r + 20);
    gpsTime = get<uint64_t>(r + 22);
  }
  void pack(uint8_t* r) const {
    put(r, x);
    put(r + 4, y);
    put(r + 8, z);
    put(r + 12, intensity);
    r[14] = uint8_t(returnNumber | (numberOfReturns << 4));
    r[15] = uint8_t(classFlags | (channel << 4) | (scanDirection << 6) | (edge << 7));
    r[16] = classification;
    r[17] = userData;
    put(r + 18, scanAngle);
    put(r + 20, pointSource);
    put(r + 22, gpsTime);
  }
};

// GPS time codes: a difference to the last one as a multiple (1..499) of the last integer
// difference, 500 for "500 or more", 501-510 for -1..-10 times, 511 for a new full time, and
// 512-514 to switch to one of three other remembered time sequences.
constexpr uint32_t kGpsMulti = 500;
constexpr int32_t kGpsMultiMinus = -10;
constexpr uint32_t kGpsCodeFull = kGpsMulti - kGpsMultiMinus + 1;    // 511
constexpr uint32_t kGpsMultiTotal = kGpsMulti - kGpsMultiMinus + 5;  // 515 symbols

struct Point14Context {
  bool used = false;     // initialised in this chunk
  uint32_t pending = 0;  // models still to reset (bits below), see fresh()
  enum : uint32_t {
    kChanged = 0,  // 8 bits: changed[0..7]
    kScannerChannel = 8,
    kReturnNumberGpsSame,
    kDx,
    kDy,
    kZ,
    kIntensity,
    kScanAngle,
    kPointSource,
    kGpsMulti,
    kGps0Diff,
    kGps,
    kAll = (1u << 19) - 1
  };
  Point14 last;
  // channel/returns/XY layer
  std::vector<SymbolModel> changed = models(8, 128);  // which fields change, by last return
  SymbolModel scannerChannel{3};
  std::array<std::unique_ptr<SymbolModel>, 16> numberOfReturns, returnNumber;  // by last value
  uint64_t freshNumberOfReturns = 0, freshReturnNumber = 0;
  SymbolModel returnNumberGpsSame{13};
  IntegerDecoder dx{32, 2}, dy{32, 22};
  std::array<Median5, 12> medianX, medianY;
  // Z layer
  IntegerDecoder z{32, 20};
  std::array<uint32_t, 8> lastZ{};
  // classification, flags, user data layers: one model per last value (class, flags, user/4)
  std::array<std::unique_ptr<SymbolModel>, 64> classification, flags, userData;
  uint64_t freshClassification = 0, freshFlags = 0, freshUserData = 0;
  // intensity, scan angle, point source layers
  IntegerDecoder intensity{16, 4}, scanAngle{16, 2}, pointSource{16, 1};
  std::array<uint16_t, 8> lastIntensity{};
  // GPS time layer: four remembered sequences
  SymbolModel gpsMulti{kGpsMultiTotal}, gps0Diff{5};
  IntegerDecoder gps{32, 9};
  uint32_t gpsLast = 0, gpsNext = 0;
  std::array<uint64_t, 4> gpsTime{};
  std::array<int32_t, 4> gpsDiff{}, gpsExtreme{};

  // The reference's createAndInitModelsAndDecompressors: fresh models, and last values from the
  // point `from` (the chunk's first point, or the last point of the context being left).
  void init(const Point14& from) {
    used = true;
    pending = kAll;
    freshNumberOfReturns = freshReturnNumber = 0;
    medianX.fill(Median5());
    medianY.fill(Median5());
    lastZ.fill(from.z);
    freshClassification = freshFlags = freshUserData = 0;
    lastIntensity.fill(from.intensity);
    gpsLast = gpsNext = 0;
    gpsTime = {from.gpsTime, 0, 0, 0};
    gpsDiff.fill(0);
    gpsExtreme.fill(0);
    last = from;
    last.gpsTimeChanged = false;
  }
};

// ---- RGB14 / RGBNIR14 -------------------------------------------------------------------------

struct RgbContext {
  bool used = false;
  uint32_t pending = 0;            // bits: 0 rgbUsed, 1-6 rgbDiff, 7 nirUsed, 8-9 nirDiff
  std::array<uint16_t, 4> last{};  // r, g, b, nir
  SymbolModel rgbUsed{128};        // which of the six colour bytes change
  std::vector<SymbolModel> rgbDiff = models(6, 256);
  SymbolModel nirUsed{4};
  std::vector<SymbolModel> nirDiff = models(2, 256);

  void init(const std::array<uint16_t, 4>& from) {
    used = true;
    pending = (1u << 10) - 1;
    last = from;
  }
};

// ---- WAVEPACKET14 -----------------------------------------------------------------------------

struct WaveContext {
  bool used = false;
  uint32_t pending = 0;  // bits: 0 packetIndex, 1-4 offsetSym, 5 offsetDiff, 6 packetSize,
                         // 7 returnPoint, 8 xyz
  std::array<uint8_t, 29> last{};
  int32_t lastOffsetDiff = 0;
  uint32_t lastOffsetSym = 0;
  SymbolModel packetIndex{256};
  std::vector<SymbolModel> offsetSym = models(4, 4);  // by the last offset code
  IntegerDecoder offsetDiff{32, 1}, packetSize{32, 1}, returnPoint{32, 1}, xyz{32, 3};

  void init(const uint8_t* from) {
    used = true;
    pending = (1u << 9) - 1;
    lastOffsetDiff = 0;
    lastOffsetSym = 0;
    std::memcpy(last.data(), from, last.size());
  }
};

// ---- BYTE14 -----------------------------------------------------------------------------------

struct ByteContext {
  bool used = false;
  uint32_t generation = 0;  // bumped at each init: a model whose stamp differs is reset first
  std::vector<uint8_t> last;
  std::vector<std::unique_ptr<SymbolModel>> model;  // per byte, allocated on first use
  std::vector<uint32_t> stamp;

  explicit ByteContext(size_t n) : last(n), model(n), stamp(n, 0) {}
  void init(const uint8_t* from) {
    used = true;
    ++generation;
    if (generation == 0) {  // wrapped: stamps could match falsely
      std::fill(stamp.begin(), stamp.end(), 0);
      generation = 1;
    }
    std::memcpy(last.data(), from, last.size());
  }
  SymbolModel& byteModel(size_t i) {
    if (stamp[i] != generation) {
      if (model[i])
        model[i]->reset();
      else
        model[i] = std::make_unique<SymbolModel>(256);
      stamp[i] = generation;
    }
    return *model[i];
  }
};

// POINT14's context of scanner channel `c`, made on first use.
inline Point14Context& pointContext(std::array<std::unique_ptr<Point14Context>, 4>& ctxs,
                                    uint32_t c) {
  if (!ctxs[c]) ctxs[c] = std::make_unique<Point14Context>();
  return *ctxs[c];
}
// A chunk starts with every context unused but that of its first point's channel (`current`),
// initialised from that point.
inline Point14Context* startChunk(std::array<std::unique_ptr<Point14Context>, 4>& ctxs,
                                  const Point14& first, uint32_t& current) {
  for (auto& c : ctxs)
    if (c) c->used = false;
  current = first.channel;
  Point14Context* c = &pointContext(ctxs, current);
  c->init(first);
  return c;
}
// The context of the changed-fields model: the last point's return (single, first, last or
// intermediate) and whether its GPS time changed.
inline uint32_t lastReturnContext(const Point14& last) {
  return (last.returnNumber == 1 ? 1u : 0u) |
         (last.returnNumber >= last.numberOfReturns ? 2u : 0u) | (last.gpsTimeChanged ? 4u : 0u);
}

// RGB14/RGBNIR14 context `c` made (on first use) and initialised from the last values `from`.
inline void initRgb(std::array<std::unique_ptr<RgbContext>, 4>& ctxs, uint32_t c,
                    const std::array<uint16_t, 4>& from) {
  if (!ctxs[c]) ctxs[c] = std::make_unique<RgbContext>();
  ctxs[c]->init(from);
}
// At a chunk's start: every context unused but `current`, initialised from the first point's
// item `first` (3 or, with NIR, 4 values).
inline void startRgbChunk(std::array<std::unique_ptr<RgbContext>, 4>& ctxs, uint32_t current,
                          const uint8_t* first, bool nir) {
  for (auto& c : ctxs)
    if (c) c->used = false;
  std::array<uint16_t, 4> values{};
  for (size_t i = 0; i < (nir ? 4u : 3u); ++i) values[i] = get<uint16_t>(first + 2 * i);
  initRgb(ctxs, current, values);
}

// The context POINT14 hands the other items at point p of `records` (of `recordSize` bytes):
// version 3 names the channel only on the point where it switched (a switch always changes it)
// and context 0 otherwise; version 4 always names it.
inline uint32_t itemContext(const uint8_t* records, size_t recordSize, uint32_t p, bool v4) {
  const uint32_t ch = (records[size_t(p) * recordSize + 15] >> 4) & 3;
  if (v4) return ch;
  const uint32_t before = (records[size_t(p - 1) * recordSize + 15] >> 4) & 3;
  return ch != before ? ch : 0;
}
// The context of a chunk's first point: POINT14 names its channel at every chunk start.
inline uint32_t itemContext0(const uint8_t* records) {
  return (records[15] >> 4) & 3;
}

// Follows POINT14's context `ctx`; returns the context whose last values this point predicts
// from (version 3 predicts one point from the context it leaves when it switches to one already
// used in the chunk), `init` making a context's models fresh.
template <typename Ctx, typename Last, typename Init>
Last* follow(std::array<std::unique_ptr<Ctx>, 4>& ctxs, uint32_t& current, uint32_t ctx, bool fixed,
             Init&& init) {
  Last* last = &ctxs[current]->last;
  if (ctx != current) {
    current = ctx;
    if (!ctxs[ctx] || !ctxs[ctx]->used) {
      init(ctx, *last);
      last = &ctxs[ctx]->last;
    } else if (fixed) {
      last = &ctxs[ctx]->last;
    }
  }
  return last;
}

}  // namespace nestlight::laz::layered
