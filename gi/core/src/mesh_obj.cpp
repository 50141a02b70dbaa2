// Triangle meshes from Wavefront OBJ: "Object Files (.obj)", Appendix B1 of the Advanced
// Visualizer manual (Wavefront Technologies, 1995). Read: `v` (x y z; a w or the vertex colours
// some writers append are ignored), `vn`, `vt` (counted only, so that face references to them
// can be checked) and `f` with corners v, v/vt, v//vn or v/vt/vn, indices from 1 or negative
// (relative to the data read so far). Every other statement (o, g, s, usemtl, mtllib, l, p,
// curves) is skipped. A line ending in a backslash continues on the next, as the spec allows.
//
// OBJ gives normals per face corner, a mesh per vertex. A vertex keeps the normal its first
// corner names; a corner naming another normal gets a copy of the vertex (appended after the
// file's vertices), so hard edges stay hard and smooth ones stay shared. Corners without a
// normal in a file where others have one get the area-weighted mean of their triangles' normals
// (MeshBuilder::finish) and a warning.
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>

#include "mesh_builder.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/text.h"

namespace nestlight::gi::meshio {
namespace {

constexpr uint32_t kNoNormal = std::numeric_limits<uint32_t>::max();
constexpr uint32_t kUnassigned = kNoNormal - 1;

class ObjMeshReader {
 public:
  ObjMeshReader(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out)
      : file_(file), data_(reinterpret_cast<const char*>(data)), size_(size), out_(out) {}

  void read() {
    if (size_ == 0) throw Error(file_, Error::atByte(0), "empty file");
    size_t pos = 0;
    std::string_view l;
    std::string joined;
    while (text::takeLine(data_, size_, pos, l)) {
      ++line_;
      statementLine_ = line_;
      std::string_view stmt = stripComment(l);
      if (endsInBackslash(stmt)) {
        joined.clear();
        do {
          const std::string_view s = text::trim(stmt);
          joined.append(s.substr(0, s.size() - 1));
          joined += ' ';
          stmt = {};
          if (!text::takeLine(data_, size_, pos, l)) break;
          ++line_;
          stmt = stripComment(l);
        } while (endsInBackslash(stmt));
        joined.append(stmt);
        stmt = joined;
      }
      statement(stmt);
    }
    if (polygonSizes_.empty())
      throw Error(file_, Error::atLine(line_), "the file holds no faces ('f'): not a mesh");
    build();
  }

 private:
  static std::string_view stripComment(std::string_view l) {
    const size_t hash = l.find('#');
    return hash == std::string_view::npos ? l : l.substr(0, hash);
  }
  static bool endsInBackslash(std::string_view s) {
    s = text::trim(s);
    return !s.empty() && s.back() == '\\';
  }

  [[noreturn]] void fail(const std::string& why) const {
    throw Error(file_, Error::atLine(statementLine_), why);
  }

  void statement(std::string_view s) {
    Tokens t{s.data(), s.data() + s.size()};
    std::string_view kw;
    if (!t.next(kw)) return;
    if (kw == "v") {
      if (out_.mesh.positions.size() >= std::numeric_limits<uint32_t>::max())
        fail("more than 2^32 - 1 vertices (meshes use 32-bit indices)");
      out_.mesh.positions.push_back(vec3(t, "v"));
    } else if (kw == "vn") {
      if (normals_.size() >= kUnassigned) fail("more than 2^32 - 2 normals");
      normals_.push_back(vec3(t, "vn"));
    } else if (kw == "vt") {
      ++texcoords_;
    } else if (kw == "f") {
      face(t);
    }
  }

  glm::vec3 vec3(Tokens& t, const char* what) const {
    glm::vec3 v;
    std::string_view tok;
    for (int c = 0; c < 3; ++c) {
      if (!t.next(tok)) fail(std::string("'") + what + "' needs three numbers");
      if (!text::parseFloat(tok.data(), tok.data() + tok.size(), v[c]))
        fail(std::string("cannot read ") + text::quote(tok) + " as a number in '" + what + "'");
    }
    return v;
  }

  // An OBJ index (1-based, or negative: -1 is the last one read) as a 0-based one.
  uint64_t resolve(std::string_view tok, uint64_t count, const char* what) const {
    int64_t i;
    if (!text::parseInteger(tok.data(), tok.data() + tok.size(), i))
      fail(std::string("cannot read ") + text::quote(tok) + " as a " + what + " index");
    if (i == 0) fail(std::string(what) + " index 0: OBJ indices start at 1 (or are negative)");
    if (i > 0 && uint64_t(i) <= count) return uint64_t(i) - 1;
    if (i < 0 && uint64_t(-(i + 1)) < count) return count - uint64_t(-(i + 1)) - 1;
    fail(std::string(what) + " index " + std::string(tok) + " is out of range: " +
         std::to_string(count) + " " + what + "s are defined before this line");
  }

  void face(Tokens& t) {
    std::string_view tok;
    uint32_t n = 0;
    while (t.next(tok)) {
      // v, v/vt, v//vn or v/vt/vn.
      std::string_view part[3];
      int parts = 0;
      size_t b = 0;
      while (true) {
        const size_t slash = tok.find('/', b);
        if (parts == 3) fail("face corner " + text::quote(tok) + " has more than three parts");
        part[parts++] = tok.substr(b, slash == std::string_view::npos ? slash : slash - b);
        if (slash == std::string_view::npos) break;
        b = slash + 1;
      }
      if (part[0].empty()) fail("face corner " + text::quote(tok) + " has no vertex index");
      const uint64_t v = resolve(part[0], out_.mesh.positions.size(), "vertex");
      if (parts >= 2 && !part[1].empty()) resolve(part[1], texcoords_, "texture coordinate");
      uint32_t vn = kNoNormal;
      if (parts == 3 && !part[2].empty())
        vn = uint32_t(resolve(part[2], normals_.size(), "normal"));
      cornerVertex_.push_back(uint32_t(v));
      cornerNormal_.push_back(vn);
      if (n == std::numeric_limits<uint32_t>::max()) fail("a face of more than 2^32 - 1 corners");
      ++n;
    }
    polygonSizes_.push_back(n);
  }

  // Corners to mesh vertices (see the top of the file), then the polygons to the builder.
  void build() {
    auto& m = out_.mesh;
    const size_t nFile = m.positions.size();
    bool anyNormal = false;
    uint64_t without = 0;
    for (uint32_t n : cornerNormal_) {
      anyNormal |= n != kNoNormal;
      without += n == kNoNormal;
    }
    if (anyNormal) {
      m.normals.assign(nFile, glm::vec3(0));
      out_.needsNormal.assign(nFile, 0);
      if (without > 0)
        out_.report.warnings.push_back(
            std::to_string(without) +
            " face corners have no normal while others have one; their vertices get the "
            "area-weighted mean of their triangles' normals");
    }
    std::vector<uint32_t> slot(anyNormal ? nFile : 0, kUnassigned);
    std::unordered_map<uint64_t, uint32_t> copies;
    auto assign = [&](uint32_t v, uint32_t n) -> uint32_t {
      if (!anyNormal) return v;
      auto give = [&](uint32_t to) {
        m.normals[to] = n == kNoNormal ? glm::vec3(0) : normals_[n];
        out_.needsNormal[to] = n == kNoNormal;
      };
      if (slot[v] == kUnassigned) {
        slot[v] = n;
        give(v);
        return v;
      }
      if (slot[v] == n) return v;
      const uint64_t key = uint64_t(v) << 32 | n;
      if (auto it = copies.find(key); it != copies.end()) return it->second;
      if (m.positions.size() >= std::numeric_limits<uint32_t>::max())
        throw Error(file_, "",
                    "more than 2^32 - 1 vertices once vertices with several normals are split");
      const auto copy = uint32_t(m.positions.size());
      m.positions.push_back(m.positions[v]);
      m.normals.emplace_back(0);
      out_.needsNormal.push_back(0);
      give(copy);
      copies.emplace(key, copy);
      return copy;
    };
    std::vector<uint32_t> corners;
    size_t c = 0;
    for (uint32_t n : polygonSizes_) {
      corners.clear();
      for (uint32_t k = 0; k < n; ++k, ++c)
        corners.push_back(assign(cornerVertex_[c], cornerNormal_[c]));
      out_.addPolygon(corners.data(), corners.size());
    }
  }

  const std::string& file_;
  const char* data_;
  size_t size_;
  MeshBuilder& out_;
  uint64_t line_ = 0, statementLine_ = 0;
  std::vector<glm::vec3> normals_;
  uint64_t texcoords_ = 0;
  std::vector<uint32_t> cornerVertex_, cornerNormal_, polygonSizes_;
};

}  // namespace

void readObj(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out) {
  ObjMeshReader(file, data, size, out).read();
}

}  // namespace nestlight::gi::meshio
