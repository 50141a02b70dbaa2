// The header of a PLY file (G. Turk, "The PLY Polygon File Format", Stanford, 1994), shared by
// the scan reader in converters and the mesh reader in gi.
//
// A PLY header declares elements ("vertex", "face", ...) with their scalar and list properties;
// the data then holds every element's records in header order, as ascii (one record per line)
// or binary of either byte order. This parser knows nothing of what the elements mean: each
// reader decides which properties it wants and walks the rest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "nestlight/octree/attribute.h"

namespace nestlight::ply {

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

const char* encodingName(Encoding e);

struct Property {
  std::string name;
  std::string typeName;  // as the header spells it
  ScalarType type = ScalarType::U8;
  bool list = false;
  std::string countTypeName;
  ScalarType countType = ScalarType::U8;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  uint64_t line = 0;  // of its "element" line, for messages
  std::vector<Property> properties;

  bool hasLists() const;
  size_t scalarBytes() const;
  // The least a binary record can take: its scalars and its lists' counts.
  size_t minBinaryBytes() const;
};

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::string version;
  std::vector<std::string> comments;
  std::vector<std::string> objInfo;
  std::vector<Element> elements;
  size_t dataStart = 0;  // byte offset of the first record
  uint64_t headerLines = 0;
};

// Throws nestlight::Error naming `file` and the line of the fault. Names and comments come back
// as valid UTF-8 whatever bytes the file holds.
Header parseHeader(const std::string& file, const uint8_t* data, size_t size);

// A binary list's length stored as `t` at `p` (in the other byte order when `swap`); nullopt when
// negative, which is a malformed file rather than a short one.
std::optional<uint64_t> listCount(ScalarType t, const uint8_t* p, bool swap);

// The next line from `pos` that holds a non-blank character, into `out`; `line` counts every line
// passed. Ascii records are one per line and blank lines between them are allowed.
bool nextDataLine(const char* d, size_t size, size_t& pos, uint64_t& line, std::string_view& out);

}  // namespace nestlight::ply
