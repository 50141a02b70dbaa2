// Triangle meshes from PLY: G. Turk, "The PLY Polygon File Format" (Stanford, 1994). The header
// parser is the scan reader's (octree/ply_header); the records are read here, because a mesh
// wants other things from them than a scan does: the "face" element's vertex lists, and vertex
// colours as linear albedo rather than 16-bit sRGB.
//
// Read: vertex x, y, z of any numeric type (float and double in practice); nx, ny, nz; red,
// green, blue (uchar or ushort as sRGB codes, decoded to linear; float or double as linear values
// in [0,1], clamped); the face list "vertex_indices" (or "vertex_index") of any integer count and
// index types. Every other element and property is walked over, lists included.
//
// Every count in the file is untrusted: records are read one by one against the bytes that are
// really there, memory is reserved only for what the remaining bytes can hold, and an element
// without properties (records of no bytes) is passed over without looping over its count.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "mesh_builder.h"
#include "nestlight/gi/srgb.h"
#include "nestlight/octree/attribute.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/ply_header.h"
#include "nestlight/octree/text.h"

namespace nestlight::gi::meshio {
namespace {

constexpr bool kNativeLittle = std::endian::native == std::endian::little;

// What a property of an element is read as.
enum class Role : uint8_t { Skip, X, Y, Z, NX, NY, NZ, Red, Green, Blue, Indices, kCount };

// How a colour channel's stored value becomes linear [0,1].
enum class ColourCode : uint8_t { Srgb8, Srgb16, Linear };

float toFloat(double v) {
  // Beyond float's range a value becomes an infinity, which the builder counts as non-finite.
  constexpr double kMax = std::numeric_limits<float>::max();
  if (v > kMax) return std::numeric_limits<float>::infinity();
  if (v < -kMax) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(v);
}

// One ascii token as a value of `t`: integers must be whole and in the type's range (some writers
// print them as "255.000000").
bool parseAscii(ScalarType t, std::string_view tok, double& out) {
  const char* b = tok.data();
  const char* e = b + tok.size();
  if (isFloat(t)) return text::parseDouble(b, e, out);
  int64_t i;
  if (text::parseInteger(b, e, i)) {
    out = double(i);
  } else {
    uint64_t u;
    if (text::parseInteger(b, e, u))
      out = double(u);
    else if (!text::parseDouble(b, e, out) || !std::isfinite(out) || out != std::trunc(out))
      return false;
  }
  double lo = 0, hi = 0;
  switch (t) {
    case ScalarType::U8:
      lo = 0, hi = 255;
      break;
    case ScalarType::I8:
      lo = -128, hi = 127;
      break;
    case ScalarType::U16:
      lo = 0, hi = 65535;
      break;
    case ScalarType::I16:
      lo = -32768, hi = 32767;
      break;
    case ScalarType::U32:
      lo = 0, hi = 4294967295.0;
      break;
    case ScalarType::I32:
      lo = -2147483648.0, hi = 2147483647.0;
      break;
    case ScalarType::U64:
      lo = 0, hi = 18446744073709551615.0;
      break;
    case ScalarType::I64:
      lo = -9223372036854775808.0, hi = 9223372036854775807.0;
      break;
    case ScalarType::F32:
    case ScalarType::F64:
      break;
  }
  return out >= lo && out <= hi;
}

class PlyMeshReader {
 public:
  PlyMeshReader(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out)
      : file_(file), data_(data), size_(size), out_(out), h_(ply::parseHeader(file, data, size)) {
    swap_ = h_.encoding != ply::Encoding::Ascii &&
            (h_.encoding == ply::Encoding::BinaryLittle) != kNativeLittle;
  }

  void read() {
    plan();
    checkSizes();
    pos_ = h_.dataStart;
    line_ = h_.headerLines;
    for (size_t i = 0; i < h_.elements.size(); ++i) {
      const ply::Element& e = h_.elements[i];
      if (e.properties.empty()) continue;  // records of nothing: nothing to read or skip
      if (ascii())
        readAsciiElement(i);
      else
        readBinaryElement(i);
    }
    trailing();
    if (out_.report.facesRead == 0)
      throw Error(file_, Error::atLine(h_.elements[face_].line),
                  "the 'face' element holds no faces: a point cloud, not a mesh");
    if (clamped_ > 0)
      out_.report.warnings.push_back(std::to_string(clamped_) +
                                     " colour values outside [0, 1] were clamped");
  }

 private:
  bool ascii() const { return h_.encoding == ply::Encoding::Ascii; }
  std::string where() const { return ascii() ? Error::atLine(line_) : Error::atByte(pos_); }

  // Chooses each property's role, and checks what a mesh needs: x, y, z and the face lists.
  void plan() {
    roles_.resize(h_.elements.size());
    for (size_t i = 0; i < h_.elements.size(); ++i) {
      const auto& e = h_.elements[i];
      roles_[i].assign(e.properties.size(), Role::Skip);
      if (e.name == "vertex") vertex_ = i;
      if (e.name == "face") face_ = i;
    }
    const uint64_t headerEnd = h_.headerLines;
    if (vertex_ == kNone)
      throw Error(file_, Error::atLine(headerEnd), "the PLY header declares no 'vertex' element");
    if (face_ == kNone)
      throw Error(file_, Error::atLine(headerEnd),
                  "the PLY header declares no 'face' element: a point cloud, not a mesh");
    const ply::Element& v = h_.elements[vertex_];
    const ply::Element& f = h_.elements[face_];
    if (v.count > std::numeric_limits<uint32_t>::max())
      throw Error(file_, Error::atLine(v.line),
                  "the header declares " + std::to_string(v.count) +
                      " vertices; meshes hold at most 2^32 - 1 (32-bit indices)");
    vertexCount_ = v.count;

    auto find = [&](const ply::Element& e, std::string_view name) -> int {
      for (size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].name == name) return int(i);
      return -1;
    };
    auto& vr = roles_[vertex_];
    const char* xyz[3] = {"x", "y", "z"};
    for (int c = 0; c < 3; ++c) {
      const int i = find(v, xyz[c]);
      if (i < 0 || v.properties[i].list)
        throw Error(file_, Error::atLine(v.line),
                    std::string("the vertex element has no scalar property '") + xyz[c] + "'");
      vr[i] = Role(int(Role::X) + c);
    }
    auto group = [&](std::initializer_list<std::array<const char*, 3>> sets) {
      for (const auto& names : sets) {
        std::array<int, 3> idx{find(v, names[0]), find(v, names[1]), find(v, names[2])};
        if (idx[0] >= 0 && idx[1] >= 0 && idx[2] >= 0 && !v.properties[idx[0]].list &&
            !v.properties[idx[1]].list && !v.properties[idx[2]].list)
          return idx;
      }
      return std::array<int, 3>{-1, -1, -1};
    };
    const auto normal = group({{"nx", "ny", "nz"}, {"normal_x", "normal_y", "normal_z"}});
    if (normal[0] >= 0) {
      hasNormals_ = true;
      for (int c = 0; c < 3; ++c) vr[normal[c]] = Role(int(Role::NX) + c);
    }
    const auto rgb =
        group({{"red", "green", "blue"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}});
    if (rgb[0] >= 0) {
      bool ok = true;
      for (int c = 0; c < 3; ++c) {
        const ScalarType t = v.properties[rgb[c]].type;
        if (t == ScalarType::U8)
          colourCode_[c] = ColourCode::Srgb8;
        else if (t == ScalarType::U16)
          colourCode_[c] = ColourCode::Srgb16;
        else if (isFloat(t))
          colourCode_[c] = ColourCode::Linear;
        else
          ok = false;
      }
      if (ok) {
        hasColours_ = true;
        for (int c = 0; c < 3; ++c) vr[rgb[c]] = Role(int(Role::Red) + c);
      } else {
        out_.report.warnings.push_back(
            "vertex colours ignored: '" + v.properties[rgb[0]].name + "' and its channels are " +
            v.properties[rgb[0]].typeName + "/" + v.properties[rgb[1]].typeName + "/" +
            v.properties[rgb[2]].typeName + ", not uchar, ushort, float or double");
      }
    }

    int list = find(f, "vertex_indices");
    if (list < 0) list = find(f, "vertex_index");
    if (list < 0 || !f.properties[list].list)
      throw Error(file_, Error::atLine(f.line),
                  "the face element has no list property 'vertex_indices' or 'vertex_index'");
    if (isFloat(f.properties[list].type))
      throw Error(
          file_, Error::atLine(f.line),
          "vertex indices of type " + f.properties[list].typeName + "; indices must be integers");
    roles_[face_][list] = Role::Indices;
  }

  // A binary header that declares more records than the bytes can hold fails here, before any
  // reading or reserving.
  void checkSizes() {
    if (ascii()) return;
    const uint64_t avail = size_ - h_.dataStart;
    uint64_t need = 0;
    for (const auto& e : h_.elements) {
      const uint64_t rec = e.minBinaryBytes();
      if (rec == 0) continue;
      if (e.count > (avail - need) / rec) {
        throw Error(file_, Error::atByte(h_.dataStart),
                    "the header declares " + std::to_string(e.count) + " '" + e.name +
                        "' records of at least " + std::to_string(rec) +
                        " bytes each, more than the " + std::to_string(avail - need) +
                        " bytes left for them; the file is truncated or its header lies");
      }
      need += e.count * rec;
    }
  }

  void reserve(size_t element) {
    const ply::Element& e = h_.elements[element];
    const size_t perRecord = ascii() ? 2 * e.properties.size() : e.minBinaryBytes();
    const uint64_t fit = (size_ - std::min(pos_, size_)) / std::max<size_t>(perRecord, 1) + 1;
    const size_t n = size_t(std::min<uint64_t>(e.count, fit));
    if (element == vertex_) {
      out_.mesh.positions.reserve(n);
      if (hasNormals_) out_.mesh.normals.reserve(n);
      if (hasColours_) out_.mesh.colors.reserve(n);
    } else if (element == face_) {
      out_.mesh.indices.reserve(3 * n);
    }
  }

  void startRecord() { std::fill(values_.begin(), values_.end(), 0.0); }

  void endVertex() {
    auto& m = out_.mesh;
    const double* v = values_.data();
    m.positions.emplace_back(toFloat(v[int(Role::X)]), toFloat(v[int(Role::Y)]),
                             toFloat(v[int(Role::Z)]));
    if (hasNormals_)
      m.normals.emplace_back(toFloat(v[int(Role::NX)]), toFloat(v[int(Role::NY)]),
                             toFloat(v[int(Role::NZ)]));
    if (hasColours_) {
      Rgb c;
      for (int k = 0; k < 3; ++k) {
        double x = v[int(Role::Red) + k];
        switch (colourCode_[k]) {
          case ColourCode::Srgb8:
            x = srgbDecode(float(x / 255.0));
            break;
          case ColourCode::Srgb16:
            x = srgbDecode(float(x / 65535.0));
            break;
          case ColourCode::Linear:
            if (!(x >= 0 && x <= 1)) {
              ++clamped_;
              x = x > 1 ? 1 : 0;  // NaN becomes 0
            }
            break;
        }
        c[k] = float(x);
      }
      m.colors.push_back(c);
    }
  }

  void index(uint64_t i, uint64_t record) {
    if (i >= vertexCount_)
      throw Error(file_, where(),
                  "face " + std::to_string(record) + ": vertex index " + std::to_string(i) +
                      " is out of range (the header declares " + std::to_string(vertexCount_) +
                      " vertices)");
    corners_.push_back(uint32_t(i));
  }

  [[noreturn]] void endsInside(size_t element, uint64_t record) const {
    const ply::Element& e = h_.elements[element];
    throw Error(file_, where(),
                "the file ends inside element '" + e.name + "': " + std::to_string(record) +
                    " of the " + std::to_string(e.count) +
                    " records the header declares are complete; the file is truncated or its "
                    "header lies");
  }

  void readAsciiElement(size_t element) {
    const ply::Element& e = h_.elements[element];
    const auto& roles = roles_[element];
    const bool isVertex = element == vertex_, isFace = element == face_;
    const char* d = reinterpret_cast<const char*>(data_);
    reserve(element);
    std::string_view text, tok;
    for (uint64_t r = 0; r < e.count; ++r) {
      if (!ply::nextDataLine(d, size_, pos_, line_, text)) endsInside(element, r);
      Tokens t{text.data(), text.data() + text.size()};
      startRecord();
      corners_.clear();
      auto tooFew = [&] {
        throw Error(file_, where(),
                    e.name + " " + std::to_string(r) +
                        ": the line ends before the last property '" + e.properties.back().name +
                        "'");
      };
      for (size_t p = 0; p < e.properties.size(); ++p) {
        const ply::Property& prop = e.properties[p];
        if (!t.next(tok)) tooFew();
        if (prop.list) {
          uint64_t n;
          if (!text::parseInteger(tok.data(), tok.data() + tok.size(), n))
            throw Error(file_, where(),
                        e.name + " " + std::to_string(r) + ": cannot read " + text::quote(tok) +
                            " as the length of list '" + prop.name + "'");
          for (uint64_t k = 0; k < n; ++k) {
            if (!t.next(tok)) tooFew();
            if (roles[p] != Role::Indices) continue;
            double x;
            if (!parseAscii(prop.type, tok, x) || x < 0)
              throw Error(file_, where(),
                          "face " + std::to_string(r) + ": cannot read " + text::quote(tok) +
                              " as a vertex index of type " + prop.typeName);
            index(x >= 18446744073709551615.0 ? std::numeric_limits<uint64_t>::max() : uint64_t(x),
                  r);
          }
          continue;
        }
        if (roles[p] == Role::Skip) continue;
        if (!parseAscii(prop.type, tok, values_[int(roles[p])]))
          throw Error(file_, where(),
                      e.name + " " + std::to_string(r) + ": cannot read " + text::quote(tok) +
                          " as " + prop.typeName + " (property '" + prop.name + "')");
      }
      if (t.next(tok))
        throw Error(file_, where(),
                    e.name + " " + std::to_string(r) + ": more values than the " +
                        std::to_string(e.properties.size()) +
                        " properties the header declares (a list counts as its length and items)");
      if (isVertex) endVertex();
      if (isFace) out_.addPolygon(corners_.data(), corners_.size());
    }
  }

  void readBinaryElement(size_t element) {
    const ply::Element& e = h_.elements[element];
    const auto& roles = roles_[element];
    const bool isVertex = element == vertex_, isFace = element == face_;
    if (!isVertex && !isFace && !e.hasLists()) {
      const size_t rec = e.scalarBytes();
      if (e.count > (size_ - pos_) / rec) endsInside(element, (size_ - pos_) / rec);
      pos_ += size_t(e.count * rec);
      return;
    }
    reserve(element);
    uint8_t tmp[8];
    auto load = [&](ScalarType t) {
      const size_t s = scalarSize(t);
      std::memcpy(tmp, data_ + pos_, s);
      if (swap_) std::reverse(tmp, tmp + s);
      pos_ += s;
      return loadAsDouble(t, tmp);
    };
    for (uint64_t r = 0; r < e.count; ++r) {
      startRecord();
      corners_.clear();
      for (size_t p = 0; p < e.properties.size(); ++p) {
        const ply::Property& prop = e.properties[p];
        if (!prop.list) {
          const size_t s = scalarSize(prop.type);
          if (size_ - pos_ < s) endsInside(element, r);
          if (roles[p] == Role::Skip)
            pos_ += s;
          else
            values_[int(roles[p])] = load(prop.type);
          continue;
        }
        const size_t cs = scalarSize(prop.countType);
        if (size_ - pos_ < cs) endsInside(element, r);
        const auto n = ply::listCount(prop.countType, data_ + pos_, swap_);
        if (!n)
          throw Error(
              file_, where(),
              e.name + " " + std::to_string(r) + ": negative length of list '" + prop.name + "'");
        pos_ += cs;
        const size_t is = scalarSize(prop.type);
        if (*n > (size_ - pos_) / is) endsInside(element, r);
        if (roles[p] != Role::Indices) {
          pos_ += size_t(*n * is);
          continue;
        }
        for (uint64_t k = 0; k < *n; ++k) {
          const auto i = ply::listCount(prop.type, data_ + pos_, swap_);
          if (!i)
            throw Error(file_, where(), "face " + std::to_string(r) + ": negative vertex index");
          index(*i, r);
          pos_ += is;
        }
      }
      if (isVertex) endVertex();
      if (isFace) out_.addPolygon(corners_.data(), corners_.size());
    }
  }

  // Data after the last element loses nothing, but may mean the header declares too little.
  void trailing() {
    if (ascii()) {
      const char* d = reinterpret_cast<const char*>(data_);
      std::string_view text;
      uint64_t extra = 0, line = line_;
      const uint64_t first = line_ + 1;
      while (ply::nextDataLine(d, size_, pos_, line, text)) ++extra;
      if (extra > 0)
        out_.report.warnings.push_back(Error::atLine(first) + ": " + std::to_string(extra) +
                                       " lines follow the last element the header declares");
    } else if (pos_ < size_) {
      out_.report.warnings.push_back(Error::atByte(pos_) + ": " + std::to_string(size_ - pos_) +
                                     " bytes follow the last element the header declares");
    }
  }

  static constexpr size_t kNone = std::numeric_limits<size_t>::max();

  const std::string& file_;
  const uint8_t* data_;
  size_t size_;
  MeshBuilder& out_;
  ply::Header h_;
  bool swap_ = false;
  size_t vertex_ = kNone, face_ = kNone;
  uint64_t vertexCount_ = 0;
  bool hasNormals_ = false, hasColours_ = false;
  std::array<ColourCode, 3> colourCode_{};
  std::vector<std::vector<Role>> roles_;  // per element, per property

  size_t pos_ = 0;
  uint64_t line_ = 0;
  std::array<double, size_t(Role::kCount)> values_{};
  std::vector<uint32_t> corners_;
  uint64_t clamped_ = 0;
};

}  // namespace

void readPly(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out) {
  PlyMeshReader(file, data, size, out).read();
}

}  // namespace nestlight::gi::meshio
