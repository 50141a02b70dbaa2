// Text helpers of the readers (PLY, XYZ/PTS/TXT, and the mesh readers' PLY and OBJ): number
// tokens, and strings for metadata. They live in octree, the library every reader links, so that
// gi's mesh reader shares them without linking the converters (and, through them, PCL).
//
// std::from_chars is the fast path: it neither allocates nor consults the locale, and in
// libstdc++ 12 it is fast_float. It leaves out two forms that scan files contain: a leading '+',
// and values beyond the type's range, which it reports instead of giving ±inf or 0 as strtod does.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace nestlight::text {

inline bool isBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && isBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && isBlank(s.back())) s.remove_suffix(1);
  return s;
}

// The non-empty runs of `line` between characters for which `separator` is true.
template <class IsSeparator>
std::vector<std::string_view> splitBy(std::string_view line, IsSeparator separator) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) ++i;
    size_t b = i;
    while (i < line.size() && !separator(line[i])) ++i;
    if (i > b) words.push_back(line.substr(b, i - b));
  }
  return words;
}

inline std::vector<std::string_view> splitWords(std::string_view line) {
  return splitBy(line, [](char c) { return isBlank(c); });
}

// The line of [d, d + size) that starts at `pos`, without its '\n', into `out`; moves `pos` to the
// next line. False when `pos` is at the end.
inline bool takeLine(const char* d, size_t size, size_t& pos, std::string_view& out) {
  if (pos >= size) return false;
  const char* b = d + pos;
  const char* nl = static_cast<const char*>(std::memchr(b, '\n', size - pos));
  const size_t len = nl ? size_t(nl - b) : size - pos;
  pos += nl ? len + 1 : len;
  out = std::string_view(b, len);
  return true;
}

// What fromChars made of a token.
enum class Parsed { Ok, Malformed, OutOfRange };

// std::from_chars over all of [b, e) after an optional leading '+', which it moves `b` past.
// OutOfRange: a well-formed token beyond T's range.
template <typename T>
inline Parsed fromChars(const char*& b, const char* e, T& v) {
  if (b != e && *b == '+') ++b;
  if (b == e) return Parsed::Malformed;
  auto r = std::from_chars(b, e, v);
  if (r.ptr != e) return Parsed::Malformed;
  if (r.ec == std::errc()) return Parsed::Ok;
  return r.ec == std::errc::result_out_of_range ? Parsed::OutOfRange : Parsed::Malformed;
}

// All of [b, e) as a double: "nan", "inf" and "infinity" (any case) included.
inline bool parseDouble(const char* b, const char* e, double& v) {
  const Parsed p = fromChars(b, e, v);
  if (p != Parsed::OutOfRange) return p == Parsed::Ok;
  // Rare: an overflow or underflow, which strtod resolves to ±inf or a (signed) zero. The token
  // is known to be a well-formed number here, so strtod reads all of it.
  std::string s(b, e);
  v = std::strtod(s.c_str(), nullptr);
  return true;
}

inline bool parseFloat(const char* b, const char* e, float& v) {
  const Parsed p = fromChars(b, e, v);
  if (p != Parsed::OutOfRange) return p == Parsed::Ok;
  double d;
  if (!parseDouble(b, e, d)) return false;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  v = std::fabs(d) > std::numeric_limits<float>::max() ? (d > 0 ? kInf : -kInf)
                                                       : static_cast<float>(d);
  return true;
}

// An integer token: optional sign, decimal digits, nothing else; false on overflow.
template <typename T>
inline bool parseInteger(const char* b, const char* e, T& v) {
  return fromChars(b, e, v) == Parsed::Ok;
}

// A token of arbitrary bytes, quoted for a message: binary or fuzzed input must not put control
// characters or megabytes into an error.
inline std::string quote(std::string_view s) {
  std::string q = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) q += (s[i] >= 0x20 && s[i] < 0x7f) ? s[i] : '?';
  if (s.size() > 40) q += "...";
  return q + "'";
}

// `s` as valid UTF-8, invalid bytes replaced by U+FFFD. Comments and names in scan files can hold
// any bytes (Latin-1 from old tools, or garbage), and nlohmann::json refuses to write a string
// that is not UTF-8, so whatever goes into the metadata passes through here.
inline std::string validUtf8(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  size_t i = 0;
  while (i < s.size()) {
    const auto c = uint8_t(s[i]);
    const size_t len = c < 0x80         ? 1
                       : (c >> 5) == 6  ? 2
                       : (c >> 4) == 14 ? 3
                       : (c >> 3) == 30 ? 4
                                        : 0;
    bool ok = len > 0 && len <= s.size() - i;
    uint32_t cp = len == 1 ? c : len == 2 ? c & 0x1f : len == 3 ? c & 0x0f : c & 0x07;
    for (size_t k = 1; ok && k < len; ++k) {
      const auto cc = uint8_t(s[i + k]);
      ok = (cc & 0xc0) == 0x80;
      cp = cp << 6 | (cc & 0x3f);
    }
    // No overlong forms, surrogates or code points beyond U+10FFFF.
    static constexpr uint32_t kMin[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (ok && len > 1) ok = cp >= kMin[len] && !(cp >= 0xd800 && cp <= 0xdfff) && cp <= 0x10ffff;
    if (ok) {
      out.append(s.substr(i, len));
      i += len;
    } else {
      out += "\xef\xbf\xbd";
      ++i;
    }
  }
  return out;
}

}  // namespace nestlight::text
