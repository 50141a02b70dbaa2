// The adaptive arithmetic decoder of LASzip, safe on untrusted input. Private to converters/src.
//
// LASzip (Isenburg, "LASzip: lossless compression of LiDAR data", Photogrammetric Engineering &
// Remote Sensing 79(2), 2013; the LAZ format as specified by the LASzip reference implementation
// 2.x-3.x) entropy-codes every field with an adaptive range coder after Amir Said ("Introduction
// to Arithmetic Coding - Theory and Practice", HP Labs HPL-2004-76, 2004): 32-bit interval,
// byte-wise renormalisation, symbol models whose cumulative counts are rebuilt periodically (with
// a lookup table that narrows the search for the decoded symbol), and binary
// models with a scaled probability of 0. A decoder must reproduce the encoder's model updates bit
// for bit, so the constants and update rules below are the format, not tuning.
//
// Written here because Debian packages neither LASzip nor LAZperf. Differences from the reference
// decoder, none of which changes the decoded values of a valid stream:
// - reading past the end of the stream yields zero bytes and is counted (overrun()), so that the
//   caller can report a truncated or damaged chunk instead of reading foreign memory;
// - the table lookup is clamped, because a damaged stream can leave value >= length, where the
//   reference decoder would index past its table;
// - all interval arithmetic is unsigned (wrapping), so a damaged stream cannot cause undefined
//   behaviour; models keep their invariants (every count >= 1), so length never reaches zero and
//   renormalisation always terminates.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace nestlight::laz {

inline constexpr uint32_t kMinLength = 0x01000000u;  // renormalise below 2^24
inline constexpr uint32_t kMaxLength = 0xFFFFFFFFu;
inline constexpr uint32_t kBitLengthShift = 13;  // binary models: probabilities in 1/2^13
inline constexpr uint32_t kBitMaxCount = 1u << kBitLengthShift;
inline constexpr uint32_t kSymbolLengthShift = 15;  // symbol models: distribution in 1/2^15
inline constexpr uint32_t kSymbolMaxCount = 1u << kSymbolLengthShift;
inline constexpr uint32_t kMaxSymbols = 1u << 11;

// Binary adaptive model.
struct BitModel {
  uint32_t bit0Count = 1, bitCount = 2;
  uint32_t bit0Prob = 1u << (kBitLengthShift - 1);
  uint32_t updateCycle = 4, bitsUntilUpdate = 4;

  void reset() { *this = BitModel(); }
  void update() {
    if ((bitCount += updateCycle) > kBitMaxCount) {
      bitCount = (bitCount + 1) >> 1;
      bit0Count = (bit0Count + 1) >> 1;
      if (bit0Count == bitCount) ++bitCount;
    }
    const uint32_t scale = 0x80000000u / bitCount;
    bit0Prob = (bit0Count * scale) >> (31 - kBitLengthShift);
    updateCycle = (5 * updateCycle) >> 2;
    if (updateCycle > 64) updateCycle = 64;
    bitsUntilUpdate = updateCycle;
  }
};

// Adaptive model of `symbols` symbols (2 to 2048).
class SymbolModel {
 public:
  // `resetNow` false: the owner resets it before first use (IntegerDecoder's lazy models), which
  // saves building tables that a chunk never uses.
  explicit SymbolModel(uint32_t symbols, bool resetNow = true)
      : symbols_(symbols), last_(symbols - 1) {
    // The decoder table maps the top bits of value/length to the first candidate symbol. Its size
    // is the decoder's choice (it changes no decoded value): the reference uses a quarter of an
    // entry per symbol and only above 16 symbols, leaving a bisection of a few unpredictable
    // branches per symbol; four entries per symbol make most lookups final.
    uint32_t bits = 0;
    while ((1u << bits) < symbols) ++bits;
    bits = std::min(bits + 2, kSymbolLengthShift);
    tableSize_ = 1u << bits;
    tableShift_ = kSymbolLengthShift - bits;
    storage_.resize(size_t(symbols) + 1 + tableSize_ + 2);
    storage_[symbols] = 0xFFFF;  // the decoder's sentinel (distribution values are < 2^15)
    counts_.resize(symbols);
    if (resetNow) reset();
  }
  SymbolModel(const SymbolModel&) = delete;
  SymbolModel& operator=(const SymbolModel&) = delete;
  SymbolModel(SymbolModel&&) = default;
  SymbolModel& operator=(SymbolModel&&) = default;

  void reset() {
    uint32_t* count = counts();
    for (uint32_t k = 0; k < symbols_; ++k) count[k] = 1;
    totalCount_ = 0;
    updateCycle_ = symbols_;
    update();
    symbolsUntilUpdate_ = updateCycle_ = (symbols_ + 6) >> 1;
  }

  uint32_t symbols() const { return symbols_; }

 private:
  friend class ArithmeticDecoder;
  friend class ArithmeticEncoder;
  uint16_t* distribution() { return storage_.data(); }
  uint32_t* counts() { return counts_.data(); }
  uint16_t* table() { return storage_.data() + size_t(symbols_) + 1; }

  void update() {
    uint32_t* count = counts();
    uint16_t* dist = distribution();
    if ((totalCount_ += updateCycle_) > kSymbolMaxCount) {
      totalCount_ = 0;
      for (uint32_t n = 0; n < symbols_; ++n) totalCount_ += (count[n] = (count[n] + 1) >> 1);
    }
    const uint32_t scale = 0x80000000u / totalCount_;
    // The decoder table: entry t is the last symbol whose distribution starts below cell t (the
    // first candidate for a value in cell t), built without a data-dependent branch (a loop per
    // symbol over its cells mispredicts at every end): each symbol counted in the cell after
    // its start, then a running sum.
    uint32_t sum = 0;
    uint16_t* tab = table();
    std::fill(tab, tab + tableSize_ + 2, uint16_t(0));
    for (uint32_t k = 0; k < symbols_; ++k) {
      dist[k] = static_cast<uint16_t>((scale * sum) >> (31 - kSymbolLengthShift));
      sum += count[k];
      ++tab[(dist[k] >> tableShift_) + 1];
    }
    uint32_t below = 0;
    for (uint32_t t = 0; t < tableSize_ + 2; ++t) {
      below += tab[t];
      tab[t] = static_cast<uint16_t>(below - 1);
    }
    tab[0] = 0;
    updateCycle_ = (5 * updateCycle_) >> 2;
    const uint32_t maxCycle = (symbols_ + 6) << 3;
    if (updateCycle_ > maxCycle) updateCycle_ = maxCycle;
    symbolsUntilUpdate_ = updateCycle_;
  }

  uint32_t symbols_, last_;
  uint32_t tableSize_ = 0, tableShift_ = 0;  // decoder table: tableSize_ + 2 entries
  uint32_t totalCount_ = 0, updateCycle_ = 0, symbolsUntilUpdate_ = 0;
  std::vector<uint16_t> storage_;  // distribution (< 2^15), sentinel, decoder table (< 2^11)
  std::vector<uint32_t> counts_;
};

class ArithmeticDecoder {
 public:
  // Starts decoding the bytes [begin, end): reads the first four bytes of the code value.
  void init(const uint8_t* begin, const uint8_t* end) {
    begin_ = p_ = begin;
    end_ = end;
    overrun_ = 0;
    length_ = kMaxLength;
    value_ = uint32_t(byte()) << 24;
    value_ |= uint32_t(byte()) << 16;
    value_ |= uint32_t(byte()) << 8;
    value_ |= uint32_t(byte());
  }

  // Bytes asked for beyond the end of the stream (read as zero). A valid stream never needs
  // them: the encoder pads its last bytes so that the decoder stays inside.
  size_t overrun() const { return overrun_; }
  // Bytes consumed so far (streams without a chunk table continue where the decoder stopped).
  size_t consumed() const { return size_t(p_ - begin_); }

  uint32_t decodeBit(BitModel& m) {
    const uint32_t x = m.bit0Prob * (length_ >> kBitLengthShift);
    uint32_t sym;
    if (value_ < x) {
      sym = 0;
      length_ = x;
      ++m.bit0Count;
    } else {
      sym = 1;
      value_ -= x;
      length_ -= x;
    }
    renormaliseFast();
    if (--m.bitsUntilUpdate == 0) m.update();
    return sym;
  }

  // Inlined into the item decoders: a call per symbol costs measurably at ~40 cycles a symbol.
  [[gnu::always_inline]] inline uint32_t decodeSymbol(SymbolModel& m) {
    uint32_t y = length_;
    const uint16_t* dist = m.distribution();
    length_ >>= kSymbolLengthShift;
    const uint32_t dv = value_ / length_;
    uint32_t t = dv >> m.tableShift_;
    if (t > m.tableSize_) t = m.tableSize_;  // only a damaged stream gets here
    const uint16_t* tab = m.table();
    uint32_t sym = tab[t];
    // Forward from the cell's first candidate (rarely more than one step with four table
    // entries per symbol). The sentinel after the last symbol stops it; a damaged stream's
    // larger values are clamped below the sentinel.
    const uint32_t bound = dv < 0xFFFEu ? dv : 0xFFFEu;
    while (dist[sym + 1] <= bound) ++sym;
    const uint32_t x = dist[sym] * length_;
    if (sym != m.last_) y = dist[sym + 1] * length_;
    value_ -= x;
    length_ = y - x;
    renormaliseFast();
    ++m.counts()[sym];
    if (--m.symbolsUntilUpdate_ == 0) m.update();
    return sym;
  }

  uint32_t readBit() {
    const uint32_t sym = value_ / (length_ >>= 1);
    value_ -= length_ * sym;
    renormaliseFast();
    return sym;
  }

  // 1 to 32 raw bits (more than 19 are read as 16 low bits and the rest).
  [[gnu::always_inline]] inline uint32_t readBits(uint32_t bits) {
    if (bits > 19) [[unlikely]] {
      const uint32_t low = readShort();
      const uint32_t high = readBitsUpTo19(bits - 16);
      return (high << 16) | low;
    }
    return readBitsUpTo19(bits);
  }
  [[gnu::always_inline]] inline uint32_t readBitsUpTo19(uint32_t bits) {
    const uint32_t sym = value_ / (length_ >>= bits);
    value_ -= length_ * sym;
    renormaliseFast();
    return sym;
  }

  uint8_t readByte() { return static_cast<uint8_t>(readBits(8)); }
  uint16_t readShort() {
    const uint32_t sym = value_ / (length_ >>= 16);
    value_ -= length_ * sym;
    renormaliseFast();
    return static_cast<uint16_t>(sym);
  }
  uint32_t readInt() {
    const uint32_t low = readShort();
    const uint32_t high = readShort();
    return (high << 16) | low;
  }
  uint64_t readInt64() {
    const uint64_t low = readInt();
    const uint64_t high = readInt();
    return (high << 32) | low;
  }

 private:
  // Renormalisation without a branch on the length (which a high-entropy field would
  // mispredict): shifts in the 0 to 3 bytes it needs from a 4-byte read; the last bytes of the
  // stream take the bounded byte-wise path.
  [[gnu::always_inline]] inline void renormaliseFast() {
    if (end_ - p_ >= 4) [[likely]] {
      const uint32_t shift = uint32_t(__builtin_clz(length_)) & 24u;  // length_ is never 0
      uint32_t next;
      std::memcpy(&next, p_, 4);
      next = __builtin_bswap32(next);
      value_ = uint32_t((((uint64_t(value_) << 32) | next) << shift) >> 32);
      length_ <<= shift;
      p_ += shift >> 3;
    } else if (length_ < kMinLength) {
      renormalise();
    }
  }
  uint8_t byte() {
    if (p_ < end_) return *p_++;
    ++overrun_;
    return 0;
  }
  void renormalise() {
    do value_ = (value_ << 8) | byte();
    while ((length_ <<= 8) < kMinLength);
  }

  const uint8_t* begin_ = nullptr;
  const uint8_t* p_ = nullptr;
  const uint8_t* end_ = nullptr;
  size_t overrun_ = 0;
  uint32_t value_ = 0, length_ = kMaxLength;
};

// The matching encoder (LASzip's ArithmeticEncoder): writes chunk tables and lets tests craft
// streams and check that decoding inverts encoding for every model path.
class ArithmeticEncoder {
 public:
  explicit ArithmeticEncoder(std::vector<uint8_t>& out) : out_(out), start_(out.size()) {}

  void encodeBit(BitModel& m, uint32_t bit) {
    const uint32_t x = m.bit0Prob * (length_ >> kBitLengthShift);
    if (bit == 0) {
      length_ = x;
      ++m.bit0Count;
    } else {
      add(x);
      length_ -= x;
    }
    if (length_ < kMinLength) renormalise();
    if (--m.bitsUntilUpdate == 0) m.update();
  }

  void encodeSymbol(SymbolModel& m, uint32_t sym) {
    const uint16_t* dist = m.distribution();
    if (sym == m.last_) {
      const uint32_t x = dist[sym] * (length_ >> kSymbolLengthShift);
      add(x);
      length_ -= x;
    } else {
      length_ >>= kSymbolLengthShift;
      const uint32_t x = dist[sym] * length_;
      add(x);
      length_ = dist[sym + 1] * length_ - x;
    }
    if (length_ < kMinLength) renormalise();
    ++m.counts()[sym];
    if (--m.symbolsUntilUpdate_ == 0) m.update();
  }

  void writeBits(uint32_t bits, uint32_t value) {
    if (bits > 19) {
      writeShort(static_cast<uint16_t>(value));
      value >>= 16;
      bits -= 16;
    }
    add(value * (length_ >>= bits));
    if (length_ < kMinLength) renormalise();
  }
  void writeShort(uint16_t v) {
    add(uint32_t(v) * (length_ >>= 16));
    if (length_ < kMinLength) renormalise();
  }
  void writeInt(uint32_t v) {
    writeShort(static_cast<uint16_t>(v));
    writeShort(static_cast<uint16_t>(v >> 16));
  }

  // Flushes the interval and pads so that the decoder never reads past the stream.
  void done() {
    const uint32_t before = base_;
    bool anotherByte = true;
    if (length_ > 2 * kMinLength) {
      base_ += kMinLength;
      length_ = kMinLength >> 1;
    } else {
      base_ += kMinLength >> 1;
      length_ = kMinLength >> 9;
      anotherByte = false;
    }
    if (before > base_) carry();
    renormalise();
    out_.push_back(0);
    out_.push_back(0);
    if (anotherByte) out_.push_back(0);
  }

 private:
  void add(uint32_t x) {
    const uint32_t before = base_;
    base_ += x;
    if (before > base_) carry();
  }
  void carry() {
    size_t i = out_.size();
    while (i > start_ && out_[i - 1] == 0xFF) out_[--i] = 0;
    if (i > start_) ++out_[i - 1];
  }
  void renormalise() {
    do {
      out_.push_back(static_cast<uint8_t>(base_ >> 24));
      base_ <<= 8;
    } while ((length_ <<= 8) < kMinLength);
  }

  std::vector<uint8_t>& out_;
  size_t start_;
  uint32_t base_ = 0, length_ = kMaxLength;
};

// Corrector coding of integer differences (LASzip's IntegerCompressor, decoding side): a
// difference to a prediction is coded as the number k of its significant bits (one symbol model
// per context) and then its position inside [-(2^k - 1), -(2^(k-1))] u [2^(k-1) + 1, 2^k], with
// one model per k (low bits beyond `bitsHigh` raw).
class IntegerDecoder {
 public:
  explicit IntegerDecoder(uint32_t bits = 16, uint32_t contexts = 1, uint32_t bitsHigh = 8,
                          uint32_t range = 0)
      : bitsHigh_(bitsHigh) {
    if (range) {
      corrBits_ = 0;
      corrRange_ = range;
      while (range) {
        range >>= 1;
        ++corrBits_;
      }
      if (corrRange_ == (1u << (corrBits_ - 1))) --corrBits_;
      corrMin_ = -static_cast<int32_t>(corrRange_ / 2);
    } else if (bits && bits < 32) {
      corrBits_ = bits;
      corrRange_ = 1u << bits;
      corrMin_ = -static_cast<int32_t>(corrRange_ / 2);
    } else {
      corrBits_ = 32;
      corrRange_ = 0;
      corrMin_ = INT32_MIN;
    }
    bits_.reserve(contexts);
    // Stamps start unequal to the generation: every model is reset at its first use.
    for (uint32_t i = 0; i < contexts; ++i) bits_.emplace_back(corrBits_ + 1, false);
    bitsStamp_.assign(contexts, 0);
    correctorStamp_.assign(corrBits_ + 1, 0);
    corrector_.reserve(corrBits_ + 1);
    corrector_.emplace_back(2, false);  // placeholder for k = 0, which uses corrector0_
    for (uint32_t i = 1; i <= corrBits_; ++i)
      corrector_.emplace_back(1u << std::min(i, bitsHigh_), false);
  }

  // Resets every model. Lazily: a model is reset when first used after this, which decodes the
  // same and saves most of the per-chunk cost for small chunks (COPC nodes), whose points touch
  // few of the 33 corrector models.
  void reset() {
    if (++generation_ == 0) {  // wrapped after 2^32 resets: reset for real, stamp everything
      for (auto& m : bits_) m.reset();
      for (size_t i = 1; i < corrector_.size(); ++i) corrector_[i].reset();
      generation_ = 1;
      std::fill(bitsStamp_.begin(), bitsStamp_.end(), generation_);
      std::fill(correctorStamp_.begin(), correctorStamp_.end(), generation_);
    }
    corrector0_.reset();
  }

  // The prediction plus the decoded corrector, wrapped into the corrector range.
  int32_t decompress(ArithmeticDecoder& dec, int32_t pred, uint32_t context = 0) {
    readK(dec, context);
    return finish(dec, readHigh(dec), pred);
  }

  // decompress() for N independent streams at once (the chunks of one thread, each with its own
  // IntegerDecoder): lane by lane at every step, so that the processor overlaps their serial
  // chains of interval arithmetic. Each lane decodes exactly what decompress() would.
  template <size_t N>
  [[gnu::always_inline]] static inline void decompressLanes(IntegerDecoder* const ic[],
                                                            ArithmeticDecoder* const dec[],
                                                            const int32_t pred[],
                                                            const uint32_t context[],
                                                            int32_t out[]) {
    uint32_t high[N];
    for (size_t l = 0; l < N; ++l) ic[l]->readK(*dec[l], context[l]);
    for (size_t l = 0; l < N; ++l) high[l] = ic[l]->readHigh(*dec[l]);
    for (size_t l = 0; l < N; ++l) out[l] = ic[l]->finish(*dec[l], high[l], pred[l]);
  }

  // The three steps of decompress(): the corrector's bit count k (a symbol of the context's
  // model), its high part (a symbol of k's model; the bit of k = 0), then its raw low bits and
  // the sum with the prediction.
  [[gnu::always_inline]] inline void readK(ArithmeticDecoder& dec, uint32_t context) {
    k_ = dec.decodeSymbol(bitsModel(context));
  }
  [[gnu::always_inline]] inline uint32_t readHigh(ArithmeticDecoder& dec) {
    if (k_ == 0) return dec.decodeBit(corrector0_);
    if (k_ >= 32) return 0;  // the encoder never emits this; keep it defined
    return dec.decodeSymbol(correctorModel(k_));
  }
  [[gnu::always_inline]] inline int32_t finish(ArithmeticDecoder& dec, uint32_t c, int32_t pred) {
    uint32_t corr;
    if (k_ == 0) {
      corr = c;
    } else if (k_ >= 32) {
      corr = static_cast<uint32_t>(corrMin_);
    } else {
      if (k_ > bitsHigh_) {
        const uint32_t k1 = k_ - bitsHigh_;
        c = (c << k1) | dec.readBits(k1);
      }
      corr = c >= (1u << (k_ - 1)) ? c + 1 : c - ((1u << k_) - 1);
    }
    uint32_t real = static_cast<uint32_t>(pred) + corr;
    if (corrRange_) {
      if (static_cast<int32_t>(real) < 0)
        real += corrRange_;
      else if (real >= corrRange_)
        real -= corrRange_;
    }
    return static_cast<int32_t>(real);
  }

  // The encoding side (the reference's compress): codes real - pred, folded into the range.
  void compress(ArithmeticEncoder& enc, int32_t pred, int32_t real, uint32_t context = 0) {
    uint32_t corr = static_cast<uint32_t>(real) - static_cast<uint32_t>(pred);
    if (corrRange_) {
      const int32_t corrMax = corrMin_ + static_cast<int32_t>(corrRange_ - 1);
      if (static_cast<int32_t>(corr) < corrMin_)
        corr += corrRange_;
      else if (static_cast<int32_t>(corr) > corrMax)
        corr -= corrRange_;
    }
    writeCorrector(enc, static_cast<int32_t>(corr), context);
  }

  // The number of significant bits of the last corrector (later fields choose contexts by it).
  uint32_t k() const { return k_; }
  uint32_t contexts() const { return static_cast<uint32_t>(bits_.size()); }

 private:
  [[gnu::always_inline]] inline SymbolModel& bitsModel(uint32_t context) {
    if (bitsStamp_[context] != generation_) {
      bits_[context].reset();
      bitsStamp_[context] = generation_;
    }
    return bits_[context];
  }
  [[gnu::always_inline]] inline SymbolModel& correctorModel(uint32_t k) {
    if (correctorStamp_[k] != generation_) {
      corrector_[k].reset();
      correctorStamp_[k] = generation_;
    }
    return corrector_[k];
  }

  void writeCorrector(ArithmeticEncoder& enc, int32_t c, uint32_t context) {
    // k: the smallest with c in [-(2^k - 1), 2^k]
    uint32_t c1 = c <= 0 ? 0u - static_cast<uint32_t>(c) : static_cast<uint32_t>(c) - 1;
    k_ = 0;
    while (c1) {
      c1 >>= 1;
      ++k_;
    }
    enc.encodeSymbol(bitsModel(context), k_);
    if (k_ == 0) {
      enc.encodeBit(corrector0_, static_cast<uint32_t>(c));
      return;
    }
    if (k_ >= 32) return;  // INT32_MIN (see finish)
    uint32_t v = c < 0 ? static_cast<uint32_t>(c) + ((1u << k_) - 1) : static_cast<uint32_t>(c) - 1;
    if (k_ <= bitsHigh_) {
      enc.encodeSymbol(correctorModel(k_), v);
    } else {
      const uint32_t k1 = k_ - bitsHigh_;
      enc.encodeSymbol(correctorModel(k_), v >> k1);
      enc.writeBits(k1, v & ((1u << k1) - 1));
    }
  }

  uint32_t bitsHigh_;
  uint32_t corrBits_ = 0, corrRange_ = 0;
  int32_t corrMin_ = 0;
  uint32_t k_ = 0;
  uint32_t generation_ = 1;  // models whose stamp differs are reset before use
  std::vector<uint32_t> bitsStamp_, correctorStamp_;
  std::vector<SymbolModel> bits_;
  BitModel corrector0_;
  std::vector<SymbolModel> corrector_;
};

}  // namespace nestlight::laz
