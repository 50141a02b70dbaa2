// PLY header parsing: G. Turk, "The PLY Polygon File Format" (Stanford, 1994), with the keywords
// and type names of the rply/Stanford writers (uchar/uint8, float/float32, ...).
#include "nestlight/octree/ply_header.h"

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "nestlight/octree/error.h"
#include "nestlight/octree/text.h"

namespace nestlight::ply {

const char* encodingName(Encoding e) {
  switch (e) {
    case Encoding::Ascii:
      return "ascii";
    case Encoding::BinaryLittle:
      return "binary_little_endian";
    case Encoding::BinaryBig:
      return "binary_big_endian";
  }
  return "?";
}

bool Element::hasLists() const {
  return std::any_of(properties.begin(), properties.end(), [](auto& p) { return p.list; });
}

size_t Element::scalarBytes() const {
  size_t n = 0;
  for (auto& p : properties)
    if (!p.list) n += scalarSize(p.type);
  return n;
}

size_t Element::minBinaryBytes() const {
  size_t n = 0;
  for (auto& p : properties) n += scalarSize(p.list ? p.countType : p.type);
  return n;
}

bool nextDataLine(const char* d, size_t size, size_t& pos, uint64_t& line, std::string_view& out) {
  std::string_view l;
  while (text::takeLine(d, size, pos, l)) {
    ++line;
    for (char c : l)
      if (!text::isBlank(c)) {
        out = l;
        return true;
      }
  }
  return false;
}

Header parseHeader(const std::string& file, const uint8_t* data, size_t size) {
  const char* d = reinterpret_cast<const char*>(data);
  if (size == 0) throw Error(file, Error::atByte(0), "empty file");

  Header h;
  size_t pos = 0;
  uint64_t line = 0;
  std::string_view text;
  auto nextLine = [&]() {
    if (!text::takeLine(d, size, pos, text)) return false;
    ++line;
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    return true;
  };
  auto malformed = [&](const std::string& why) {
    return Error(file, Error::atLine(line), "malformed PLY header: " + why);
  };

  if (!nextLine() || text::trim(text) != "ply")
    throw Error(file, Error::atByte(0), "not a PLY file: the first line must be 'ply'");
  bool haveFormat = false, ended = false;
  while (!ended && nextLine()) {
    const auto w = text::splitWords(text);
    if (w.empty()) continue;
    const std::string_view kw = w[0];
    if (kw == "comment" || kw == "obj_info") {
      std::string_view rest = text::trim(text::trim(text).substr(kw.size()));
      (kw == "comment" ? h.comments : h.objInfo).push_back(text::validUtf8(rest));
    } else if (kw == "format") {
      if (haveFormat) throw malformed("a second 'format' line");
      if (w.size() != 3) throw malformed("expected 'format <encoding> 1.0'");
      if (w[1] == "ascii")
        h.encoding = Encoding::Ascii;
      else if (w[1] == "binary_little_endian")
        h.encoding = Encoding::BinaryLittle;
      else if (w[1] == "binary_big_endian")
        h.encoding = Encoding::BinaryBig;
      else
        throw malformed("unknown encoding " + text::quote(w[1]) +
                        "; expected ascii, binary_little_endian or binary_big_endian");
      if (w[2] != "1.0" && w[2] != "1")
        throw malformed("unsupported PLY version " + text::quote(w[2]) + "; only 1.0 exists");
      h.version = std::string(w[2]);
      haveFormat = true;
    } else if (kw == "element") {
      if (w.size() != 3) throw malformed("expected 'element <name> <count>'");
      Element e;
      e.name = text::validUtf8(w[1]);
      e.line = line;
      if (!text::parseInteger(w[2].data(), w[2].data() + w[2].size(), e.count))
        throw malformed("bad element count " + text::quote(w[2]));
      for (auto& o : h.elements)
        if (o.name == e.name) throw malformed("a second element " + text::quote(e.name));
      h.elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (h.elements.empty()) throw malformed("a property before any element");
      Property p;
      auto type = [&](std::string_view t) {
        auto s = parseScalarName(t);
        if (!s) throw malformed("unknown property type " + text::quote(t));
        return *s;
      };
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) throw malformed("expected 'property list <count type> <type> <name>'");
        p.list = true;
        p.countType = type(w[2]);
        p.countTypeName = std::string(w[2]);
        if (isFloat(p.countType)) throw malformed("a list count of type " + text::quote(w[2]));
        p.type = type(w[3]);
        p.typeName = std::string(w[3]);
        p.name = text::validUtf8(w[4]);
      } else {
        if (w.size() != 3) throw malformed("expected 'property <type> <name>'");
        p.type = type(w[1]);
        p.typeName = std::string(w[1]);
        p.name = text::validUtf8(w[2]);
      }
      auto& props = h.elements.back().properties;
      for (auto& o : props)
        if (o.name == p.name)
          throw malformed("a second property " + text::quote(p.name) + " in element " +
                          text::quote(h.elements.back().name));
      props.push_back(std::move(p));
    } else if (kw == "end_header") {
      ended = true;
    } else {
      throw malformed("unknown keyword " + text::quote(kw));
    }
  }
  if (!ended) throw malformed("no 'end_header' line");
  if (!haveFormat) throw malformed("no 'format' line");
  h.dataStart = pos;
  h.headerLines = line;
  return h;
}

std::optional<uint64_t> listCount(ScalarType t, const uint8_t* p, bool swap) {
  uint8_t tmp[8];
  const size_t n = scalarSize(t);
  if (swap && n > 1) {
    for (size_t i = 0; i < n; ++i) tmp[i] = p[n - 1 - i];
    p = tmp;
  }
  auto get = [p]<typename T>(T) -> std::optional<uint64_t> {
    T v;
    std::memcpy(&v, p, sizeof v);
    if constexpr (std::is_signed_v<T>)
      if (v < 0) return std::nullopt;
    return static_cast<uint64_t>(v);
  };
  switch (t) {
    case ScalarType::U8:
      return get(uint8_t());
    case ScalarType::I8:
      return get(int8_t());
    case ScalarType::U16:
      return get(uint16_t());
    case ScalarType::I16:
      return get(int16_t());
    case ScalarType::U32:
      return get(uint32_t());
    case ScalarType::I32:
      return get(int32_t());
    case ScalarType::U64:
      return get(uint64_t());
    case ScalarType::I64:
      return get(int64_t());
    default:
      return std::nullopt;
  }
}

}  // namespace nestlight::ply
