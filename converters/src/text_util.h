// Number tokens of the text readers (PLY ascii, XYZ/PTS/TXT).
//
// std::from_chars is the fast path: it neither allocates nor consults the locale, and in
// libstdc++ 12 it is fast_float. It leaves out two forms that scan files contain: a leading '+',
// and values beyond the type's range, which it reports instead of giving ±inf or 0 as strtod does.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>

namespace nestlight::text {

inline bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// All of [b, e) as a double: "nan", "inf" and "infinity" (any case) included.
inline bool parseDouble(const char* b, const char* e, double& v) {
  if (b != e && *b == '+') ++b;
  if (b == e) return false;
  auto r = std::from_chars(b, e, v);
  if (r.ptr != e) return false;
  if (r.ec == std::errc()) return true;
  if (r.ec != std::errc::result_out_of_range) return false;
  // Rare: an overflow or underflow, which strtod resolves to ±inf or a (signed) zero. The token
  // is known to be a well-formed number here, so strtod reads all of it.
  std::string s(b, e);
  v = std::strtod(s.c_str(), nullptr);
  return true;
}

inline bool parseFloat(const char* b, const char* e, float& v) {
  if (b != e && *b == '+') ++b;
  if (b == e) return false;
  auto r = std::from_chars(b, e, v);
  if (r.ptr != e) return false;
  if (r.ec == std::errc()) return true;
  if (r.ec != std::errc::result_out_of_range) return false;
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
  if (b != e && *b == '+') ++b;
  if (b == e) return false;
  auto r = std::from_chars(b, e, v);
  return r.ptr == e && r.ec == std::errc();
}

}  // namespace nestlight::text
