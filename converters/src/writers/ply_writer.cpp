// PLY writer (`nestlight export`, `nestlight generate`): one "vertex" element in the layout that
// ply_reader.cpp maps back, so that reading a written file gives the points that were written.
//
// Positions are doubles: a scan in national-grid coordinates loses its millimetres in float.
// The file is written under a temporary name and renamed by close(), so that an interrupted
// export leaves nothing that looks complete (DESIGN.md).
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "nestlight/converters/point_writer.h"
#include "nestlight/octree/error.h"

namespace nestlight {
namespace {

constexpr bool kNativeLittle = std::endian::native == std::endian::little;

// The vertex count is known only at close(): the header keeps a fixed-width field for it, padded
// with trailing spaces, which PLY readers split away as whitespace.
constexpr size_t kCountWidth = 20;

const char* plyTypeName(ScalarType t) {
  switch (t) {
    case ScalarType::U8:
      return "uchar";
    case ScalarType::I8:
      return "char";
    case ScalarType::U16:
      return "ushort";
    case ScalarType::I16:
      return "short";
    case ScalarType::U32:
      return "uint";
    case ScalarType::I32:
      return "int";
    // PLY has no 64-bit integers; these spellings are understood by ply_reader.cpp only.
    case ScalarType::U64:
      return "uint64";
    case ScalarType::I64:
      return "int64";
    case ScalarType::F32:
      return "float";
    case ScalarType::F64:
      return "double";
  }
  return "?";
}

// A header line must not be split by a name with spaces in it.
std::string propertyName(const std::string& name) {
  std::string n = name.empty() ? "attribute" : name;
  for (char& c : n)
    if (c <= 0x20 || c >= 0x7f) c = '_';
  return n;
}

class PlyWriter final : public PointWriter {
 public:
  PlyWriter(std::string path, const SourceHeader& header, bool ascii)
      : path_(std::move(path)), tmp_(path_ + ".tmp"), layout_(header.layout), ascii_(ascii) {
    planFields(header);
    file_ = std::fopen(tmp_.c_str(), "wb");
    if (!file_) throw Error(tmp_, "", std::string("cannot create: ") + std::strerror(errno));
    std::string h = "ply\nformat ";
    h += ascii_ ? "ascii" : "binary_little_endian";
    h += " 1.0\ncomment written by nestlight\n";
    if (header.crs.is_object()) {
      if (auto w = header.crs.find("wkt"); w != header.crs.end() && w->is_string()) {
        std::string wkt = w->get<std::string>();
        for (char& c : wkt)
          if (c == '\n' || c == '\r') c = ' ';
        h += "comment crs: " + wkt + "\n";
      } else if (auto e = header.crs.find("epsg"); e != header.crs.end() && e->is_number()) {
        h += "comment crs: EPSG:" + std::to_string(e->get<int64_t>()) + "\n";
      }
    }
    h += "element vertex ";
    countOffset_ = h.size();
    h += std::string(kCountWidth, ' ') + "\n";
    h += properties_;
    h += "end_header\n";
    put(h.data(), h.size());
  }

  ~PlyWriter() override {
    if (file_) {
      std::fclose(file_);
      std::remove(tmp_.c_str());
    }
  }

  void write(const PointBatch& batch) override {
    NL_CHECK_MSG(file_, "write after close");
    const size_t n = batch.size();
    const size_t stride = layout_.stride();
    NL_CHECK_MSG(batch.attrs.size() == n * stride, "the batch does not follow the layout");
    buf_.clear();
    for (size_t i = 0; i < n; ++i) {
      const double* xyz = &batch.xyz[3 * i];
      const uint8_t* a = batch.attrs.data() + i * stride;
      for (int c = 0; c < 3; ++c) value(ScalarType::F64, xyz[c]);
      for (const Field& f : fields_) {
        const uint8_t* p = a + f.offset;
        const size_t size = scalarSize(f.type);
        for (uint32_t c = 0; c < f.components; ++c, p += size) {
          switch (f.kind) {
            case Kind::RgbU8ToU8:
              raw(ScalarType::U8, p);
              break;
            case Kind::RgbU16ToU8: {
              uint16_t v;
              std::memcpy(&v, p, 2);
              value(ScalarType::U8, std::round(v / 257.0));
              break;
            }
            case Kind::Normal:
              value(ScalarType::F32, loadAsDouble(f.type, p));
              break;
            case Kind::Raw:
              raw(f.type, p);
              break;
          }
        }
      }
      if (ascii_) buf_.back() = '\n';
    }
    put(buf_.data(), buf_.size());
    count_ += n;
  }

  void close() override {
    if (!file_) return;
    std::string count = std::to_string(count_);
    count.resize(kCountWidth, ' ');
    bool ok = std::fflush(file_) == 0 && std::fseek(file_, long(countOffset_), SEEK_SET) == 0 &&
              std::fwrite(count.data(), 1, count.size(), file_) == count.size() &&
              std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    const int err = errno;
    ok = std::fclose(file_) == 0 && ok;
    file_ = nullptr;
    if (!ok) {
      std::remove(tmp_.c_str());
      throw Error(tmp_, "", std::string("cannot write: ") + std::strerror(err));
    }
    std::error_code ec;
    std::filesystem::rename(tmp_, path_, ec);
    if (ec) {
      std::remove(tmp_.c_str());
      throw Error(path_, "", "cannot rename " + tmp_ + ": " + ec.message());
    }
  }

 private:
  enum class Kind { RgbU8ToU8, RgbU16ToU8, Normal, Raw };
  struct Field {
    Kind kind;
    ScalarType type;
    uint32_t components;
    size_t offset;
  };

  void planFields(const SourceHeader& header) {
    std::set<std::string> used = {"x", "y", "z"};
    auto unique = [&](std::string n) {
      while (used.count(n)) n += "_";
      used.insert(n);
      return n;
    };
    auto property = [&](ScalarType t, const std::string& name) {
      properties_ += std::string("property ") + plyTypeName(t) + " " + unique(name) + "\n";
    };
    properties_ = "property double x\nproperty double y\nproperty double z\n";
    for (size_t i = 0; i < layout_.size(); ++i) {
      const Attribute& a = layout_[i];
      Field f{Kind::Raw, a.type, a.components, layout_.offset(i)};
      if (a.name == attr::kRgb && a.components == 3 &&
          (a.type == ScalarType::U8 || a.type == ScalarType::U16)) {
        const bool bytes = a.type == ScalarType::U8 || header.rgbBits == 8;
        f.kind = a.type == ScalarType::U8 ? Kind::RgbU8ToU8 : bytes ? Kind::RgbU16ToU8 : Kind::Raw;
        for (const char* c : {"red", "green", "blue"})
          property(bytes ? ScalarType::U8 : ScalarType::U16, c);
      } else if (a.name == attr::kNormal && a.components == 3) {
        f.kind = Kind::Normal;
        for (const char* c : {"nx", "ny", "nz"}) property(ScalarType::F32, c);
      } else if (a.components == 1) {
        property(a.type, propertyName(a.name));
      } else {
        for (uint32_t c = 0; c < a.components; ++c)
          property(a.type, propertyName(a.name) + "_" + std::to_string(c));
      }
      fields_.push_back(f);
    }
  }

  // One component, from its native bytes.
  void raw(ScalarType t, const uint8_t* p) {
    const size_t n = scalarSize(t);
    if (ascii_) return value(t, loadAsDouble(t, p), p);
    if (kNativeLittle) {
      buf_.insert(buf_.end(), p, p + n);
    } else {
      for (size_t b = 0; b < n; ++b) buf_.push_back(p[n - 1 - b]);
    }
  }

  // One component of type `t` holding `v` (`native`, when given, is the exact value: doubles
  // cannot hold every 64-bit integer).
  void value(ScalarType t, double v, const uint8_t* native = nullptr) {
    uint8_t bytes[8];
    if (!native) {
      storeFromDouble(t, v, bytes);
      native = bytes;
    }
    if (!ascii_) return raw(t, native);
    char s[40];
    std::to_chars_result r;
    switch (t) {
      case ScalarType::F32: {
        float f;
        std::memcpy(&f, native, 4);
        r = std::to_chars(s, s + sizeof s, f);
        break;
      }
      case ScalarType::F64: {
        double d;
        std::memcpy(&d, native, 8);
        r = std::to_chars(s, s + sizeof s, d);
        break;
      }
      case ScalarType::U64: {
        uint64_t u;
        std::memcpy(&u, native, 8);
        r = std::to_chars(s, s + sizeof s, u);
        break;
      }
      case ScalarType::I64: {
        int64_t i;
        std::memcpy(&i, native, 8);
        r = std::to_chars(s, s + sizeof s, i);
        break;
      }
      default:
        r = std::to_chars(s, s + sizeof s, int64_t(loadAsDouble(t, native)));
        break;
    }
    buf_.insert(buf_.end(), s, r.ptr);
    buf_.push_back(' ');
  }

  void put(const void* p, size_t n) {
    if (n > 0 && std::fwrite(p, 1, n, file_) != n)
      throw Error(tmp_, "", std::string("cannot write: ") + std::strerror(errno));
  }

  std::string path_, tmp_;
  PointLayout layout_;
  bool ascii_;
  std::FILE* file_ = nullptr;
  std::string properties_;
  std::vector<Field> fields_;
  size_t countOffset_ = 0;
  uint64_t count_ = 0;
  std::vector<uint8_t> buf_;
};

}  // namespace

std::unique_ptr<PointWriter> createPlyWriter(const std::string& path, const SourceHeader& header,
                                             bool ascii) {
  return std::make_unique<PlyWriter>(path, header, ascii);
}

}  // namespace nestlight
