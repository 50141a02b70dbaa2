// LAS writer: LAS 1.2 with point formats 0-3, or LAS 1.4 with formats 6-8 when the points carry
// what only those formats hold (scanner channel, 16-bit scan angle, NIR, more than 7 returns,
// classes above 31, the overlap flag). Layout attributes that the chosen format has no field for
// go into extra bytes described by an Extra Bytes VLR (ASPRS LAS 1.4 R15, section 2.5.8), so
// that reading the file back gives every attribute again.
//
// Points are written to `path`.tmp and renamed at close(), after the header's counts and bounds
// are known: a killed export leaves no file that looks complete (DESIGN.md). LAZ output is
// compressed while the points arrive (laz::ChunkWriter), so an export needs the disk space of
// its .laz file, never that of the uncompressed LAS.
#include <tbb/parallel_for.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "laz/points.h"
#include "laz/writer.h"
#include "nestlight/converters/point_writer.h"
#include "nestlight/octree/error.h"
#include "readers/las_format.h"

namespace nestlight {
namespace {

using las::load;
using las::store;

// Record fields the writer fills from attributes of the same name and type.
enum Field : int {
  kFIntensity,
  kFReturnNumber,
  kFNumberOfReturns,
  kFScanDirection,
  kFEdge,
  kFClassification,
  kFClassificationFlags,
  kFScannerChannel,
  kFScanAngleRank,
  kFScanAngle,
  kFUserData,
  kFPointSourceId,
  kFGpsTime,
  kFRgb,
  kFNir,
  kFieldCount
};
struct KnownField {
  const char* name;
  ScalarType type;
  uint32_t components;
};
constexpr KnownField kKnown[kFieldCount] = {{las::kIntensity, ScalarType::U16, 1},
                                            {las::kReturnNumber, ScalarType::U8, 1},
                                            {las::kNumberOfReturns, ScalarType::U8, 1},
                                            {las::kScanDirection, ScalarType::U8, 1},
                                            {las::kEdgeOfFlightLine, ScalarType::U8, 1},
                                            {las::kClassification, ScalarType::U8, 1},
                                            {las::kClassificationFlags, ScalarType::U8, 1},
                                            {las::kScannerChannel, ScalarType::U8, 1},
                                            {las::kScanAngleRank, ScalarType::I8, 1},
                                            {las::kScanAngle, ScalarType::I16, 1},
                                            {las::kUserData, ScalarType::U8, 1},
                                            {las::kPointSourceId, ScalarType::U16, 1},
                                            {las::kGpsTime, ScalarType::F64, 1},
                                            {las::kRgb, ScalarType::U16, 3},
                                            {las::kNir, ScalarType::U16, 1}};

bool formatHas(int pf, int f) {
  switch (f) {
    case kFScannerChannel:
    case kFScanAngle:
      return !las::isLegacyFormat(pf);
    case kFScanAngleRank:
      return las::isLegacyFormat(pf);
    case kFGpsTime:
      return las::hasGps(pf);
    case kFRgb:
      return las::hasRgb(pf);
    case kFNir:
      return las::hasNir(pf);
    default:
      return true;
  }
}

int knownField(const Attribute& a) {
  for (int f = 0; f < kFieldCount; ++f)
    if (a.name == kKnown[f].name && a.type == kKnown[f].type &&
        a.components == kKnown[f].components)
      return f;
  return -1;
}

// How one layout maps into records of one point format.
struct Plan {
  int pointFormat = 0;
  int minor = 2;
  size_t recordLength = 0;
  size_t headerSize = 0;
  std::array<int, kFieldCount> src;  // byte offset in the batch's attributes; -1 when absent
  struct Extra {
    size_t src, size, dst;
  };
  std::vector<Extra> extras;
  std::vector<size_t> extraAttributes;  // layout indices, in record order
};

Plan makePlan(const PointLayout& layout, int pf, int minor) {
  Plan p;
  p.pointFormat = pf;
  p.minor = minor;
  p.headerSize = minor >= 4 ? las::kHeaderSize14 : las::kHeaderSize12;
  p.src.fill(-1);
  size_t dst = las::kBaseRecordSize[pf];
  for (size_t i = 0; i < layout.size(); ++i) {
    const int f = knownField(layout[i]);
    if (f >= 0 && formatHas(pf, f) && p.src[f] < 0) {
      p.src[f] = static_cast<int>(layout.offset(i));
    } else {
      p.extras.push_back({layout.offset(i), layout[i].byteSize(), dst});
      p.extraAttributes.push_back(i);
      dst += layout[i].byteSize();
    }
  }
  p.recordLength = dst;
  return p;
}

template <typename T>
T field(const Plan& p, int f, const uint8_t* attrs, T fallback = T()) {
  return p.src[f] < 0 ? fallback : load<T>(attrs + p.src[f]);
}

// The values a legacy format (0-5) cannot hold: the file must become LAS 1.4 format 6+.
bool fitsLegacy(const Plan& p, const uint8_t* a) {
  return field<uint8_t>(p, kFReturnNumber, a) <= 7 &&
         field<uint8_t>(p, kFNumberOfReturns, a) <= 7 &&
         field<uint8_t>(p, kFClassification, a) <= 31 &&
         field<uint8_t>(p, kFClassificationFlags, a) <= 7;
}

// Encodes one point. Bit fields too narrow for the value in every format are errors: the writer
// does not silently cut values.
void encodeRecord(const Plan& p, const int32_t q[3], const uint8_t* a, uint8_t* r,
                  const std::string& path, uint64_t index) {
  auto bits = [&](int f, unsigned max, uint8_t fallback = 0) {
    const uint8_t v = field<uint8_t>(p, f, a, fallback);
    if (v > max)
      throw Error(path, "point " + std::to_string(index),
                  std::string(kKnown[f].name) + " " + std::to_string(v) +
                      " does not fit the LAS point record (at most " + std::to_string(max) + ")");
    return v;
  };
  std::memset(r, 0, p.recordLength);
  std::memcpy(r, q, 12);
  store<uint16_t>(r + 12, field<uint16_t>(p, kFIntensity, a));
  // Return numbers start at 1; a source without them has single returns. Formats 0-5 have three
  // bits for each (write() moved values above 7 to format 6+), formats 6-10 four.
  const unsigned maxReturn = las::isLegacyFormat(p.pointFormat) ? 7 : 15;
  const uint8_t ret = bits(kFReturnNumber, maxReturn, 1);
  const uint8_t nret = bits(kFNumberOfReturns, maxReturn, std::max<uint8_t>(ret, 1));
  size_t o;
  if (las::isLegacyFormat(p.pointFormat)) {
    r[14] = static_cast<uint8_t>(ret | nret << 3 | bits(kFScanDirection, 1) << 6 |
                                 bits(kFEdge, 1) << 7);
    r[15] = static_cast<uint8_t>(bits(kFClassification, 31) | bits(kFClassificationFlags, 7) << 5);
    r[16] = static_cast<uint8_t>(field<int8_t>(p, kFScanAngleRank, a));
    r[17] = field<uint8_t>(p, kFUserData, a);
    store<uint16_t>(r + 18, field<uint16_t>(p, kFPointSourceId, a));
    o = 20;
  } else {
    r[14] = static_cast<uint8_t>(ret | nret << 4);
    r[15] = static_cast<uint8_t>(bits(kFClassificationFlags, 15) | bits(kFScannerChannel, 3) << 4 |
                                 bits(kFScanDirection, 1) << 6 | bits(kFEdge, 1) << 7);
    r[16] = field<uint8_t>(p, kFClassification, a);
    r[17] = field<uint8_t>(p, kFUserData, a);
    store<int16_t>(r + 18, field<int16_t>(p, kFScanAngle, a));
    store<uint16_t>(r + 20, field<uint16_t>(p, kFPointSourceId, a));
    o = 22;
  }
  if (las::hasGps(p.pointFormat)) {
    if (p.src[kFGpsTime] >= 0) std::memcpy(r + o, a + p.src[kFGpsTime], 8);
    o += 8;
  }
  if (las::hasRgb(p.pointFormat)) {
    if (p.src[kFRgb] >= 0) std::memcpy(r + o, a + p.src[kFRgb], 6);
    o += 6;
  }
  if (las::hasNir(p.pointFormat) && p.src[kFNir] >= 0) std::memcpy(r + o, a + p.src[kFNir], 2);
  for (const auto& e : p.extras) std::memcpy(r + e.dst, a + e.src, e.size);
}

// The inverse of encodeRecord for the fields the layout has, used when a file changes format
// part way through.
void decodeRecord(const Plan& p, const uint8_t* r, uint8_t* a) {
  auto put = [&](int f, uint8_t v) {
    if (p.src[f] >= 0) a[p.src[f]] = v;
  };
  auto copy = [&](int f, size_t at, size_t n) {
    if (p.src[f] >= 0) std::memcpy(a + p.src[f], r + at, n);
  };
  copy(kFIntensity, 12, 2);
  size_t o;
  if (las::isLegacyFormat(p.pointFormat)) {
    put(kFReturnNumber, r[14] & 7);
    put(kFNumberOfReturns, (r[14] >> 3) & 7);
    put(kFScanDirection, (r[14] >> 6) & 1);
    put(kFEdge, r[14] >> 7);
    put(kFClassification, r[15] & 31);
    put(kFClassificationFlags, r[15] >> 5);
    copy(kFScanAngleRank, 16, 1);
    copy(kFUserData, 17, 1);
    copy(kFPointSourceId, 18, 2);
    o = 20;
  } else {
    put(kFReturnNumber, r[14] & 15);
    put(kFNumberOfReturns, r[14] >> 4);
    put(kFClassificationFlags, r[15] & 15);
    put(kFScannerChannel, (r[15] >> 4) & 3);
    put(kFScanDirection, (r[15] >> 6) & 1);
    put(kFEdge, r[15] >> 7);
    copy(kFClassification, 16, 1);
    copy(kFUserData, 17, 1);
    copy(kFScanAngle, 18, 2);
    copy(kFPointSourceId, 20, 2);
    o = 22;
  }
  if (las::hasGps(p.pointFormat)) copy(kFGpsTime, o, 8), o += 8;
  if (las::hasRgb(p.pointFormat)) copy(kFRgb, o, 6), o += 6;
  if (las::hasNir(p.pointFormat)) copy(kFNir, o, 2);
  for (const auto& e : p.extras) std::memcpy(a + e.src, r + e.dst, e.size);
}

void putString(uint8_t* dst, size_t n, const std::string& s) {
  std::memcpy(dst, s.data(), std::min(n, s.size()));
}

class LasWriter final : public PointWriter {
 public:
  LasWriter(std::string path, const SourceHeader& header, bool compress)
      : path_(std::move(path)), tmp_(path_ + ".tmp"), layout_(header.layout), compress_(compress) {
    for (int a = 0; a < 3; ++a) {
      scale_[a] = header.scale ? (*header.scale)[a] : 0.001;
      if (!(std::isfinite(scale_[a]) && scale_[a] > 0))
        throw Error(path_, "",
                    "LAS scale factor " + std::to_string(scale_[a]) + " is not positive");
    }
    if (header.offset) {
      offset_ = *header.offset;
      haveOffset_ = true;
    }
    if (header.details.is_object()) {
      const auto& d = header.details;
      if (d.contains("global_encoding") && d["global_encoding"].is_number_unsigned())
        gpsStandard_ = (d["global_encoding"].get<uint64_t>() & las::kEncodingGpsStandard) != 0;
      if ((header.format == "las" || header.format == "laz") && d.contains("file_source_id") &&
          d["file_source_id"].is_number_unsigned())
        fileSourceId_ = static_cast<uint16_t>(d["file_source_id"].get<uint64_t>());
    }
    if (header.crs.is_object()) {
      if (header.crs.contains("wkt") && header.crs["wkt"].is_string())
        wkt_ = header.crs["wkt"].get<std::string>();
      if (header.crs.contains("geotiff")) geotiff_ = header.crs["geotiff"];
    }

    const bool needs14 = hasKnown(kFScannerChannel) || hasKnown(kFScanAngle) || hasKnown(kFNir);
    plan_ = makePlan(layout_, needs14 ? modernFormat() : legacyFormat(), needs14 ? 4 : 2);

    file_ = std::fopen(tmp_.c_str(), "w+b");
    if (!file_) throw Error(tmp_, "", std::string("cannot create: ") + std::strerror(errno));
    try {
      chunks_ = start(file_, tmp_, plan_);
    } catch (...) {
      discard();
      throw;
    }
  }

  ~LasWriter() override {
    if (file_) discard();
  }

  void write(const PointBatch& batch) override {
    NL_CHECK_MSG(file_, "write() after close()");
    const size_t n = batch.size();
    const size_t stride = layout_.stride();
    NL_CHECK(batch.attrs.size() == n * stride);
    if (n == 0) return;
    if (!haveOffset_) {
      for (int a = 0; a < 3; ++a) offset_[a] = std::floor(batch.xyz[a]);
      haveOffset_ = true;
    }
    if (las::isLegacyFormat(plan_.pointFormat)) {
      for (size_t i = 0; i < n; ++i)
        if (!fitsLegacy(plan_, batch.attrs.data() + i * stride)) {
          rewrite(makePlan(layout_, modernFormat(), 4));
          break;
        }
    }
    buffer_.resize(n * plan_.recordLength);
    // Records are independent: large batches are encoded in blocks on every core (an export's
    // writer is otherwise the one serial stage), each block with its own bounds and return
    // counts, merged after. A failure reports the first failing point, as a serial loop would.
    constexpr size_t kBlock = 8192;
    const size_t blocks = (n + kBlock - 1) / kBlock;
    struct Stats {
      std::array<int64_t, 3> qmin{INT64_MAX, INT64_MAX, INT64_MAX},
          qmax{INT64_MIN, INT64_MIN, INT64_MIN};
      std::array<uint64_t, 15> byReturn{};
      std::exception_ptr failure;
    };
    std::vector<Stats> stats(blocks);
    auto encodeBlock = [&](size_t b) {
      Stats& st = stats[b];
      try {
        for (size_t i = b * kBlock, end = std::min(n, (b + 1) * kBlock); i < end; ++i) {
          int32_t q[3];
          for (int a = 0; a < 3; ++a) {
            const double v = batch.xyz[3 * i + a];
            const double s = std::nearbyint((v - offset_[a]) / scale_[a]);
            if (!(s >= std::numeric_limits<int32_t>::min() &&
                  s <= std::numeric_limits<int32_t>::max()))
              throw Error(path_, "point " + std::to_string(count_ + i),
                          std::string(1, "xyz"[a]) + " = " + std::to_string(v) +
                              " cannot be stored in LAS with scale " + std::to_string(scale_[a]) +
                              " and offset " + std::to_string(offset_[a]) +
                              " (not finite, or outside the 32-bit integer range)");
            q[a] = static_cast<int32_t>(s);
            st.qmin[a] = std::min<int64_t>(st.qmin[a], q[a]);
            st.qmax[a] = std::max<int64_t>(st.qmax[a], q[a]);
          }
          const uint8_t* attrs = batch.attrs.data() + i * stride;
          encodeRecord(plan_, q, attrs, buffer_.data() + i * plan_.recordLength, path_, count_ + i);
          const uint8_t ret = field<uint8_t>(plan_, kFReturnNumber, attrs, 1);
          if (ret >= 1 && ret <= 15) ++st.byReturn[ret - 1];
        }
      } catch (...) {
        st.failure = std::current_exception();
      }
    };
    if (blocks > 1)
      tbb::parallel_for(size_t(0), blocks, encodeBlock);
    else
      encodeBlock(0);
    for (const Stats& st : stats) {
      if (st.failure) std::rethrow_exception(st.failure);
      for (int a = 0; a < 3; ++a)
        qmin_[a] = std::min(qmin_[a], st.qmin[a]), qmax_[a] = std::max(qmax_[a], st.qmax[a]);
      for (int r = 0; r < 15; ++r) byReturn_[r] += st.byReturn[r];
    }
    if (chunks_)
      chunks_->add(buffer_.data(), n);
    else
      writeBytes(file_, tmp_, buffer_.data(), buffer_.size());
    count_ += n;
  }

  void close() override {
    if (!file_) return;
    try {
      if (plan_.minor < 4 && count_ > std::numeric_limits<uint32_t>::max())
        rewrite(makePlan(layout_, plan_.pointFormat, 4));
      if (chunks_) {
        chunks_->finish();
        chunks_.reset();
      }
      const std::vector<uint8_t> h = headerBytes(plan_);
      if (::fseeko(file_, 0, SEEK_SET) != 0) ioError(tmp_, "seek");
      writeBytes(file_, tmp_, h.data(), h.size());
      std::FILE* f = file_;
      file_ = nullptr;
      if (std::fclose(f) != 0) ioError(tmp_, "close");
      std::error_code ec;
      std::filesystem::rename(tmp_, path_, ec);
      if (ec) throw Error(path_, "", "cannot rename " + tmp_ + ": " + ec.message());
    } catch (...) {
      discard();
      throw;
    }
  }

 private:
  bool hasKnown(int f) const {
    for (const auto& a : layout_.attributes())
      if (knownField(a) == f) return true;
    return false;
  }
  int legacyFormat() const {
    const bool gps = hasKnown(kFGpsTime), rgb = hasKnown(kFRgb);
    return gps ? (rgb ? 3 : 1) : (rgb ? 2 : 0);
  }
  int modernFormat() const { return hasKnown(kFNir) ? 8 : hasKnown(kFRgb) ? 7 : 6; }
  [[noreturn]] static void ioError(const std::string& file, const char* what) {
    throw Error(file, "", std::string("cannot ") + what + ": " + std::strerror(errno));
  }
  static void writeBytes(std::FILE* f, const std::string& name, const void* p, size_t n) {
    if (n && std::fwrite(p, 1, n, f) != n) ioError(name, "write");
  }

  void discard() {
    chunks_.reset();
    if (file_) std::fclose(file_);
    file_ = nullptr;
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
    std::filesystem::remove(tmp_ + "2", ec);
  }

  std::vector<uint8_t> vlrBytes(const Plan& p, uint32_t* count) const {
    std::vector<uint8_t> out;
    *count = 0;
    auto add = [&](const char* user, uint16_t id, const char* description, const uint8_t* data,
                   size_t n) {
      if (n > std::numeric_limits<uint16_t>::max())
        throw Error(path_, "",
                    std::string("VLR '") + description + "' needs " + std::to_string(n) +
                        " bytes; LAS allows 65535");
      const size_t at = out.size();
      out.resize(at + las::kVlrHeaderSize + n, 0);
      putString(&out[at + 2], 16, user);
      store<uint16_t>(&out[at + 18], id);
      store<uint16_t>(&out[at + 20], static_cast<uint16_t>(n));
      putString(&out[at + 22], 32, description);
      if (n) std::memcpy(&out[at + las::kVlrHeaderSize], data, n);
      ++*count;
    };

    if (!p.extras.empty()) {
      std::vector<uint8_t> desc;
      auto describe = [&](const std::string& name, int type, uint8_t options,
                          const std::string& description) {
        const size_t at = desc.size();
        desc.resize(at + las::kExtraBytesDescriptorSize, 0);
        desc[at + 2] = static_cast<uint8_t>(type);
        desc[at + 3] = options;
        putString(&desc[at + 4], 32, name);  // names longer than 32 characters are cut
        putString(&desc[at + 160], 32, description);
      };
      for (size_t i : p.extraAttributes) {
        const Attribute& a = layout_[i];
        const int base = las::extraBytesType(a.type);
        if (a.components <= 3) {
          // 2 and 3 components use the array types 11-30: deprecated in 1.4 R13 but read by
          // PDAL and LAStools, and they keep "normal" one attribute.
          describe(a.name, base + 10 * static_cast<int>(a.components - 1), 0, a.description);
        } else if (a.type == ScalarType::U8) {
          // Bytes without a type: type 0, `options` holds the count (at most 255 per descriptor).
          const uint32_t chunks = (a.components + 254) / 255;
          for (uint32_t c = 0; c < chunks; ++c)
            describe(chunks == 1 ? a.name : a.name + "[" + std::to_string(c) + "]", 0,
                     static_cast<uint8_t>(std::min<uint32_t>(255, a.components - 255 * c)),
                     a.description);
        } else {
          for (uint32_t c = 0; c < a.components; ++c)
            describe(a.name + "[" + std::to_string(c) + "]", base, 0, a.description);
        }
      }
      add("LASF_Spec", las::kRecordExtraBytes, "Extra Bytes", desc.data(), desc.size());
    }
    if (compress_) {
      // LASzip's VLR, which LAZ readers look for by its user and record id.
      const std::vector<uint8_t> v = laz::ChunkWriter::vlrFor(p.pointFormat, p.recordLength, path_);
      out.insert(out.end(), v.begin(), v.end());
      ++*count;
    }
    if (!wkt_.empty()) {
      // The WKT is NUL-terminated (spec 2.5.1).
      add("LASF_Projection", las::kRecordWkt, "OGC WKT coordinate system",
          reinterpret_cast<const uint8_t*>(wkt_.c_str()), wkt_.size() + 1);
    }
    if (geotiff_.is_object() && geotiff_.contains("keys") && geotiff_["keys"].is_array() &&
        (wkt_.empty() || p.minor < 4)) {
      // GeoTIFF keys as read: carried, not interpreted. LAS 1.4 formats 6+ take the WKT alone.
      std::vector<uint8_t> keys;
      bool ok = true;
      for (const auto& k : geotiff_["keys"]) {
        ok &= k.is_number_unsigned() && k.get<uint64_t>() <= 0xFFFF;
        if (!ok) break;
        keys.resize(keys.size() + 2);
        store<uint16_t>(&keys[keys.size() - 2], static_cast<uint16_t>(k.get<uint64_t>()));
      }
      if (ok && !keys.empty()) {
        add("LASF_Projection", las::kRecordGeoKeys, "GeoTIFF GeoKeyDirectoryTag", keys.data(),
            keys.size());
        if (geotiff_.contains("doubles") && geotiff_["doubles"].is_array()) {
          std::vector<uint8_t> v;
          for (const auto& x : geotiff_["doubles"]) {
            v.resize(v.size() + 8);
            store<double>(&v[v.size() - 8], x.is_number() ? x.get<double>() : 0.0);
          }
          add("LASF_Projection", las::kRecordGeoDoubles, "GeoTIFF GeoDoubleParamsTag", v.data(),
              v.size());
        }
        if (geotiff_.contains("ascii") && geotiff_["ascii"].is_string()) {
          const std::string& s = geotiff_["ascii"].get_ref<const std::string&>();
          add("LASF_Projection", las::kRecordGeoAscii, "GeoTIFF GeoAsciiParamsTag",
              reinterpret_cast<const uint8_t*>(s.c_str()), s.size() + 1);
        }
      }
    }
    return out;
  }

  std::vector<uint8_t> headerBytes(const Plan& p) const {
    uint32_t vlrCount = 0;
    const std::vector<uint8_t> vlrs = vlrBytes(p, &vlrCount);
    std::vector<uint8_t> h(p.headerSize, 0);
    std::memcpy(h.data(), "LASF", 4);
    store<uint16_t>(&h[4], fileSourceId_);
    uint16_t encoding = gpsStandard_ ? las::kEncodingGpsStandard : 0;
    if (p.minor >= 4 && !wkt_.empty()) encoding |= las::kEncodingWkt;
    store<uint16_t>(&h[6], encoding);
    h[24] = 1;
    h[25] = static_cast<uint8_t>(p.minor);
    putString(&h[26], 32, "Nestlight");
    putString(&h[58], 32, "nestlight export");
    std::time_t now = std::time(nullptr);
    std::tm tm{};
    ::gmtime_r(&now, &tm);
    store<uint16_t>(&h[90], static_cast<uint16_t>(tm.tm_yday + 1));
    store<uint16_t>(&h[92], static_cast<uint16_t>(tm.tm_year + 1900));
    store<uint16_t>(&h[94], static_cast<uint16_t>(p.headerSize));
    store<uint32_t>(&h[96], static_cast<uint32_t>(p.headerSize + vlrs.size()));
    store<uint32_t>(&h[100], vlrCount);
    h[104] = static_cast<uint8_t>(p.pointFormat | (compress_ ? 0x80 : 0));
    store<uint16_t>(&h[105], static_cast<uint16_t>(p.recordLength));
    // LAS 1.4 keeps the 32-bit counts zero for formats 6+ and for counts they cannot hold.
    const bool legacyCounts =
        las::isLegacyFormat(p.pointFormat) && count_ <= std::numeric_limits<uint32_t>::max();
    if (legacyCounts) {
      store<uint32_t>(&h[107], static_cast<uint32_t>(count_));
      for (int r = 0; r < 5; ++r)
        store<uint32_t>(&h[111 + 4 * r], static_cast<uint32_t>(byReturn_[r]));
    }
    for (int a = 0; a < 3; ++a) {
      store<double>(&h[131 + 8 * a], scale_[a]);
      store<double>(&h[155 + 8 * a], offset_[a]);
      const bool any = count_ > 0;
      store<double>(&h[179 + 16 * a], any ? qmax_[a] * scale_[a] + offset_[a] : 0.0);
      store<double>(&h[187 + 16 * a], any ? qmin_[a] * scale_[a] + offset_[a] : 0.0);
    }
    if (p.minor >= 4) {
      store<uint64_t>(&h[247], count_);
      for (int r = 0; r < 15; ++r) store<uint64_t>(&h[255 + 8 * r], byReturn_[r]);
    }
    h.insert(h.end(), vlrs.begin(), vlrs.end());
    return h;
  }

  // Writes the header and VLRs of `p`; records follow, or for LAZ the returned chunk writer's
  // point data.
  std::unique_ptr<laz::ChunkWriter> start(std::FILE* f, const std::string& name, const Plan& p) {
    if (p.recordLength > std::numeric_limits<uint16_t>::max())
      throw Error(path_, "",
                  "a LAS point record would need " + std::to_string(p.recordLength) +
                      " bytes; LAS allows 65535");
    const std::vector<uint8_t> h = headerBytes(p);
    writeBytes(f, name, h.data(), h.size());
    if (!compress_) return nullptr;
    auto chunks = std::make_unique<laz::ChunkWriter>(p.pointFormat, p.recordLength, path_);
    chunks->begin(f, name, h.size());
    return chunks;
  }

  // Re-encodes the records written so far under a new plan (another point format or LAS
  // version). Rare: only when a value turns up that the first choice cannot hold. LAZ output
  // decodes its chunks written so far.
  void rewrite(const Plan& next) {
    const std::string tmp2 = tmp_ + "2";
    std::FILE* out = std::fopen(tmp2.c_str(), "w+b");
    if (!out) ioError(tmp2, "create");
    std::unique_ptr<laz::ChunkWriter> nextChunks;
    try {
      nextChunks = start(out, tmp2, next);
      std::vector<uint8_t> outBuf, attrs(layout_.stride());
      auto reencode = [&](const uint8_t* records, size_t n, uint64_t done) {
        outBuf.resize(n * next.recordLength);
        for (size_t i = 0; i < n; ++i) {
          const uint8_t* r = records + i * plan_.recordLength;
          decodeRecord(plan_, r, attrs.data());
          int32_t q[3];
          std::memcpy(q, r, 12);
          encodeRecord(next, q, attrs.data(), outBuf.data() + i * next.recordLength, path_,
                       done + i);
        }
        if (nextChunks)
          nextChunks->add(outBuf.data(), n);
        else
          writeBytes(out, tmp2, outBuf.data(), n * next.recordLength);
      };
      const uint64_t firstRecord = headerBytes(plan_).size();
      if (chunks_) {
        chunks_->finish();
        if (std::fflush(file_) != 0) ioError(tmp_, "flush");
        const laz::LaszipInfo info = chunks_->info();
        chunks_.reset();
        auto src = mapFile(tmp_);
        laz::LazPoints points(src, info, firstRecord, src->size(), count_, false,
                              [](const std::string&) {});
        NL_CHECK(points.points() == count_);
        laz::RecordBuffer records;
        uint64_t done = 0;
        for (size_t c = 0; c < points.chunks().size(); ++c) {
          const uint64_t n = points.decode({c}, records);
          reencode(records.data(), size_t(n), done);
          done += n;
        }
        NL_CHECK(done == count_);
      } else {
        if (std::fflush(file_) != 0 ||
            ::fseeko(file_, static_cast<off_t>(firstRecord), SEEK_SET) != 0)
          ioError(tmp_, "seek");
        const size_t chunk = 65536;
        std::vector<uint8_t> in(chunk * plan_.recordLength);
        for (uint64_t done = 0; done < count_;) {
          const size_t n = static_cast<size_t>(std::min<uint64_t>(chunk, count_ - done));
          if (std::fread(in.data(), plan_.recordLength, n, file_) != n) ioError(tmp_, "read back");
          reencode(in.data(), n, done);
          done += n;
        }
      }
    } catch (...) {
      nextChunks.reset();
      std::fclose(out);
      throw;
    }
    std::fclose(file_);
    file_ = out;
    chunks_ = std::move(nextChunks);
    std::error_code ec;
    std::filesystem::rename(tmp2, tmp_, ec);
    if (ec) throw Error(tmp_, "", "cannot rename " + tmp2 + ": " + ec.message());
    plan_ = next;
  }

  std::string path_, tmp_;
  PointLayout layout_;
  bool compress_ = false;
  Plan plan_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<laz::ChunkWriter> chunks_;  // LAZ: the compressed point data being written
  Vec3d scale_, offset_;
  bool haveOffset_ = false;
  bool gpsStandard_ = false;
  uint16_t fileSourceId_ = 0;
  std::string wkt_;
  nlohmann::json geotiff_;
  uint64_t count_ = 0;
  std::array<uint64_t, 15> byReturn_{};
  std::array<int64_t, 3> qmin_{INT64_MAX, INT64_MAX, INT64_MAX};
  std::array<int64_t, 3> qmax_{INT64_MIN, INT64_MIN, INT64_MIN};
  std::vector<uint8_t> buffer_;
};

}  // namespace

std::unique_ptr<PointWriter> createLasWriter(const std::string& path, const SourceHeader& header) {
  return std::make_unique<LasWriter>(path, header, false);
}

std::unique_ptr<PointWriter> createLazWriter(const std::string& path, const SourceHeader& header) {
  return std::make_unique<LasWriter>(path, header, true);
}

}  // namespace nestlight
