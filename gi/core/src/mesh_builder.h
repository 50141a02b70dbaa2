// Shared by the PLY and OBJ mesh readers: polygons in, clean triangles out. Private to gi/core.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "nestlight/gi/mesh.h"
#include "nestlight/octree/text.h"

namespace nestlight::gi::meshio {

class MeshBuilder {
 public:
  TriangleMesh mesh;
  MeshReadReport report;
  // Vertices whose normal the file leaves out while other vertices have one (OBJ corners without
  // `vn`): finish() gives them the area-weighted mean of their triangles' normals. Empty, or one
  // flag per position.
  std::vector<uint8_t> needsNormal;

  // `corners` index mesh.positions (the readers check the range, against the declared count
  // when the positions are not read yet). Fans the polygon out from its first corner.
  void addPolygon(const uint32_t* corners, size_t n);

  // Once every vertex and face is in: drops and counts degenerate triangles, normalises normals
  // and fills the rest of the report.
  void finish();
};

// Blank-separated tokens of a line, without allocating (ascii PLY records, OBJ statements).
struct Tokens {
  const char* p;
  const char* e;
  bool next(std::string_view& t) {
    while (p < e && text::isBlank(*p)) ++p;
    if (p == e) return false;
    const char* b = p;
    while (p < e && !text::isBlank(*p)) ++p;
    t = std::string_view(b, size_t(p - b));
    return true;
  }
};

// The format readers; both throw nestlight::Error naming `file` and the line or byte.
void readPly(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out);
void readObj(const std::string& file, const uint8_t* data, size_t size, MeshBuilder& out);

}  // namespace nestlight::gi::meshio
