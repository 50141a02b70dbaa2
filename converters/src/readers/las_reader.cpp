// LAS reader: LAS 1.0-1.4, point data record formats 0-10, uncompressed or LASzip-compressed
// (LAZ, COPC: the chunks are decoded by laz_points.cpp into the same records).
//
// Follows the ASPRS LAS Specification 1.4 - R15 (ASPRS, July 2019): the public header block
// (section 2.4, table 3), variable and extended variable length records (2.5, 2.7), point data
// record formats 0-10 (2.6, tables 7-17), the Extra Bytes VLR (2.5.8, tables 24-25) and the
// coordinate reference system VLRs (2.5.1-2.5.4). Earlier versions are prefixes of 1.4: 1.0-1.2
// end the header at byte 227, 1.3 at 235.
//
// The reader parses in place from the mapped bytes. Everything it reads is checked against the
// size of the input first, because the reader is fuzzed and a header is just a claim: counts,
// offsets and lengths are compared without multiplying so that they cannot overflow.
#include <tbb/task_arena.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <set>
#include <string>

#include "laz/points.h"
#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "readers/las_format.h"

namespace nestlight {
namespace {

using las::load;

// Header strings are fixed-size and NUL-padded; the bytes are untrusted, and JSON must be valid
// UTF-8 to be written, so anything but printable ASCII (and line breaks for WKT) becomes '?'.
std::string fixedString(const uint8_t* p, size_t n, bool multiline = false) {
  std::string s;
  for (size_t i = 0; i < n && p[i] != 0; ++i) {
    const char c = static_cast<char>(p[i]);
    const bool ok =
        (p[i] >= 0x20 && p[i] < 0x7f) || (multiline && (c == '\n' || c == '\r' || c == '\t'));
    s.push_back(ok ? c : '?');
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

std::string shortest(double v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// Decodes `n` records of point format PF starting at `rec` into world xyz and the base layout
// (las::baseLayout(PF)) followed by the record's extra bytes, verbatim. Offsets are constants so
// that the loop compiles to plain loads and stores; nothing here can fail.
template <int PF>
void decodeRecords(const uint8_t* rec, size_t n, size_t recordLength, const Vec3d& scale,
                   const Vec3d& offset, double* xyz, uint8_t* out, size_t stride,
                   size_t extraBytes) {
  constexpr bool kLegacy = las::isLegacyFormat(PF);
  constexpr size_t kBase = las::kBaseRecordSize[PF];
  constexpr size_t kGpsAt = kLegacy ? 20 : 22;
  constexpr size_t kRgbAt = kLegacy ? (las::hasGps(PF) ? 28 : 20) : 30;
  constexpr size_t kNirAt = 36;
  constexpr size_t kWaveAt = kBase - las::kWavePacketBytes;
  for (size_t i = 0; i < n; ++i, rec += recordLength, out += stride, xyz += 3) {
    xyz[0] = load<int32_t>(rec + 0) * scale.x + offset.x;
    xyz[1] = load<int32_t>(rec + 4) * scale.y + offset.y;
    xyz[2] = load<int32_t>(rec + 8) * scale.z + offset.z;
    std::memcpy(out, rec + 12, 2);  // intensity
    size_t o;
    if constexpr (kLegacy) {
      const uint8_t bits = rec[14], cls = rec[15];
      out[2] = bits & 7;                   // return number
      out[3] = (bits >> 3) & 7;            // number of returns
      out[4] = (bits >> 6) & 1;            // scan direction
      out[5] = bits >> 7;                  // edge of flight line
      out[6] = cls & 31;                   // classification
      out[7] = cls >> 5;                   // synthetic, key-point, withheld
      out[8] = rec[16];                    // scan angle rank
      out[9] = rec[17];                    // user data
      std::memcpy(out + 10, rec + 18, 2);  // point source id
      o = 12;
    } else {
      const uint8_t returns = rec[14], flags = rec[15];
      out[2] = returns & 15;
      out[3] = returns >> 4;
      out[4] = (flags >> 6) & 1;
      out[5] = flags >> 7;
      out[6] = rec[16];                    // classification
      out[7] = flags & 15;                 // synthetic, key-point, withheld, overlap
      out[8] = (flags >> 4) & 3;           // scanner channel
      std::memcpy(out + 9, rec + 18, 2);   // scan angle
      out[11] = rec[17];                   // user data
      std::memcpy(out + 12, rec + 20, 2);  // point source id
      o = 14;
    }
    if constexpr (las::hasGps(PF)) std::memcpy(out + o, rec + kGpsAt, 8), o += 8;
    if constexpr (las::hasRgb(PF)) std::memcpy(out + o, rec + kRgbAt, 6), o += 6;
    if constexpr (las::hasNir(PF)) std::memcpy(out + o, rec + kNirAt, 2), o += 2;
    if constexpr (las::hasWave(PF))
      std::memcpy(out + o, rec + kWaveAt, las::kWavePacketBytes), o += las::kWavePacketBytes;
    if (extraBytes) std::memcpy(out + o, rec + kBase, extraBytes);
  }
}

using DecodeFn = void (*)(const uint8_t*, size_t, size_t, const Vec3d&, const Vec3d&, double*,
                          uint8_t*, size_t, size_t);
constexpr DecodeFn kDecoders[las::kMaxPointFormat + 1] = {
    decodeRecords<0>, decodeRecords<1>, decodeRecords<2>, decodeRecords<3>,
    decodeRecords<4>, decodeRecords<5>, decodeRecords<6>, decodeRecords<7>,
    decodeRecords<8>, decodeRecords<9>, decodeRecords<10>};

class LasReader final : public PointReader {
 public:
  LasReader(std::shared_ptr<ByteSource> src, const ReadOptions& options)
      : src_(std::move(src)), options_(options) {
    parse();
  }

  const SourceHeader& header() const override { return header_; }
  std::vector<std::string> warnings() const override { return warnings_; }
  uint64_t bytesTotal() const override {
    if (restricted_ && laz_) return chunkOffset(end_) - chunkOffset(first_);
    return restricted_ ? (stop() - first_) * recordLength_ : src_->size();
  }
  uint64_t bytesConsumed() const override {
    if (restricted_ && laz_)
      return chunkOffset(std::min<uint64_t>(nextChunk_, end_)) - chunkOffset(first_);
    if (laz_) {
      const auto& chunks = laz_->chunks();
      return nextChunk_ >= chunks.size() ? src_->size() : chunks[nextChunk_].offset;
    }
    if (restricted_) return (std::min(next_, stop()) - first_) * recordLength_;
    return next_ >= count_ ? src_->size() : pointStart_ + next_ * recordLength_;
  }
  // Parts: ranges of an uncompressed file's fixed-size records, or of a LAZ file's chunks where
  // its chunk table (or COPC hierarchy) says where each starts; a LAZ file without one is whole.
  uint64_t splitUnits() const override {
    if (laz_) return laz_->hasChunkTable() ? laz_->chunks().size() : 1;
    return count_;
  }
  void restrictTo(uint64_t first, uint64_t end) override {
    const uint64_t units = splitUnits();
    NL_CHECK(first <= end && end <= units && (units > 1 || (first == 0 && end == units)));
    first_ = first, end_ = end;
    restricted_ = !(first == 0 && end == units);  // the whole file: as never restricted
    rewind();
  }
  uint64_t pointsUnreadable() const override { return laz_ ? laz_->unreadable() : 0; }

  bool read(PointBatch& batch, size_t maxPoints) override {
    if (laz_) return readLaz(batch, maxPoints) != 0;
    batch.clear();
    if (next_ >= stop() || maxPoints == 0) return false;
    const size_t n = static_cast<size_t>(std::min<uint64_t>(maxPoints, stop() - next_));
    const size_t stride = header_.layout.stride();
    batch.xyz.resize(3 * n);
    batch.attrs.resize(n * stride);
    const uint8_t* rec = src_->data() + pointStart_ + next_ * recordLength_;
    kDecoders[pointFormat_](rec, n, recordLength_, scale_, offset_, batch.xyz.data(),
                            batch.attrs.data(), stride, extraBytes_);
    next_ += n;
    src_->releaseBefore(pointStart_ + next_ * recordLength_);
    return true;
  }

  // Fixed-size records: skipping is free, so the counting pass decodes one record in `step`.
  size_t readSampled(PointBatch& batch, size_t maxPoints, size_t step) override {
    if (laz_) {
      // Compressed points cannot be skipped one by one, but whole chunks can.
      if (step <= 1 || !laz_->hasChunkTable()) return readLaz(batch, maxPoints) ? 1 : 0;
      batch.clear();
      std::vector<size_t> which;
      const size_t weight = takeChunks(maxPoints, step, which);
      if (weight) decodeChunks(which, batch);
      return weight;
    }
    batch.clear();
    if (step <= 1) return read(batch, maxPoints) ? 1 : 0;
    if (next_ >= stop() || maxPoints == 0) return false;
    const uint64_t left = (stop() - next_ + step - 1) / step;
    const size_t n = static_cast<size_t>(std::min<uint64_t>(maxPoints, left));
    const size_t stride = header_.layout.stride();
    batch.xyz.resize(3 * n);
    batch.attrs.resize(n * stride);
    const uint8_t* rec = src_->data() + pointStart_ + next_ * recordLength_;
    kDecoders[pointFormat_](rec, n, recordLength_ * step, scale_, offset_, batch.xyz.data(),
                            batch.attrs.data(), stride, extraBytes_);
    next_ = std::min<uint64_t>(stop(), next_ + uint64_t(n) * step);
    src_->releaseBefore(pointStart_ + next_ * recordLength_);
    return step;
  }

  // Every point record as the uncompressed file stores it, in file order, in batches.
  void forEachRecords(const std::function<void(const uint8_t*, size_t)>& sink) {
    rewind();
    if (!laz_) {
      const size_t batch = std::max<size_t>((16u << 20) / recordLength_, 1);
      for (uint64_t i = 0; i < count_; i += batch) {
        const size_t n = static_cast<size_t>(std::min<uint64_t>(batch, count_ - i));
        sink(src_->data() + pointStart_ + i * recordLength_, n);
      }
      return;
    }
    PointBatch unused;
    while (readLaz(unused, SIZE_MAX, false)) {
      sink(cache_.data(), cacheCount_);
      cacheAt_ = cacheCount_;
    }
  }
  size_t recordLength() const { return recordLength_; }

  // LAZ with a chunk table: whole chunks, decoded by batch.finish() on the caller's workers.
  size_t readDeferred(PointBatch& batch, size_t maxPoints, size_t step) override {
    if (!laz_ || !laz_->hasChunkTable() || cacheAt_ < cacheCount_)
      return PointReader::readDeferred(batch, maxPoints, step);
    batch.clear();
    std::vector<size_t> which;
    const size_t weight = takeChunks(maxPoints, step, which);
    if (!weight) return 0;
    for (size_t c : which) batch.pendingPoints += laz_->chunks()[c].points;
    batch.pending = [this, which = std::move(which)](PointBatch& b) { decodeChunks(which, b); };
    return weight;
  }

  void rewind() override {
    next_ = laz_ ? 0 : first_;
    src_->releaseBefore(restricted_ && !laz_ ? pointStart_ + first_ * recordLength_ : 0);
    if (laz_) {
      laz_->rewind();
      nextChunk_ = restricted_ ? size_t(first_) : 0;
      cacheAt_ = cacheCount_ = 0;
    }
  }

 private:
  [[noreturn]] void fail(uint64_t at, const std::string& reason) const {
    throw Error(src_->name(), Error::atByte(at), reason);
  }
  // A damaged chunk met by the sampled planning pass and again by the full pass is one warning.
  void warn(std::string w) {
    if (std::find(warnings_.begin(), warnings_.end(), w) == warnings_.end())
      warnings_.push_back(std::move(w));
  }

  void parse();
  void describeHeader(int major, int minor, uint16_t headerSize, uint16_t globalEncoding,
                      bool has14);
  void countRecords(uint64_t declared, uint64_t dataEnd);
  void readVlrs(uint64_t start, uint32_t count, uint64_t limit);
  void readEvlrs(uint64_t start, uint32_t count);
  void handleRecord(const std::string& user, uint16_t id, const uint8_t* data, uint64_t length,
                    uint64_t at, bool extended);
  void buildLayout();
  void setupLaz(uint64_t declared, uint64_t dataEnd);
  std::vector<laz::Chunk> copcChunks();
  size_t readLaz(PointBatch& batch, size_t maxPoints, bool decodeFields = true);
  size_t takeChunks(size_t maxPoints, size_t step, std::vector<size_t>& which);
  void decodeChunks(const std::vector<size_t>& which, PointBatch& batch) const;

  std::shared_ptr<ByteSource> src_;
  ReadOptions options_;
  SourceHeader header_;
  std::vector<std::string> warnings_;

  int pointFormat_ = 0;
  uint64_t pointStart_ = 0;
  size_t recordLength_ = 0;
  size_t extraBytes_ = 0;
  uint64_t count_ = 0;
  uint64_t next_ = 0;
  // restrictTo: the records [first_, end_) alone.
  bool restricted_ = false;
  uint64_t first_ = 0, end_ = 0;
  uint64_t stop() const { return restricted_ ? end_ : count_; }
  // LAZ: the chunk after the last one to read, and where chunk `c` starts (the end of the file
  // for the last).
  size_t chunkStop() const { return restricted_ ? size_t(end_) : laz_->chunks().size(); }
  uint64_t chunkOffset(uint64_t c) const {
    return c < laz_->chunks().size() ? laz_->chunks()[c].offset : src_->size();
  }
  Vec3d scale_, offset_;

  nlohmann::json geotiff_;
  const uint8_t* copcInfo_ = nullptr;
  const uint8_t* laszipVlr_ = nullptr;
  uint64_t laszipVlrLength_ = 0, laszipVlrAt_ = 0;
  bool compressed_ = false;
  std::unique_ptr<laz::LazPoints> laz_;
  laz::RecordBuffer cache_;  // decoded LAZ records not yet returned
  size_t cacheAt_ = 0, cacheCount_ = 0;
  size_t nextChunk_ = 0;  // first LAZ chunk not decoded yet
  const uint8_t* extraBytesVlr_ = nullptr;
  uint64_t extraBytesVlrLength_ = 0;
  uint64_t extraBytesVlrAt_ = 0;
};

void LasReader::parse() {
  const uint8_t* d = src_->data();
  const uint64_t size = src_->size();
  header_.path = src_->name();
  header_.format = "las";

  if (size < 4 || std::memcmp(d, "LASF", 4) != 0)
    fail(0, size == 0 ? "empty file, not a LAS file" : "not a LAS file (no 'LASF' signature)");
  if (size < las::kHeaderSize12)
    fail(size, "file ends inside the LAS header (" + std::to_string(size) + " of at least " +
                   std::to_string(las::kHeaderSize12) + " bytes)");

  const int major = d[24], minor = d[25];
  if (major != 1)
    fail(24, "unsupported LAS version " + std::to_string(major) + "." + std::to_string(minor));
  if (minor > 4) warn("LAS version 1." + std::to_string(minor) + " is newer than 1.4; read as 1.4");
  const uint16_t headerSize = load<uint16_t>(d + 94);
  if (headerSize < las::kHeaderSize12)
    fail(94, "header size " + std::to_string(headerSize) + " is smaller than the " +
                 std::to_string(las::kHeaderSize12) + " bytes of a LAS header");
  if (headerSize > size)
    fail(94, "header size " + std::to_string(headerSize) + " runs past the end of the file (" +
                 std::to_string(size) + " bytes)");
  const size_t versionHeaderSize = minor >= 4   ? las::kHeaderSize14
                                   : minor == 3 ? las::kHeaderSize13
                                                : las::kHeaderSize12;
  if (headerSize < versionHeaderSize)
    warn("header size " + std::to_string(headerSize) + " is smaller than LAS 1." +
         std::to_string(minor) + " needs (" + std::to_string(versionHeaderSize) +
         "); fields past it are ignored");
  const bool has13 = headerSize >= las::kHeaderSize13 && minor >= 3;
  const bool has14 = headerSize >= las::kHeaderSize14 && minor >= 4;

  const uint16_t globalEncoding = load<uint16_t>(d + 6);
  pointStart_ = load<uint32_t>(d + 96);
  const uint32_t vlrCount = load<uint32_t>(d + 100);
  const uint8_t formatByte = d[104];
  recordLength_ = load<uint16_t>(d + 105);
  const uint32_t legacyCount = load<uint32_t>(d + 107);

  // LASzip marks compressed files by setting bit 7 (and bit 6 in some versions) of the format.
  compressed_ = (formatByte & 0xC0) != 0;
  pointFormat_ = formatByte & 0x3F;
  if (compressed_) header_.format = "laz";
  if (pointFormat_ > las::kMaxPointFormat)
    fail(104, "unknown point data record format " + std::to_string(pointFormat_) +
                  " (LAS 1.4 defines 0-10)");
  if (recordLength_ < las::kBaseRecordSize[pointFormat_])
    fail(105, "point record length " + std::to_string(recordLength_) + " is smaller than the " +
                  std::to_string(las::kBaseRecordSize[pointFormat_]) + " bytes point format " +
                  std::to_string(pointFormat_) + " needs");
  extraBytes_ = recordLength_ - las::kBaseRecordSize[pointFormat_];
  if (pointStart_ < headerSize)
    fail(96, "offset to point data " + std::to_string(pointStart_) + " lies inside the header (" +
                 std::to_string(headerSize) + " bytes)");
  if (pointStart_ > size)
    fail(96, "offset to point data " + std::to_string(pointStart_) +
                 " is beyond the end of the file (" + std::to_string(size) + " bytes)");

  for (int a = 0; a < 3; ++a) {
    scale_[a] = load<double>(d + 131 + 8 * a);
    offset_[a] = load<double>(d + 155 + 8 * a);
  }
  if (!(std::isfinite(scale_.x) && std::isfinite(scale_.y) && std::isfinite(scale_.z) &&
        scale_.x != 0 && scale_.y != 0 && scale_.z != 0))
    warn("scale factors (" + shortest(scale_.x) + ", " + shortest(scale_.y) + ", " +
         shortest(scale_.z) + ") are not all finite and non-zero");
  header_.scale = scale_;
  header_.offset = offset_;
  Box3d bounds;
  bounds.max = {load<double>(d + 179), load<double>(d + 195), load<double>(d + 211)};
  bounds.min = {load<double>(d + 187), load<double>(d + 203), load<double>(d + 219)};
  header_.declaredBounds = bounds;

  uint64_t declared = legacyCount;
  uint64_t evlrStart = 0;
  uint32_t evlrCount = 0;
  uint64_t waveformStart = 0;
  if (has13) waveformStart = load<uint64_t>(d + 227);
  if (has14) {
    evlrStart = load<uint64_t>(d + 235);
    evlrCount = load<uint32_t>(d + 243);
    const uint64_t count64 = load<uint64_t>(d + 247);
    // Writers of 1.4 files for formats 0-5 often fill only the legacy count.
    if (count64 != 0 || legacyCount == 0) {
      if (legacyCount != 0 && legacyCount != count64)
        warn("legacy point count " + std::to_string(legacyCount) +
             " differs from the 64-bit count " + std::to_string(count64) + "; using the latter");
      declared = count64;
    }
  }
  header_.declaredPoints = declared;

  describeHeader(major, minor, headerSize, globalEncoding, has14);
  header_.details["vlrs"] = nlohmann::json::array();

  readVlrs(headerSize, vlrCount, pointStart_);

  // Where the point records end: at the first EVLR (1.4) or the internal waveform data (1.3),
  // when those lie after the point data start, else at the end of the file.
  uint64_t dataEnd = size;
  if (has14 && evlrCount > 0) {
    if (evlrStart < pointStart_ || evlrStart > size) {
      const std::string what = "start of first EVLR " + std::to_string(evlrStart) +
                               (evlrStart < pointStart_ ? " lies before the point data"
                                                        : " is beyond the end of the file (" +
                                                              std::to_string(size) + " bytes)");
      if (!options_.lenient) fail(235, what);
      warn(what + "; EVLRs ignored");
    } else {
      dataEnd = evlrStart;
      header_.details["evlrs"] = nlohmann::json::array();
      readEvlrs(evlrStart, evlrCount);
    }
  }
  if (has13 && (globalEncoding & las::kEncodingWaveformInternal) && waveformStart >= pointStart_ &&
      waveformStart < dataEnd)
    dataEnd = waveformStart;

  if (compressed_) {
    setupLaz(declared, dataEnd);
  } else {
    countRecords(declared, dataEnd);
  }

  buildLayout();
  if (!geotiff_.is_null()) {
    if (geotiff_.contains("keys"))
      header_.crs["geotiff"] = std::move(geotiff_);
    else
      warn("GeoTIFF parameters without a GeoKeyDirectory (record 34735) ignored");
  }
}

// The header's descriptive fields, for `info` (none of them changes how points are read).
void LasReader::describeHeader(int major, int minor, uint16_t headerSize, uint16_t globalEncoding,
                               bool has14) {
  const uint8_t* d = src_->data();
  nlohmann::json& det = header_.details;
  det["version"] = std::to_string(major) + "." + std::to_string(minor);
  det["point_format"] = pointFormat_;
  det["record_length"] = recordLength_;
  det["extra_bytes"] = extraBytes_;
  det["header_size"] = headerSize;
  det["file_source_id"] = load<uint16_t>(d + 4);
  det["global_encoding"] = globalEncoding;
  det["system_identifier"] = fixedString(d + 26, 32);
  det["generating_software"] = fixedString(d + 58, 32);
  det["creation_day_of_year"] = load<uint16_t>(d + 90);
  det["creation_year"] = load<uint16_t>(d + 92);
  {
    char guid[40];
    std::snprintf(guid, sizeof guid, "%08x-%04x-%04x-%02x%02x-%02x%02x%02x%02x%02x%02x",
                  load<uint32_t>(d + 8), load<uint16_t>(d + 12), load<uint16_t>(d + 14), d[16],
                  d[17], d[18], d[19], d[20], d[21], d[22], d[23]);
    det["project_id"] = guid;
  }
  nlohmann::json byReturn = nlohmann::json::array();
  if (has14)
    for (int r = 0; r < 15; ++r) byReturn.push_back(load<uint64_t>(d + 255 + 8 * r));
  else
    for (int r = 0; r < 5; ++r) byReturn.push_back(load<uint32_t>(d + 111 + 4 * r));
  det["points_by_return"] = std::move(byReturn);
}

// An uncompressed file's records: the declared count, or the complete records the file holds
// when it holds fewer (an error unless lenient); bytes after them that no EVLR explains are a
// warning, since they often mean a header that undercounts.
void LasReader::countRecords(uint64_t declared, uint64_t dataEnd) {
  const uint64_t complete = (dataEnd - pointStart_) / recordLength_;
  if (declared > complete) {
    const uint64_t at = pointStart_ + complete * recordLength_;
    const std::string what = "header declares " + std::to_string(declared) +
                             " points but the file holds only " + std::to_string(complete) +
                             " complete records of " + std::to_string(recordLength_) +
                             " bytes (point data from byte " + std::to_string(pointStart_) +
                             " to byte " + std::to_string(dataEnd) + ")";
    if (!options_.lenient) fail(at, what + "; the file is truncated or its header is wrong");
    warn(src_->name() + ": " + Error::atByte(at) + ": " + what + "; read the " +
         std::to_string(complete) + " complete records");
    count_ = complete;
  } else {
    count_ = declared;
    const uint64_t end = pointStart_ + declared * recordLength_;
    if (end < dataEnd) {
      const uint64_t trailing = dataEnd - end;
      std::string what = std::to_string(trailing) + " bytes after the " + std::to_string(declared) +
                         " declared points (from byte " + std::to_string(end) + ") are not EVLRs";
      if (trailing >= recordLength_)
        what += "; they would hold " + std::to_string(trailing / recordLength_) +
                " more records: does the header claim fewer points than the file holds?";
      warn(what);
    }
  }
}

void LasReader::readVlrs(uint64_t start, uint32_t count, uint64_t limit) {
  const uint8_t* d = src_->data();
  const uint64_t size = src_->size();
  uint64_t p = start;
  for (uint32_t i = 0; i < count; ++i) {
    const std::string which =
        "variable length record " + std::to_string(i + 1) + " of " + std::to_string(count);
    if (size - p < las::kVlrHeaderSize)
      fail(p, which + " runs past the end of the file (" + std::to_string(size) + " bytes)");
    const uint16_t length = load<uint16_t>(d + p + 20);
    if (size - p - las::kVlrHeaderSize < length)
      fail(p, which + " (" + std::to_string(length) + " bytes) runs past the end of the file (" +
                  std::to_string(size) + " bytes)");
    if (p + las::kVlrHeaderSize + length > limit) {
      warn(Error::atByte(p) + ": " + which + " runs into the point data at byte " +
           std::to_string(limit) + "; it and the following VLRs are ignored");
      return;
    }
    handleRecord(fixedString(d + p + 2, 16), load<uint16_t>(d + p + 18),
                 d + p + las::kVlrHeaderSize, length, p, false);
    header_.details["vlrs"].push_back({{"user_id", fixedString(d + p + 2, 16)},
                                       {"record_id", load<uint16_t>(d + p + 18)},
                                       {"length", length},
                                       {"description", fixedString(d + p + 22, 32)}});
    p += las::kVlrHeaderSize + length;
  }
}

void LasReader::readEvlrs(uint64_t start, uint32_t count) {
  const uint8_t* d = src_->data();
  const uint64_t size = src_->size();
  uint64_t p = start;
  for (uint32_t i = 0; i < count; ++i) {
    const std::string which =
        "extended variable length record " + std::to_string(i + 1) + " of " + std::to_string(count);
    if (size - p < las::kEvlrHeaderSize ||
        size - p - las::kEvlrHeaderSize < load<uint64_t>(d + p + 20)) {
      const std::string what =
          which + " runs past the end of the file (" + std::to_string(size) + " bytes)";
      if (!options_.lenient) fail(p, what);
      warn(Error::atByte(p) + ": " + what + "; it and the following EVLRs are ignored");
      return;
    }
    const uint64_t length = load<uint64_t>(d + p + 20);
    handleRecord(fixedString(d + p + 2, 16), load<uint16_t>(d + p + 18),
                 d + p + las::kEvlrHeaderSize, length, p, true);
    header_.details["evlrs"].push_back({{"user_id", fixedString(d + p + 2, 16)},
                                        {"record_id", load<uint16_t>(d + p + 18)},
                                        {"length", length},
                                        {"description", fixedString(d + p + 28, 32)}});
    p += las::kEvlrHeaderSize + length;
  }
}

void LasReader::handleRecord(const std::string& user, uint16_t id, const uint8_t* data,
                             uint64_t length, uint64_t at, bool extended) {
  if (user == "LASF_Projection") {
    if (id == las::kRecordWkt) {
      if (!header_.crs.contains("wkt"))
        header_.crs["wkt"] = fixedString(data, static_cast<size_t>(length), true);
    } else if (id == las::kRecordGeoKeys) {
      nlohmann::json keys = nlohmann::json::array();
      for (uint64_t k = 0; k + 2 <= length; k += 2) keys.push_back(load<uint16_t>(data + k));
      geotiff_["keys"] = std::move(keys);
    } else if (id == las::kRecordGeoDoubles) {
      nlohmann::json values = nlohmann::json::array();
      for (uint64_t k = 0; k + 8 <= length; k += 8) values.push_back(load<double>(data + k));
      geotiff_["doubles"] = std::move(values);
    } else if (id == las::kRecordGeoAscii) {
      // GeoAsciiParams are '|'-separated strings; keep them verbatim (NULs end the last one).
      geotiff_["ascii"] = fixedString(data, static_cast<size_t>(length), true);
    }
  } else if (user == "copc" && id == 1 && !extended && length >= 160) {
    copcInfo_ = data;  // COPC 1.0: must be the first VLR; where it is does not matter here
  } else if (user == laz::kLaszipUserId && id == laz::kLaszipRecordId && !extended) {
    if (laszipVlr_) {
      warn(Error::atByte(at) + ": a second LASzip record is ignored");
      return;
    }
    laszipVlr_ = data;
    laszipVlrLength_ = length;
    laszipVlrAt_ = at;
  } else if (user == "LASF_Spec" && id == las::kRecordExtraBytes) {
    if (extended || extraBytesVlr_) {
      warn(Error::atByte(at) + ": a second Extra Bytes record is ignored");
      return;
    }
    extraBytesVlr_ = data;
    extraBytesVlrLength_ = length;
    extraBytesVlrAt_ = at;
  }
}

void LasReader::buildLayout() {
  PointLayout layout = las::baseLayout(pointFormat_);
  // Names from the file may repeat a standard name or each other; the layout needs them unique.
  auto uniqueName = [&](std::string name) {
    if (!layout.has(name)) return name;
    for (int k = 2;; ++k) {
      std::string candidate = name + "_" + std::to_string(k);
      if (!layout.has(candidate)) return candidate;
    }
  };

  size_t used = 0;  // extra bytes described so far
  if (extraBytesVlr_) {
    const size_t n = static_cast<size_t>(extraBytesVlrLength_ / las::kExtraBytesDescriptorSize);
    if (extraBytesVlrLength_ % las::kExtraBytesDescriptorSize != 0)
      warn(Error::atByte(extraBytesVlrAt_) + ": Extra Bytes record length " +
           std::to_string(extraBytesVlrLength_) + " is not a multiple of 192");
    for (size_t k = 0; k < n; ++k) {
      const uint8_t* e = extraBytesVlr_ + k * las::kExtraBytesDescriptorSize;
      const int dataType = e[2];
      const uint8_t options = e[3];
      Attribute a;
      a.name = fixedString(e + 4, 32);
      if (a.name.empty()) a.name = "extra_" + std::to_string(k);
      std::string description = fixedString(e + 160, 32);
      if (dataType == 0) {
        // Undocumented extra bytes: `options` is their count.
        a.type = ScalarType::U8;
        a.components = options;
      } else if (auto t = las::extraBytesScalar(dataType)) {
        a.type = *t;
        a.components = static_cast<uint32_t>((dataType - 1) / 10 + 1);
        // Values are stored raw; the description keeps what turns them into physical units.
        auto list = [&](const uint8_t* p) {
          std::string s;
          for (uint32_t c = 0; c < a.components; ++c) {
            if (c) s += ',';
            s += shortest(load<double>(p + 8 * c));
          }
          return s;
        };
        if (options & 8)
          description += std::string(description.empty() ? "" : "; ") + "scale=" + list(e + 112);
        if (options & 16)
          description += std::string(description.empty() ? "" : "; ") + "offset=" + list(e + 136);
      } else {
        warn("Extra Bytes descriptor " + std::to_string(k + 1) + " ('" + a.name +
             "') has the reserved data type " + std::to_string(dataType) +
             "; it and the following bytes are kept as '" + las::kUndocumentedExtraBytes + "'");
        break;
      }
      if (a.byteSize() == 0) continue;
      if (a.byteSize() > extraBytes_ - used) {
        warn("Extra Bytes descriptor " + std::to_string(k + 1) + " ('" + a.name + "', " +
             std::to_string(a.byteSize()) + " bytes) runs past the " + std::to_string(extraBytes_) +
             " extra bytes of each record; it and the following descriptors are ignored");
        break;
      }
      a.description = std::move(description);
      a.name = uniqueName(std::move(a.name));
      used += a.byteSize();
      layout.add(std::move(a));
    }
  }
  if (used < extraBytes_)
    layout.add({uniqueName(las::kUndocumentedExtraBytes), ScalarType::U8,
                static_cast<uint32_t>(extraBytes_ - used), "undocumented extra bytes"});
  // The decoders copy the extra bytes verbatim after the base fields.
  NL_CHECK(layout.stride() == las::baseLayout(pointFormat_).stride() + extraBytes_);
  header_.layout = std::move(layout);
  if (las::hasRgb(pointFormat_)) header_.rgbBits = 16;
}

void LasReader::setupLaz(uint64_t declared, uint64_t dataEnd) {
  if (!laszipVlr_)
    fail(104, "the point format byte (" + std::to_string(pointFormat_ | 0x80) +
                  ") says the points are LASzip-compressed, but there is no LASzip record "
                  "(VLR \"laszip encoded\" 22204)");
  laz::LaszipInfo info;
  const std::string bad = laz::parseLaszipVlr(laszipVlr_, static_cast<size_t>(laszipVlrLength_),
                                              pointFormat_, recordLength_, info);
  if (!bad.empty()) fail(laszipVlrAt_ + las::kVlrHeaderSize, bad);
  laz_ = std::make_unique<laz::LazPoints>(
      src_, info, pointStart_, dataEnd, declared, options_.lenient,
      [this](std::string w) { warn(std::move(w)); }, copcChunks());
  count_ = laz_->points();

  nlohmann::json items = nlohmann::json::array();
  for (const laz::Item& it : info.items)
    items.push_back(laz::itemName(it.type) + " v" + std::to_string(it.version) + " (" +
                    std::to_string(it.size) + " bytes)");
  static const char* kCompressors[] = {"none", "pointwise", "pointwise chunked", "layered chunked"};
  header_.details["laszip"] = {
      {"version", std::to_string(info.versionMajor) + "." + std::to_string(info.versionMinor) +
                      "." + std::to_string(info.versionRevision)},
      {"compressor", kCompressors[static_cast<int>(info.compressor)]},
      {"items", std::move(items)},
      {"chunk_size", info.chunkSize == laz::kVariableChunkSize ? nlohmann::json("variable")
                                                               : nlohmann::json(info.chunkSize)},
      {"chunks", laz_->chunks().size()},
      {"chunks_from", laz_->chunkSource()}};
}

// COPC (Cloud Optimized Point Cloud 1.0): the info VLR and the hierarchy pages it points to,
// whose entries name every chunk (offset, bytes, points) of the octree it stores. Returns those
// chunks, or none (with a warning) when the hierarchy is damaged: the chunk table still serves.
std::vector<laz::Chunk> LasReader::copcChunks() {
  if (!copcInfo_) return {};
  const uint8_t* d = src_->data();
  const uint64_t size = src_->size();
  const uint8_t* info = copcInfo_;
  nlohmann::json copc = {
      {"center", {load<double>(info), load<double>(info + 8), load<double>(info + 16)}},
      {"halfsize", load<double>(info + 24)},
      {"spacing", load<double>(info + 32)},
      {"gps_time", {load<double>(info + 56), load<double>(info + 64)}}};
  std::vector<laz::Chunk> chunks;
  std::vector<std::pair<uint64_t, uint64_t>> pages = {
      {load<uint64_t>(info + 40), load<uint64_t>(info + 48)}};
  std::set<uint64_t> seen;
  uint64_t entries = 0, visited = 0;
  int maxLevel = 0;
  while (!pages.empty()) {
    const auto [at, bytes] = pages.back();
    pages.pop_back();
    // Valid pages are disjoint, so together they fit in the file: a hierarchy whose pages
    // overlap (which could make the walk quadratic) stops here.
    visited += bytes;
    if (at > size || bytes > size - at || bytes % 32 != 0 || !seen.insert(at).second ||
        visited > size) {
      warn(Error::atByte(at) + ": COPC hierarchy page of " + std::to_string(bytes) +
           " bytes is damaged (outside the file, not whole entries, listed twice or "
           "overlapping); the hierarchy is ignored");
      return {};
    }
    for (uint64_t e = at; e < at + bytes; e += 32) {
      const int32_t level = load<int32_t>(d + e);
      const uint64_t offset = load<uint64_t>(d + e + 16);
      const int32_t byteSize = load<int32_t>(d + e + 24), count = load<int32_t>(d + e + 28);
      ++entries;
      maxLevel = std::max(maxLevel, level);
      if (count == -1) {
        pages.push_back({offset, uint64_t(uint32_t(byteSize))});
      } else if (count < -1 || byteSize < 0) {
        warn(Error::atByte(e) + ": COPC hierarchy entry with " + std::to_string(count) +
             " points and " + std::to_string(byteSize) + " bytes; the hierarchy is ignored");
        return {};
      } else if (count > 0) {
        chunks.push_back({offset, uint64_t(byteSize), 0, uint32_t(count)});
      }
    }
  }
  copc["hierarchy_entries"] = entries;
  copc["chunks"] = chunks.size();
  copc["max_level"] = maxLevel;
  header_.details["copc"] = std::move(copc);
  return chunks;
}

// LAZ with a chunk table, for readDeferred and readSampled: the next whole chunks up to maxPoints
// (at least one). Planning passes (`step` > 1) sample whole chunks, a coarser step than for LAS
// keeping their decoding cost small as long as enough chunks remain to stand for the rest.
// Returns how many chunks each taken one stands for; 0 at the end.
size_t LasReader::takeChunks(size_t maxPoints, size_t step, std::vector<size_t>& which) {
  const auto& chunks = laz_->chunks();
  const size_t end = chunkStop(), first = restricted_ ? size_t(first_) : 0, count = end - first;
  if (nextChunk_ >= end || maxPoints == 0) return 0;
  size_t chunkStep = 1;
  if (step > 1) chunkStep = count >= 8 * step ? 4 * step : count >= 2 * step ? step : 1;
  uint64_t points = 0;
  size_t c = nextChunk_;
  while (c < end && (which.empty() || points + chunks[c].points <= maxPoints)) {
    which.push_back(c);
    points += chunks[c].points;
    c += chunkStep;
  }
  // An even number of chunks while more follow: chunks decode two at a time on a thread.
  if (which.size() > 2 && which.size() % 2 && c < end) {
    c = which.back();
    which.pop_back();
  }
  src_->releaseBefore(chunks[nextChunk_].offset);
  nextChunk_ = std::min(c, end);
  return chunkStep;
}

// Decodes chunks on the calling thread (a worker of the caller's) into the batch's fields.
void LasReader::decodeChunks(const std::vector<size_t>& which, PointBatch& b) const {
  thread_local laz::RecordBuffer records;
  const size_t n = static_cast<size_t>(laz_->decode(which, records, false));
  const size_t stride = header_.layout.stride();
  b.xyz.resize(3 * n);
  b.attrs.resize(n * stride);
  kDecoders[pointFormat_](records.data(), n, recordLength_, scale_, offset_, b.xyz.data(),
                          b.attrs.data(), stride, extraBytes_);
}

// LAZ read(): chunks are decoded in groups, in parallel, into cache_; batches are cut from it.
size_t LasReader::readLaz(PointBatch& batch, size_t maxPoints, bool decodeFields) {
  batch.clear();
  if (maxPoints == 0) return 0;
  while (cacheAt_ >= cacheCount_) {
    const auto& chunks = laz_->chunks();
    const size_t end = laz_->hasChunkTable() ? chunkStop() : chunks.size();
    if (nextChunk_ >= end) {
      cache_.release();  // up to 64 MiB per reader, and a conversion may have many inputs
      return 0;
    }
    // Enough chunks to keep every core busy, within 64 MiB of records.
    const uint64_t threads = static_cast<uint64_t>(tbb::this_task_arena::max_concurrency());
    const uint64_t cap = std::max<uint64_t>((64u << 20) / recordLength_, 1);
    const uint64_t target =
        std::max<uint64_t>(decodeFields ? maxPoints : 0,
                           std::min<uint64_t>(cap, 4 * threads * chunks[nextChunk_].points));
    std::vector<size_t> which;
    uint64_t points = 0;
    size_t c = nextChunk_;
    if (!laz_->hasChunkTable()) {
      which.push_back(c++);
    } else {
      while (c < end && (which.empty() || points + chunks[c].points <= target)) {
        which.push_back(c);
        points += chunks[c].points;
        ++c;
      }
    }
    nextChunk_ = std::min(c, end);
    cacheCount_ = static_cast<size_t>(laz_->decode(which, cache_));
    cacheAt_ = 0;
    src_->releaseBefore(nextChunk_ < laz_->chunks().size() ? laz_->chunks()[nextChunk_].offset
                                                           : src_->size());
  }
  if (!decodeFields) return 1;
  const size_t n = std::min(maxPoints, cacheCount_ - cacheAt_);
  const size_t stride = header_.layout.stride();
  batch.xyz.resize(3 * n);
  batch.attrs.resize(n * stride);
  kDecoders[pointFormat_](cache_.data() + cacheAt_ * recordLength_, n, recordLength_, scale_,
                          offset_, batch.xyz.data(), batch.attrs.data(), stride, extraBytes_);
  cacheAt_ += n;
  next_ += n;
  return 1;
}

}  // namespace

std::unique_ptr<PointReader> openLas(std::shared_ptr<ByteSource> src, const ReadOptions& options) {
  return std::make_unique<LasReader>(std::move(src), options);
}

size_t readLasRecords(std::shared_ptr<ByteSource> src, const ReadOptions& options,
                      const std::function<void(const uint8_t*, size_t, size_t)>& sink,
                      SourceHeader* header, std::vector<std::string>* warnings) {
  LasReader r(std::move(src), options);
  r.forEachRecords([&](const uint8_t* p, size_t n) { sink(p, n, r.recordLength()); });
  if (header) *header = r.header();
  if (warnings) *warnings = r.warnings();
  return r.recordLength();
}

}  // namespace nestlight
