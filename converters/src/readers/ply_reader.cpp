// PLY reader.
//
// PLY is Greg Turk's format (G. Turk, "The PLY Polygon File Format", Stanford, 1994): a text
// header that declares elements ("vertex", "face", ...) with their scalar and list properties,
// then every element's records in header order, as ascii, binary_little_endian or
// binary_big_endian. Points are the "vertex" records. A binary file has no index: the vertices
// are found by walking the records before them, and a record with a list is as long as its count
// says, so faces written before the vertices are read count by count.
//
// Conversions are planned once per file: each vertex property becomes an operation from its
// offset in the record to the batch, adjacent operations of one kind merge (three float normals
// are one 12-byte copy), and the per-point loop runs that short list without allocating. Ascii
// tokens, and the scalars of binary records that hold lists, are first packed into a record of
// the same shape, so that one plan serves every encoding.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>

#include "nestlight/converters/reader.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/ply_header.h"
#include "nestlight/octree/text.h"

namespace nestlight {
namespace {

constexpr bool kNativeLittle = std::endian::native == std::endian::little;

// The header and the line and list helpers are shared with gi's mesh reader (octree/ply_header).
using ply::Encoding;
using ply::encodingName;
using ply::listCount;
using ply::nextDataLine;
using PlyProperty = ply::Property;
using PlyElement = ply::Element;
using PlyHeader = ply::Header;
using text::splitWords;
using text::trim;

// Writers put a CRS into comments in no standard way; these are the spellings seen: "crs: <wkt>",
// "wkt = ...", "srs EPSG:2056", or a bare WKT.
nlohmann::json crsFromComments(const std::vector<std::string>& comments) {
  for (const auto& c : comments) {
    std::string_view s = trim(c);
    std::string lower(s.substr(0, 32));
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char ch) { return char(std::tolower(ch)); });
    std::string_view value;
    for (std::string_view key : {"crs", "srs", "wkt", "spatial_reference", "coordinate_system"}) {
      if (lower.size() > key.size() && lower.compare(0, key.size(), key) == 0 &&
          (lower[key.size()] == ':' || lower[key.size()] == '=' ||
           text::isBlank(lower[key.size()]))) {
        value = s.substr(key.size());
        while (!value.empty() && (value[0] == ':' || value[0] == '=' || text::isBlank(value[0])))
          value.remove_prefix(1);
        break;
      }
    }
    if (value.empty())
      for (std::string_view root : {"PROJCS[", "GEOGCS[", "COMPD_CS[", "GEOCCS[", "PROJCRS[",
                                    "GEOGCRS[", "COMPOUNDCRS[", "GEODCRS["})
        if (auto at = s.find(root); at != std::string_view::npos) {
          value = s.substr(at);
          break;
        }
    value = trim(value);
    if (value.empty()) continue;
    if (value.find('[') != std::string_view::npos) return {{"wkt", std::string(value)}};
    if (value.size() > 5 && (value.substr(0, 5) == "EPSG:" || value.substr(0, 5) == "epsg:")) {
      uint32_t code = 0;
      if (text::parseInteger(value.data() + 5, value.data() + value.size(), code))
        return {{"epsg", code}};
    }
  }
  return nullptr;
}

// One ascii token as `t` in native byte order; false if it is not a number of that type.
bool parseScalar(ScalarType t, const char* b, const char* e, uint8_t* out) {
  switch (t) {
    case ScalarType::F32: {
      float v;
      if (!text::parseFloat(b, e, v)) return false;
      std::memcpy(out, &v, 4);
      return true;
    }
    case ScalarType::F64: {
      double v;
      if (!text::parseDouble(b, e, v)) return false;
      std::memcpy(out, &v, 8);
      return true;
    }
    case ScalarType::U64: {
      uint64_t v;
      if (!text::parseInteger(b, e, v)) return false;
      std::memcpy(out, &v, 8);
      return true;
    }
    default:
      break;
  }
  int64_t v;
  if (!text::parseInteger(b, e, v)) {
    // Some writers print integers as "255.000000".
    double d;
    if (!text::parseDouble(b, e, d) || !(d >= -9.2e18 && d <= 9.2e18) || d != std::trunc(d))
      return false;
    v = static_cast<int64_t>(d);
  }
  auto put = [&]<typename T>(T) {
    if (v < int64_t(std::numeric_limits<T>::lowest()) || v > int64_t(std::numeric_limits<T>::max()))
      return false;
    T x = static_cast<T>(v);
    std::memcpy(out, &x, sizeof x);
    return true;
  };
  switch (t) {
    case ScalarType::U8:
      return put(uint8_t());
    case ScalarType::I8:
      return put(int8_t());
    case ScalarType::U16:
      return put(uint16_t());
    case ScalarType::I16:
      return put(int16_t());
    case ScalarType::U32:
      return put(uint32_t());
    case ScalarType::I32:
      return put(int32_t());
    case ScalarType::I64:
      std::memcpy(out, &v, 8);
      return true;
    default:
      return false;
  }
}

enum class OpKind : uint8_t { Copy, Swap2, Swap4, Swap8, XyzF64, XyzF32, RgbU8, Convert };
enum class Transform : uint8_t { None, UnitToU16 };

struct Op {
  OpKind kind = OpKind::Copy;
  Transform transform = Transform::None;
  ScalarType srcType = ScalarType::U8;  // Convert
  ScalarType dstType = ScalarType::U8;  // Convert
  bool swap = false;                    // Convert: the source is in the other byte order
  bool toXyz = false;                   // Convert: the destination is the position
  uint32_t src = 0;                     // byte offset in the (packed) record
  uint32_t dst = 0;    // byte offset in the point's attributes, or in its 24-byte position
  uint32_t count = 0;  // components (bytes, for Copy)

  uint32_t srcUnit() const {
    switch (kind) {
      case OpKind::Copy:
      case OpKind::RgbU8:
        return 1;
      case OpKind::Swap2:
        return 2;
      case OpKind::Swap4:
      case OpKind::XyzF32:
        return 4;
      case OpKind::Swap8:
      case OpKind::XyzF64:
        return 8;
      case OpKind::Convert:
        return uint32_t(scalarSize(srcType));
    }
    return 0;
  }
  uint32_t dstUnit() const {
    switch (kind) {
      case OpKind::Copy:
        return 1;
      case OpKind::RgbU8:
      case OpKind::Swap2:
        return 2;
      case OpKind::Swap4:
        return 4;
      case OpKind::Swap8:
      case OpKind::XyzF32:
      case OpKind::XyzF64:
        return 8;
      case OpKind::Convert:
        return toXyz ? 8 : uint32_t(scalarSize(dstType));
    }
    return 0;
  }
  bool extends(const Op& o) const {
    return o.kind == kind && o.transform == transform && o.srcType == srcType &&
           o.dstType == dstType && o.swap == swap && o.toXyz == toXyz &&
           o.src == src + count * srcUnit() && o.dst == dst + count * dstUnit();
  }
};

template <size_t N>
inline void swapCopy(const uint8_t* s, uint8_t* d, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i, s += N, d += N)
    for (size_t b = 0; b < N; ++b) d[b] = s[N - 1 - b];
}

void convert(const Op& op, const uint8_t* s, double* xyz, uint8_t* attrs, uint64_t& clamped) {
  const size_t su = scalarSize(op.srcType), du = scalarSize(op.dstType);
  for (uint32_t i = 0; i < op.count; ++i, s += su) {
    uint8_t tmp[8];
    const uint8_t* p = s;
    if (op.swap) {
      for (size_t b = 0; b < su; ++b) tmp[b] = s[su - 1 - b];
      p = tmp;
    }
    double v = loadAsDouble(op.srcType, p);
    if (op.transform == Transform::UnitToU16) {
      if (!(v >= 0 && v <= 1)) {
        ++clamped;
        v = v > 1 ? 1 : 0;
      }
      v *= 65535;
    }
    if (op.toXyz)
      xyz[op.dst / 8 + i] = v;
    else
      storeFromDouble(op.dstType, v, attrs + op.dst + i * du);
  }
}

inline void applyOps(const Op* ops, size_t nops, const uint8_t* rec, double* xyz, uint8_t* attrs,
                     uint64_t& clamped) {
  auto* xyzBytes = reinterpret_cast<uint8_t*>(xyz);
  for (size_t k = 0; k < nops; ++k) {
    const Op& op = ops[k];
    const uint8_t* s = rec + op.src;
    switch (op.kind) {
      case OpKind::Copy:
        std::memcpy(attrs + op.dst, s, op.count);
        break;
      case OpKind::Swap2:
        swapCopy<2>(s, attrs + op.dst, op.count);
        break;
      case OpKind::Swap4:
        swapCopy<4>(s, attrs + op.dst, op.count);
        break;
      case OpKind::Swap8:
        swapCopy<8>(s, attrs + op.dst, op.count);
        break;
      case OpKind::XyzF64:
        std::memcpy(xyzBytes + op.dst, s, 8 * size_t(op.count));
        break;
      case OpKind::XyzF32:
        for (uint32_t i = 0; i < op.count; ++i) {
          float f;
          std::memcpy(&f, s + 4 * i, 4);
          xyz[op.dst / 8 + i] = f;
        }
        break;
      case OpKind::RgbU8:
        for (uint32_t i = 0; i < op.count; ++i) {
          const uint16_t v = uint16_t(s[i] * 257);
          std::memcpy(attrs + op.dst + 2 * i, &v, 2);
        }
        break;
      case OpKind::Convert:
        convert(op, s, xyz, attrs, clamped);
        break;
    }
  }
}

class PlyReader final : public PointReader {
 public:
  PlyReader(std::shared_ptr<ByteSource> src, const ReadOptions& options)
      : src_(std::move(src)),
        options_(options),
        ply_(ply::parseHeader(src_->name(), src_->data(), src_->size())) {
    for (size_t i = 0; i < ply_.elements.size(); ++i)
      if (ply_.elements[i].name == "vertex") vertexIndex_ = i;
    if (vertexIndex_ == kNone)
      throw Error(src_->name(), Error::atLine(ply_.headerLines),
                  "the PLY header declares no 'vertex' element");
    swap_ = ply_.encoding != Encoding::Ascii &&
            (ply_.encoding == Encoding::BinaryLittle) != kNativeLittle;
    plan();
    describe();
    locateVertices();
    rewind();
  }

  const SourceHeader& header() const override { return header_; }
  std::vector<std::string> warnings() const override {
    auto w = warnings_;
    if (clamped_ > 0)
      w.push_back(std::to_string(clamped_) + " colour values outside [0, 1] were clamped");
    return w;
  }
  uint64_t bytesConsumed() const override { return pos_; }
  uint64_t bytesTotal() const override { return src_->size(); }

  void rewind() override {
    pos_ = vertexStart_;
    line_ = vertexLine_;
    done_ = 0;
    ended_ = false;
    clamped_ = 0;
    src_->releaseBefore(pos_);
  }

  // The batch is resized, not cleared first: a batch reused at the same size is then written
  // over without being zero-filled again, which costs as much as the conversion itself.
  bool read(PointBatch& batch, size_t maxPoints) override {
    if (ended_ || done_ >= vertexCount_) {
      batch.clear();
      finish();
      return false;
    }
    if (maxPoints == 0) {
      batch.clear();
      return true;
    }
    size_t n;
    if (ply_.encoding == Encoding::Ascii)
      n = readAscii(batch, maxPoints);
    else if (vertexHasLists_)
      n = readVariable(batch, maxPoints);
    else
      n = readFixed(batch, maxPoints);
    src_->releaseBefore(pos_);
    if (n == 0) {
      finish();
      return false;
    }
    return true;
  }

 private:
  static constexpr size_t kNone = std::numeric_limits<size_t>::max();

  const PlyElement& vertex() const { return ply_.elements[vertexIndex_]; }

  // Chooses what each vertex property becomes and compiles the conversions.
  void plan() {
    const PlyElement& v = vertex();
    const auto& props = v.properties;
    auto find = [&](std::string_view name) -> int {
      for (size_t i = 0; i < props.size(); ++i)
        if (props[i].name == name && !props[i].list) return int(i);
      return -1;
    };
    auto findAll = [&](std::initializer_list<std::array<const char*, 3>> sets, auto accept) {
      for (const auto& names : sets) {
        std::array<int, 3> idx{find(names[0]), find(names[1]), find(names[2])};
        if (idx[0] >= 0 && idx[1] >= 0 && idx[2] >= 0 && accept(idx)) return idx;
      }
      return std::array<int, 3>{-1, -1, -1};
    };

    const std::array<int, 3> xyz = {find("x"), find("y"), find("z")};
    for (int c = 0; c < 3; ++c)
      if (xyz[c] < 0)
        throw Error(src_->name(), Error::atLine(v.line),
                    std::string("the vertex element has no scalar property '") + "xyz"[c] + "'");
    auto colourType = [&](int i) {
      ScalarType t = props[i].type;
      return t == ScalarType::U8 || t == ScalarType::U16 || isFloat(t);
    };
    const auto rgb =
        findAll({{"red", "green", "blue"},
                 {"r", "g", "b"},
                 {"diffuse_red", "diffuse_green", "diffuse_blue"}},
                [&](auto& i) { return colourType(i[0]) && colourType(i[1]) && colourType(i[2]); });
    const auto normal = findAll({{"nx", "ny", "nz"}, {"normal_x", "normal_y", "normal_z"}},
                                [](auto&) { return true; });
    int intensity = find("intensity");
    if (intensity < 0) intensity = find("scalar_intensity");

    PointLayout layout;
    std::vector<Op> ops;
    int rgbAttr = -1, normalAttr = -1;
    uint32_t packed = 0;
    for (size_t i = 0; i < props.size(); ++i) {
      const PlyProperty& p = props[i];
      if (p.list) {
        skippedLists_.push_back(p.name);
        continue;
      }
      const ScalarType t = p.type;
      const uint32_t size = uint32_t(scalarSize(t));
      const bool swap = swap_ && size > 1;
      Op op;
      op.src = packed;
      op.count = 1;
      packed += size;
      auto convertTo = [&](ScalarType dst) {
        op.kind = OpKind::Convert;
        op.srcType = t;
        op.dstType = dst;
        op.swap = swap;
      };
      auto copy = [&] {
        if (!swap) {
          op.kind = OpKind::Copy;
          op.count = size;
        } else {
          op.kind = size == 2 ? OpKind::Swap2 : size == 4 ? OpKind::Swap4 : OpKind::Swap8;
        }
      };
      auto component = [](const std::array<int, 3>& group, size_t i) {
        for (int c = 0; c < 3; ++c)
          if (group[c] == int(i)) return c;
        return -1;
      };
      if (int c = component(xyz, i); c >= 0) {
        op.dst = 8 * c;
        if (!swap && t == ScalarType::F64)
          op.kind = OpKind::XyzF64;
        else if (!swap && t == ScalarType::F32)
          op.kind = OpKind::XyzF32;
        else {
          convertTo(ScalarType::F64);
          op.toXyz = true;
        }
      } else if (int c = component(rgb, i); c >= 0) {
        if (rgbAttr < 0)
          rgbAttr = int(layout.add(
              {std::string(attr::kRgb), ScalarType::U16, 3,
               "PLY " + props[rgb[0]].name + "/" + props[rgb[1]].name + "/" + props[rgb[2]].name}));
        op.dst = uint32_t(layout.offset(rgbAttr) + 2 * c);
        if (t == ScalarType::U8)
          op.kind = OpKind::RgbU8;
        else if (t == ScalarType::U16)
          copy();
        else {
          convertTo(ScalarType::U16);
          op.transform = Transform::UnitToU16;
        }
      } else if (int c = component(normal, i); c >= 0) {
        if (normalAttr < 0)
          normalAttr = int(layout.add({std::string(attr::kNormal), ScalarType::F32, 3,
                                       "PLY " + props[normal[0]].name + "/" +
                                           props[normal[1]].name + "/" + props[normal[2]].name}));
        op.dst = uint32_t(layout.offset(normalAttr) + 4 * c);
        if (t == ScalarType::F32)
          copy();
        else
          convertTo(ScalarType::F32);
      } else {
        std::string name = int(i) == intensity ? std::string(attr::kIntensity) : p.name;
        // The fixed-meaning names must keep their meaning (uint16 x3, float x3).
        if (name == attr::kRgb || name == attr::kNormal) name = "ply_" + name;
        while (layout.has(name)) name += "_";
        const size_t a = layout.add({name, t, 1, "PLY property " + p.name});
        op.dst = uint32_t(layout.offset(a));
        copy();
      }
      if (!ops.empty() && ops.back().extends(op))
        ops.back().count += op.count;
      else
        ops.push_back(op);
    }
    if (rgb[0] >= 0) {
      const bool bytes = props[rgb[0]].type == ScalarType::U8 &&
                         props[rgb[1]].type == ScalarType::U8 &&
                         props[rgb[2]].type == ScalarType::U8;
      header_.rgbBits = bytes ? 8 : 16;
    }
    recordBytes_ = packed;
    ops_ = std::move(ops);
    header_.layout = std::move(layout);
    vertexHasLists_ = v.hasLists();
    scratch_.assign(recordBytes_ + 8, 0);
    packedOffsets_.clear();
    uint32_t off = 0;
    for (const auto& p : props) {
      packedOffsets_.push_back(off);
      if (!p.list) off += uint32_t(scalarSize(p.type));
    }
  }

  void describe() {
    header_.path = src_->name();
    header_.format = "ply";
    header_.declaredPoints = vertex().count;
    header_.crs = crsFromComments(ply_.comments);
    nlohmann::json elements = nlohmann::json::array();
    for (const auto& e : ply_.elements) {
      nlohmann::json props = nlohmann::json::array();
      for (const auto& p : e.properties) {
        if (p.list)
          props.push_back({{"name", p.name},
                           {"list", true},
                           {"countType", p.countTypeName},
                           {"type", p.typeName}});
        else
          props.push_back({{"name", p.name}, {"type", p.typeName}});
      }
      elements.push_back({{"name", e.name}, {"count", e.count}, {"properties", props}});
    }
    header_.details = {{"encoding", encodingName(ply_.encoding)},
                       {"version", ply_.version},
                       {"comments", ply_.comments},
                       {"elements", elements}};
    if (!ply_.objInfo.empty()) header_.details["obj_info"] = ply_.objInfo;
    if (!skippedLists_.empty()) header_.details["skippedVertexLists"] = skippedLists_;
  }

  // Walks the elements before the vertices, and checks that the vertices fit in the file.
  void locateVertices() {
    const std::string& file = src_->name();
    size_t pos = ply_.dataStart;
    uint64_t line = ply_.headerLines;
    for (size_t i = 0; i < vertexIndex_; ++i) {
      const PlyElement& e = ply_.elements[i];
      const uint64_t complete =
          ply_.encoding == Encoding::Ascii ? skipAscii(e, pos, line) : skipBinary(e, pos);
      if (complete < e.count)
        throw Error(file,
                    ply_.encoding == Encoding::Ascii ? Error::atLine(line) : Error::atByte(pos),
                    "the file ends inside element '" + e.name +
                        "' before the vertices: " + std::to_string(complete) + " of " +
                        std::to_string(e.count) + " records are complete");
    }
    vertexStart_ = pos;
    vertexLine_ = line;
    vertexCount_ = vertex().count;
    if (ply_.encoding != Encoding::Ascii && !vertexHasLists_) {
      const uint64_t complete =
          std::min<uint64_t>(vertexCount_, (src_->size() - vertexStart_) / recordBytes_);
      if (complete < vertexCount_)
        shortOfVertices(complete, vertexStart_ + complete * recordBytes_);
    }
  }

  // The data holds only `complete` of the declared vertices: an error, or in lenient mode a
  // warning and the complete ones.
  void shortOfVertices(uint64_t complete, size_t at) {
    const bool ascii = ply_.encoding == Encoding::Ascii;
    std::string position = ascii ? Error::atLine(line_) : Error::atByte(at);
    std::string msg = "the header declares " + std::to_string(vertex().count) +
                      " vertices but the file holds only " + std::to_string(complete) +
                      " complete ones (data ends at byte " + std::to_string(at) + ")";
    if (!options_.lenient)
      throw Error(src_->name(), position,
                  msg +
                      "; the file may be truncated (lenient mode keeps "
                      "the complete vertices)");
    warnings_.push_back(position + ": " + msg + "; kept " + std::to_string(complete));
    vertexCount_ = complete;
    shortData_ = true;
  }

  // One binary record of `e` from `pos`: false if the data ends inside it. Scalars are packed
  // into `packed` when given.
  bool walkRecord(const PlyElement& e, size_t& pos, uint8_t* packed) const {
    const uint8_t* d = src_->data();
    const size_t size = src_->size();
    size_t p = pos;
    for (const auto& prop : e.properties) {
      if (!prop.list) {
        const size_t s = scalarSize(prop.type);
        if (size - p < s) return false;
        if (packed) {
          std::memcpy(packed, d + p, s);
          packed += s;
        }
        p += s;
        continue;
      }
      const size_t cs = scalarSize(prop.countType);
      if (size - p < cs) return false;
      const auto n = listCount(prop.countType, d + p, swap_);
      if (!n)
        throw Error(
            src_->name(), Error::atByte(p),
            "negative list length in property '" + prop.name + "' of element '" + e.name + "'");
      p += cs;
      const size_t is = scalarSize(prop.type);
      if (*n > (size - p) / is) return false;
      p += *n * is;
    }
    pos = p;
    return true;
  }

  // Steps over the records of `e`; returns how many were complete before the data ended.
  uint64_t skipBinary(const PlyElement& e, size_t& pos) const {
    if (!e.hasLists()) {
      const size_t rec = e.scalarBytes();
      if (rec == 0) return e.count;
      const uint64_t complete = std::min<uint64_t>(e.count, (src_->size() - pos) / rec);
      pos += complete * rec;
      return complete;
    }
    // Every record takes at least its count's byte, so this ends with the data.
    for (uint64_t r = 0; r < e.count; ++r) {
      if (!walkRecord(e, pos, nullptr)) return r;
      if ((r & 0xFFFFF) == 0) src_->releaseBefore(pos);
    }
    return e.count;
  }

  uint64_t skipAscii(const PlyElement& e, size_t& pos, uint64_t& line) const {
    if (e.properties.empty()) return e.count;
    const char* d = reinterpret_cast<const char*>(src_->data());
    std::string_view text;
    for (uint64_t r = 0; r < e.count; ++r)
      if (!nextDataLine(d, src_->size(), pos, line, text)) return r;
    return e.count;
  }

  size_t readFixed(PointBatch& batch, size_t maxPoints) {
    const size_t n = size_t(std::min<uint64_t>(maxPoints, vertexCount_ - done_));
    const size_t stride = header_.layout.stride();
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * stride);
    const uint8_t* rec = src_->data() + pos_;
    double* xyz = batch.xyz.data();
    uint8_t* attrs = batch.attrs.data();
    const Op* ops = ops_.data();
    const size_t nops = ops_.size();
    for (size_t i = 0; i < n; ++i, rec += recordBytes_, xyz += 3, attrs += stride)
      applyOps(ops, nops, rec, xyz, attrs, clamped_);
    pos_ += n * recordBytes_;
    done_ += n;
    return n;
  }

  // Room for the points the rest of the data can hold, so that a header that claims billions
  // of vertices in a small file allocates nothing large.
  size_t reserve(PointBatch& batch, size_t maxPoints, size_t minRecordBytes) {
    const uint64_t fit = (src_->size() - pos_) / std::max<size_t>(minRecordBytes, 1) + 1;
    const size_t n = size_t(std::min<uint64_t>({maxPoints, vertexCount_ - done_, fit}));
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * header_.layout.stride());
    return n;
  }
  void shrink(PointBatch& batch, size_t n) {
    batch.xyz.resize(n * 3);
    batch.attrs.resize(n * header_.layout.stride());
  }

  size_t readVariable(PointBatch& batch, size_t maxPoints) {
    const size_t cap = reserve(batch, maxPoints, vertex().minBinaryBytes());
    const size_t stride = header_.layout.stride();
    size_t n = 0;
    while (n < cap) {
      if (!walkRecord(vertex(), pos_, scratch_.data())) {
        ended_ = true;
        shortOfVertices(done_, pos_);
        break;
      }
      applyOps(ops_.data(), ops_.size(), scratch_.data(), &batch.xyz[3 * n],
               batch.attrs.data() + n * stride, clamped_);
      ++n, ++done_;
    }
    shrink(batch, n);
    return n;
  }

  size_t readAscii(PointBatch& batch, size_t maxPoints) {
    const PlyElement& v = vertex();
    // An ascii value takes at least two bytes: a digit and a separator.
    const size_t cap = reserve(batch, maxPoints, 2 * v.properties.size());
    const size_t stride = header_.layout.stride();
    const char* d = reinterpret_cast<const char*>(src_->data());
    const size_t size = src_->size();
    size_t n = 0;
    std::string_view text;
    while (n < cap) {
      if (!nextDataLine(d, size, pos_, line_, text)) {
        ended_ = true;
        shortOfVertices(done_, pos_);
        break;
      }
      if (!parseAsciiRecord(text)) {
        // A short last line is a truncated file; a short line elsewhere is a malformed one.
        size_t after = pos_;
        uint64_t ignored = line_;
        std::string_view more;
        if (!nextDataLine(d, size, after, ignored, more)) {
          ended_ = true;
          shortOfVertices(done_, size_t(text.data() - d));
          break;
        }
        throw Error(src_->name(), Error::atLine(line_),
                    "vertex " + std::to_string(done_) + ": expected " +
                        std::to_string(v.properties.size()) +
                        " values (lists count as their length and items), found " +
                        std::to_string(splitWords(text).size()));
      }
      applyOps(ops_.data(), ops_.size(), scratch_.data(), &batch.xyz[3 * n],
               batch.attrs.data() + n * stride, clamped_);
      ++n, ++done_;
    }
    shrink(batch, n);
    return n;
  }

  // Packs one ascii vertex line into scratch_; false when it has too few or too many values.
  bool parseAsciiRecord(std::string_view text) {
    const char* p = text.data();
    const char* e = p + text.size();
    const char *tb = nullptr, *te = nullptr;
    auto next = [&] {
      while (p < e && text::isBlank(*p)) ++p;
      if (p == e) return false;
      tb = p;
      while (p < e && !text::isBlank(*p)) ++p;
      te = p;
      return true;
    };
    const auto& props = vertex().properties;
    for (size_t i = 0; i < props.size(); ++i) {
      const PlyProperty& prop = props[i];
      if (!next()) return false;
      if (prop.list) {
        uint64_t count;
        if (!text::parseInteger(tb, te, count)) badNumber(tb, te, prop, "list length");
        for (uint64_t k = 0; k < count; ++k)
          if (!next()) return false;
        continue;
      }
      if (!parseScalar(prop.type, tb, te, scratch_.data() + packedOffsets_[i]))
        badNumber(tb, te, prop, prop.typeName);
    }
    return !next();
  }

  [[noreturn]] void badNumber(const char* b, const char* e, const PlyProperty& prop,
                              const std::string& what) const {
    throw Error(src_->name(), Error::atLine(line_),
                "cannot read " + text::quote(std::string_view(b, size_t(e - b))) + " as " + what +
                    " (vertex " + std::to_string(done_) + ", property '" + prop.name + "')");
  }

  // After the last vertex: what follows should be exactly the elements the header declares.
  // Disagreements lose no point, so they are warnings. Warnings do not repeat the file's name:
  // whoever shows them names the reader's file.
  void finish() {
    if (finished_ || shortData_) return;
    finished_ = true;
    size_t pos = pos_;
    uint64_t line = line_;
    const bool ascii = ply_.encoding == Encoding::Ascii;
    try {
      for (size_t i = vertexIndex_ + 1; i < ply_.elements.size(); ++i) {
        const PlyElement& e = ply_.elements[i];
        const uint64_t complete = ascii ? skipAscii(e, pos, line) : skipBinary(e, pos);
        if (complete < e.count) {
          warnings_.push_back("the file ends inside element '" + e.name + "' after " +
                              std::to_string(complete) + " of " + std::to_string(e.count) +
                              " records (after all the vertices)");
          return;
        }
      }
    } catch (const Error& e) {
      warnings_.push_back(e.position() + ": " + e.reason() + " (after all the vertices)");
      return;
    }
    const char* d = reinterpret_cast<const char*>(src_->data());
    if (ascii) {
      uint64_t extra = 0;
      std::string_view text;
      const uint64_t first = line + 1;
      while (nextDataLine(d, src_->size(), pos, line, text)) ++extra;
      if (extra > 0)
        warnings_.push_back(Error::atLine(first) + ": " + std::to_string(extra) +
                            " lines follow the last element the header declares; the header "
                            "may declare too few vertices");
    } else if (pos < src_->size()) {
      const size_t extra = src_->size() - pos;
      std::string msg = Error::atByte(pos) + ": " + std::to_string(extra) +
                        " bytes follow the last element the header declares";
      if (vertexIndex_ + 1 == ply_.elements.size() && !vertexHasLists_)
        msg += " (room for " + std::to_string(extra / recordBytes_) +
               " more vertices: the header may declare too few)";
      warnings_.push_back(msg);
    }
  }

  std::shared_ptr<ByteSource> src_;
  ReadOptions options_;
  PlyHeader ply_;
  SourceHeader header_;
  size_t vertexIndex_ = kNone;
  bool swap_ = false;
  bool vertexHasLists_ = false;
  std::vector<Op> ops_;
  std::vector<uint32_t> packedOffsets_;  // per vertex property, in the packed record
  std::vector<std::string> skippedLists_;
  size_t recordBytes_ = 0;  // of the packed scalars: a binary record when there are no lists
  std::vector<uint8_t> scratch_;

  size_t vertexStart_ = 0;
  uint64_t vertexLine_ = 0;
  uint64_t vertexCount_ = 0;  // to read: the declared count, or the complete ones if lenient

  size_t pos_ = 0;
  uint64_t line_ = 0;
  uint64_t done_ = 0;
  bool ended_ = false;      // this pass met the end of the data before vertexCount_ (lenient)
  bool shortData_ = false;  // the data holds fewer vertices than declared (lenient)
  bool finished_ = false;
  uint64_t clamped_ = 0;
  std::vector<std::string> warnings_;
};

}  // namespace

std::unique_ptr<PointReader> openPly(std::shared_ptr<ByteSource> src, const ReadOptions& o) {
  return std::make_unique<PlyReader>(std::move(src), o);
}

}  // namespace nestlight
