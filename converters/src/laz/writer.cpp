// LAZ output: compresses an uncompressed LAS file into chunks of 50,000 points, encoded in
// parallel, with the chunk table. Point formats 0-3 (without waveform packets) become LASzip 2's
// pointwise chunked format (items POINT10, GPSTIME11, RGB12 and BYTE of version 2); formats 6-8,
// which the LAS writer chooses when legacy formats cannot hold the points, become the layered
// chunked format of LASzip 3 (laz_layered_encoder.cpp).
//
// Isenburg, "LASzip: lossless compression of LiDAR data", PE&RS 79(2), 2013; the encoders mirror
// the decoders of laz_pointwise.cpp and make the same choices as the LASzip 2 reference encoder
// (laswriteitemcompressed_v2), so that the files it writes decode with any LASzip reader. Written
// by hand because Debian packages neither LASzip nor LAZperf.
#include "laz/writer.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "laz/arithmetic.h"
#include "laz/format.h"
#include "laz/items.h"
#include "nestlight/converters/byte_source.h"
#include "nestlight/octree/error.h"
#include "readers/las_format.h"

namespace nestlight::laz {
namespace {

class ItemEncoder {
 public:
  virtual ~ItemEncoder() = default;
  virtual void init(const uint8_t* first) = 0;
  virtual void write(ArithmeticEncoder& enc, const uint8_t* item) = 0;
};

class Point10Encoder final : public ItemEncoder, private Point10V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

  void write(ArithmeticEncoder& enc, const uint8_t* item) override {
    const uint32_t r = item[14] & 7, n = (item[14] >> 3) & 7;
    const uint32_t m = kReturnMap[n][r], l = returnLevel(n, r);
    const uint16_t intensity = get<uint16_t>(item + 12);
    const uint32_t changed =
        (uint32_t(last_[14] != item[14]) << 5) | (uint32_t(lastIntensity_[m] != intensity) << 4) |
        (uint32_t(last_[15] != item[15]) << 3) | (uint32_t(last_[16] != item[16]) << 2) |
        (uint32_t(last_[17] != item[17]) << 1) |
        uint32_t(get<uint16_t>(last_ + 18) != get<uint16_t>(item + 18));
    enc.encodeSymbol(changed_, changed);
    if (changed & 32) enc.encodeSymbol(bitByte_[last_[14]], item[14]);
    if (changed & 16) {
      intensity_.compress(enc, lastIntensity_[m], intensity, m < 3 ? m : 3);
      lastIntensity_[m] = intensity;
    }
    if (changed & 8) enc.encodeSymbol(classification_[last_[15]], item[15]);
    if (changed & 4)
      enc.encodeSymbol(scanAngle_[(item[14] >> 6) & 1],
                       fold8(int32_t(item[16]) - int32_t(last_[16])));
    if (changed & 2) enc.encodeSymbol(userData_[last_[17]], item[17]);
    if (changed & 1)
      pointSource_.compress(enc, get<uint16_t>(last_ + 18), get<uint16_t>(item + 18));

    int32_t diff = static_cast<int32_t>(get<uint32_t>(item) - get<uint32_t>(last_));
    dx_.compress(enc, xMedian_[m].get(), diff, n == 1);
    xMedian_[m].add(diff);
    uint32_t kBits = dx_.k();
    diff = static_cast<int32_t>(get<uint32_t>(item + 4) - get<uint32_t>(last_ + 4));
    dy_.compress(enc, yMedian_[m].get(), diff, (n == 1) + (kBits < 20 ? (kBits & ~1u) : 20));
    yMedian_[m].add(diff);
    kBits = (dx_.k() + dy_.k()) / 2;
    const int32_t z = get<int32_t>(item + 8);
    dz_.compress(enc, lastHeight_[l], z, (n == 1) + (kBits < 18 ? (kBits & ~1u) : 18));
    lastHeight_[l] = z;
    std::memcpy(last_, item, 20);
  }
};

class GpsTimeEncoder final : public ItemEncoder, private GpsTime11V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

  void write(ArithmeticEncoder& enc, const uint8_t* item) override {
    const uint64_t t = get<uint64_t>(item);
    for (;;) {
      if (lastDiff_[last_] == 0) {
        if (t == time_[last_]) {
          enc.encodeSymbol(zeroDiff_, 0);
          return;
        }
        const int64_t d = int64_t(t - time_[last_]);
        if (d == int64_t(int32_t(d))) {
          enc.encodeSymbol(zeroDiff_, 1);
          ic_.compress(enc, 0, int32_t(d), 0);
          lastDiff_[last_] = int32_t(d);
          extreme_[last_] = 0;
          time_[last_] = t;
          return;
        }
        if (int other = otherSequence(t)) {
          enc.encodeSymbol(zeroDiff_, uint32_t(other + 2));
          last_ = (last_ + uint32_t(other)) & 3;
          continue;
        }
        enc.encodeSymbol(zeroDiff_, 2);
        writeFull(enc, t);
        return;
      }
      if (t == time_[last_]) {
        enc.encodeSymbol(multi_, kMultiUnchanged);
        return;
      }
      const int64_t d64 = int64_t(t - time_[last_]);
      if (d64 == int64_t(int32_t(d64))) {
        const int32_t d = int32_t(d64);
        // Clamped before the conversion (the reference converts unclamped, undefined beyond
        // 2^31); every multiplier beyond the coded range is treated alike anyway.
        const float f = std::clamp(float(d) / float(lastDiff_[last_]), -1e6f, 1e6f);
        const int32_t multi = f >= 0 ? int32_t(f + 0.5f) : int32_t(f - 0.5f);
        const uint32_t lastDiff = uint32_t(lastDiff_[last_]);
        auto times = [&](int32_t k) { return int32_t(uint32_t(k) * lastDiff); };
        if (multi == 1) {
          enc.encodeSymbol(multi_, 1);
          ic_.compress(enc, lastDiff_[last_], d, 1);
          extreme_[last_] = 0;
        } else if (multi > 0) {
          if (multi < kMulti) {
            enc.encodeSymbol(multi_, uint32_t(multi));
            ic_.compress(enc, times(multi), d, multi < 10 ? 2 : 3);
          } else {
            enc.encodeSymbol(multi_, kMulti);
            ic_.compress(enc, times(kMulti), d, 4);
            countExtreme(d);
          }
        } else if (multi < 0) {
          if (multi > kMultiMinus) {
            enc.encodeSymbol(multi_, uint32_t(kMulti - multi));
            ic_.compress(enc, times(multi), d, 5);
          } else {
            enc.encodeSymbol(multi_, uint32_t(kMulti - kMultiMinus));
            ic_.compress(enc, times(kMultiMinus), d, 6);
            countExtreme(d);
          }
        } else {
          enc.encodeSymbol(multi_, 0);
          ic_.compress(enc, 0, d, 7);
          countExtreme(d);
        }
        time_[last_] = t;
        return;
      }
      if (int other = otherSequence(t)) {
        enc.encodeSymbol(multi_, uint32_t(kMultiCodeFull + other));
        last_ = (last_ + uint32_t(other)) & 3;
        continue;
      }
      enc.encodeSymbol(multi_, kMultiCodeFull);
      writeFull(enc, t);
      return;
    }
  }

 private:
  // Another of the four sequences within 32 bits of `t` (1-3 ahead of last_), else 0.
  int otherSequence(uint64_t t) const {
    for (int i = 1; i < 4; ++i) {
      const int64_t d = int64_t(t - time_[(last_ + uint32_t(i)) & 3]);
      if (d == int64_t(int32_t(d))) return i;
    }
    return 0;
  }
  void writeFull(ArithmeticEncoder& enc, uint64_t t) {
    ic_.compress(enc, int32_t(time_[last_] >> 32), int32_t(t >> 32), 8);
    enc.writeInt(uint32_t(t));
    next_ = (next_ + 1) & 3;
    last_ = next_;
    lastDiff_[last_] = 0;
    extreme_[last_] = 0;
    time_[last_] = t;
  }
};

class RgbEncoder final : public ItemEncoder, private Rgb12V2State {
 public:
  void init(const uint8_t* first) override { reset(first); }

  void write(ArithmeticEncoder& enc, const uint8_t* item) override {
    uint16_t v[3];
    for (int c = 0; c < 3; ++c) v[c] = get<uint16_t>(item + 2 * c);
    auto lo = [](uint16_t x) { return int32_t(x & 0xFF); };
    auto hi = [](uint16_t x) { return int32_t(x >> 8); };
    uint32_t sym = 0;
    for (int c = 0; c < 3; ++c) {
      sym |= uint32_t(lo(last_[c]) != lo(v[c])) << (2 * c);
      sym |= uint32_t(hi(last_[c]) != hi(v[c])) << (2 * c + 1);
    }
    sym |= uint32_t(lo(v[0]) != lo(v[1]) || lo(v[0]) != lo(v[2]) || hi(v[0]) != hi(v[1]) ||
                    hi(v[0]) != hi(v[2]))
           << 6;
    enc.encodeSymbol(byteUsed_, sym);
    int32_t dl = 0, dh = 0;
    if (sym & 1) {
      dl = lo(v[0]) - lo(last_[0]);
      enc.encodeSymbol(diff_[0], fold8(dl));
    }
    if (sym & 2) {
      dh = hi(v[0]) - hi(last_[0]);
      enc.encodeSymbol(diff_[1], fold8(dh));
    }
    if (sym & 64) {
      if (sym & 4) enc.encodeSymbol(diff_[2], fold8(lo(v[1]) - clamp8(dl + lo(last_[1]))));
      if (sym & 16) {
        dl = (dl + lo(v[1]) - lo(last_[1])) / 2;
        enc.encodeSymbol(diff_[4], fold8(lo(v[2]) - clamp8(dl + lo(last_[2]))));
      }
      if (sym & 8) enc.encodeSymbol(diff_[3], fold8(hi(v[1]) - clamp8(dh + hi(last_[1]))));
      if (sym & 32) {
        dh = (dh + hi(v[1]) - hi(last_[1])) / 2;
        enc.encodeSymbol(diff_[5], fold8(hi(v[2]) - clamp8(dh + hi(last_[2]))));
      }
    }
    for (int c = 0; c < 3; ++c) last_[c] = v[c];
  }
};

class ByteEncoder final : public ItemEncoder, private ByteV2State {
 public:
  explicit ByteEncoder(size_t n) : ByteV2State(n) {}
  void init(const uint8_t* first) override { reset(first); }
  void write(ArithmeticEncoder& enc, const uint8_t* item) override {
    for (size_t i = 0; i < last_.size(); ++i) {
      enc.encodeSymbol(models_[i], fold8(int32_t(item[i]) - int32_t(last_[i])));
      last_[i] = item[i];
    }
  }
};

// One thread's encoders for a record layout.
class PointwiseEncoder final : public ChunkEncoder {
 public:
  explicit PointwiseEncoder(const LaszipInfo& info) : recordSize_(info.recordSize()) {
    size_t at = 0;
    for (const Item& it : info.items) {
      switch (it.type) {
        case ItemType::Point10:
          items_.push_back(std::make_unique<Point10Encoder>());
          break;
        case ItemType::GpsTime11:
          items_.push_back(std::make_unique<GpsTimeEncoder>());
          break;
        case ItemType::Rgb12:
          items_.push_back(std::make_unique<RgbEncoder>());
          break;
        case ItemType::Byte:
          items_.push_back(std::make_unique<ByteEncoder>(it.size));
          break;
        default:
          NL_CHECK_MSG(false, "no encoder for " + itemName(it.type));
      }
      offsets_.push_back(at);
      at += it.size;
    }
  }
  void encode(const uint8_t* records, size_t n, std::vector<uint8_t>& out) override {
    out.assign(records, records + recordSize_);
    for (size_t i = 0; i < items_.size(); ++i) items_[i]->init(records + offsets_[i]);
    ArithmeticEncoder enc(out);
    for (size_t p = 1; p < n; ++p) {
      const uint8_t* rec = records + p * recordSize_;
      for (size_t i = 0; i < items_.size(); ++i) items_[i]->write(enc, rec + offsets_[i]);
    }
    enc.done();
  }

 private:
  size_t recordSize_;
  std::vector<std::unique_ptr<ItemEncoder>> items_;
  std::vector<size_t> offsets_;
};

}  // namespace

static LaszipInfo infoFor(int pf, size_t recordLength, const std::string& nameForErrors) {
  if (pf < 0 || pf > 8 || pf == 4 || pf == 5)
    throw Error(nameForErrors, "",
                "LAZ output covers point formats 0-3 and 6-8 (no waveform packets); these points "
                "need LAS point format " +
                    std::to_string(pf) + ": write .las instead");
  LaszipInfo info;
  info.chunkSize = kChunkPoints;
  const size_t extra = recordLength - las::kBaseRecordSize[pf];
  if (pf <= 3) {
    info.compressor = Compressor::PointwiseChunked;
    info.versionMajor = 2;
    info.versionMinor = 2;
  } else {
    info.compressor = Compressor::LayeredChunked;
    info.versionMajor = 3;
    info.versionMinor = 4;
    info.versionRevision = 3;
  }
  info.items = itemsFor(pf, extra, pf <= 3 ? 2 : 3);
  NL_CHECK(info.recordSize() == recordLength);
  return info;
}

struct ChunkWriter::Encoders {
  explicit Encoders(const LaszipInfo& info)
      : local([&info]() -> std::unique_ptr<ChunkEncoder> {
          if (info.compressor == Compressor::LayeredChunked) return makeLayeredEncoder(info);
          return std::make_unique<PointwiseEncoder>(info);
        }) {}
  tbb::enumerable_thread_specific<std::unique_ptr<ChunkEncoder>> local;
};

ChunkWriter::ChunkWriter(int pointFormat, size_t recordLength, std::string nameForErrors)
    : info_(infoFor(pointFormat, recordLength, nameForErrors)),
      recordLength_(recordLength),
      name_(std::move(nameForErrors)),
      encoders_(std::make_unique<Encoders>(info_)) {}

ChunkWriter::~ChunkWriter() = default;

std::vector<uint8_t> ChunkWriter::vlrFor(int pointFormat, size_t recordLength,
                                         const std::string& nameForErrors) {
  return vlrFor(infoFor(pointFormat, recordLength, nameForErrors));
}

std::vector<uint8_t> ChunkWriter::vlrFor(const LaszipInfo& info) {
  std::vector<uint8_t> vlr(las::kVlrHeaderSize + 34 + 6 * info.items.size(), 0);
  const std::string user = kLaszipUserId;
  std::copy(user.begin(), user.end(), vlr.begin() + 2);
  las::store<uint16_t>(&vlr[18], kLaszipRecordId);
  las::store<uint16_t>(&vlr[20], uint16_t(vlr.size() - las::kVlrHeaderSize));
  const std::string text = "Nestlight LASzip encoder";
  std::copy(text.begin(), text.end(), vlr.begin() + 22);
  uint8_t* p = &vlr[las::kVlrHeaderSize];
  las::store<uint16_t>(p + 0, uint16_t(info.compressor));
  las::store<uint16_t>(p + 2, 0);  // arithmetic coder
  p[4] = info.versionMajor;
  p[5] = info.versionMinor;
  las::store<uint16_t>(p + 6, info.versionRevision);
  las::store<uint32_t>(p + 8, 0);
  las::store<uint32_t>(p + 12, info.chunkSize);
  las::store<int64_t>(p + 16, -1);  // no special EVLRs
  las::store<int64_t>(p + 24, -1);
  las::store<uint16_t>(p + 32, uint16_t(info.items.size()));
  for (size_t i = 0; i < info.items.size(); ++i) {
    las::store<uint16_t>(p + 34 + 6 * i, uint16_t(info.items[i].type));
    las::store<uint16_t>(p + 36 + 6 * i, info.items[i].size);
    las::store<uint16_t>(p + 38 + 6 * i, info.items[i].version);
  }
  return vlr;
}

void ChunkWriter::put(const void* p, size_t n) {
  if (n && std::fwrite(p, 1, n, f_) != n)
    throw Error(file_, "", std::string("cannot write: ") + std::strerror(errno));
}

void ChunkWriter::begin(std::FILE* f, std::string fileName, uint64_t pointStart) {
  NL_CHECK(!f_);
  f_ = f;
  file_ = std::move(fileName);
  tableSlot_ = pointStart;
  if (::fseeko(f_, off_t(pointStart), SEEK_SET) != 0)
    throw Error(file_, "", std::string("cannot seek: ") + std::strerror(errno));
  const int64_t placeholder = 0;
  put(&placeholder, 8);
  at_ = pointStart + 8;
}

void ChunkWriter::add(const uint8_t* records, size_t n) {
  NL_CHECK(f_);
  pending_.insert(pending_.end(), records, records + n * recordLength_);
  points_ += n;
  if (pending_.size() >= kGroupChunks * kChunkPoints * recordLength_) flush(false);
}

void ChunkWriter::flush(bool all) {
  const size_t n = pending_.size() / recordLength_;
  const size_t chunks = all ? (n + kChunkPoints - 1) / kChunkPoints : n / kChunkPoints;
  if (chunks == 0) return;
  std::vector<std::vector<uint8_t>> out(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
    const size_t first = c * kChunkPoints;
    const size_t m = std::min<size_t>(kChunkPoints, n - first);
    encoders_->local.local()->encode(pending_.data() + first * recordLength_, m, out[c]);
  });
  for (auto& o : out) {
    put(o.data(), o.size());
    chunkBytes_.push_back(uint32_t(o.size()));
    at_ += o.size();
  }
  const size_t used = std::min(n, chunks * size_t(kChunkPoints)) * recordLength_;
  pending_.erase(pending_.begin(), pending_.begin() + ptrdiff_t(used));
}

void ChunkWriter::finish() {
  NL_CHECK(f_);
  flush(true);
  // The chunk table: version 0, the count, then each chunk's bytes predicted from the previous.
  std::vector<uint8_t> table(8, 0);
  las::store<uint32_t>(&table[4], uint32_t(chunkBytes_.size()));
  {
    ArithmeticEncoder enc(table);
    IntegerDecoder ic(32, 2);
    for (size_t i = 0; i < chunkBytes_.size(); ++i)
      ic.compress(enc, i ? int32_t(chunkBytes_[i - 1]) : 0, int32_t(chunkBytes_[i]), 1);
    enc.done();
  }
  put(table.data(), table.size());
  const int64_t tableAt = int64_t(at_);
  if (::fseeko(f_, off_t(tableSlot_), SEEK_SET) != 0)
    throw Error(file_, "", std::string("cannot seek: ") + std::strerror(errno));
  put(&tableAt, 8);
  f_ = nullptr;
}

void compressLas(const std::string& lasPath, const std::string& lazPath,
                 const std::string& nameForErrors) {
  auto src = mapFile(lasPath);
  const uint8_t* d = src->data();
  const size_t size = src->size();
  NL_CHECK(size >= las::kHeaderSize12 && std::memcmp(d, "LASF", 4) == 0);
  const uint16_t headerSize = las::load<uint16_t>(d + 94);
  const uint32_t pointStart = las::load<uint32_t>(d + 96);
  const uint32_t vlrCount = las::load<uint32_t>(d + 100);
  const int pf = d[104];
  const size_t recordLength = las::load<uint16_t>(d + 105);
  const int minor = d[25];
  uint64_t count = las::load<uint32_t>(d + 107);
  if (minor >= 4 && headerSize >= las::kHeaderSize14) {
    const uint64_t count64 = las::load<uint64_t>(d + 247);
    if (count64) count = count64;
    if (las::load<uint32_t>(d + 243) != 0)
      throw Error(nameForErrors, "", "LAZ output of files with EVLRs is not supported");
  }
  ChunkWriter chunks(pf, recordLength, nameForErrors);
  NL_CHECK(uint64_t(pointStart) + count * recordLength <= size);

  // The LASzip VLR goes after the existing ones.
  const std::vector<uint8_t> vlr = chunks.vlr();
  std::vector<uint8_t> head(d, d + pointStart);
  head.insert(head.end(), vlr.begin(), vlr.end());
  head[104] = uint8_t(pf | 0x80);
  las::store<uint32_t>(&head[96], uint32_t(pointStart + vlr.size()));
  las::store<uint32_t>(&head[100], vlrCount + 1);

  std::FILE* f = std::fopen(lazPath.c_str(), "wb");
  if (!f) throw Error(lazPath, "", std::string("cannot create: ") + std::strerror(errno));
  try {
    if (head.size() && std::fwrite(head.data(), 1, head.size(), f) != head.size())
      throw Error(lazPath, "", std::string("cannot write: ") + std::strerror(errno));
    chunks.begin(f, lazPath, head.size());
    const uint64_t step = uint64_t(ChunkWriter::kGroupChunks) * kChunkPoints;
    for (uint64_t first = 0; first < count; first += step) {
      const uint64_t n = std::min(step, count - first);
      chunks.add(d + pointStart + first * recordLength, size_t(n));
      src->releaseBefore(pointStart + (first + n) * recordLength);
    }
    chunks.finish();
  } catch (...) {
    std::fclose(f);
    throw;
  }
  if (std::fclose(f) != 0)
    throw Error(lazPath, "", std::string("cannot close: ") + std::strerror(errno));
}

}  // namespace nestlight::laz
