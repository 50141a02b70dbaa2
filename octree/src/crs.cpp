#include "nestlight/octree/crs.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <memory>
#include <vector>

namespace nestlight {
namespace {

// WKT as a tree: KEYWORD[child, ...] where a child is a quoted string, a bare token (a number or
// an enumeration) or another keyword. WKT 1 and 2 share the syntax; both brackets are accepted.
struct WktNode {
  std::string keyword;
  std::vector<std::string> values;  // quoted strings and bare tokens, in order
  std::vector<WktNode> children;

  const WktNode* child(std::initializer_list<const char*> names) const {
    for (const WktNode& c : children)
      for (const char* n : names)
        if (c.keyword == n) return &c;
    return nullptr;
  }
};

class WktParser {
 public:
  explicit WktParser(const std::string& s) : s_(s) {}
  // nullptr on malformed text: a CRS that cannot be read is described as unnamed, never fatal.
  std::unique_ptr<WktNode> parse() {
    auto n = std::make_unique<WktNode>();
    if (!node(*n, 0)) return nullptr;
    return n;
  }

 private:
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool node(WktNode& n, int depth) {
    if (depth > 64) return false;
    skip();
    const size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_'))
      ++i_;
    n.keyword = s_.substr(start, i_ - start);
    std::transform(n.keyword.begin(), n.keyword.end(), n.keyword.begin(),
                   [](unsigned char c) { return std::toupper(c); });
    skip();
    if (n.keyword.empty() || i_ >= s_.size() || (s_[i_] != '[' && s_[i_] != '(')) return false;
    const char close = s_[i_] == '[' ? ']' : ')';
    ++i_;
    for (;;) {
      skip();
      if (i_ >= s_.size()) return false;
      if (s_[i_] == close) {
        ++i_;
        return true;
      }
      if (s_[i_] == ',') {
        ++i_;
        continue;
      }
      if (s_[i_] == '"') {
        std::string v;
        for (++i_; i_ < s_.size(); ++i_) {
          if (s_[i_] == '"') {
            if (i_ + 1 < s_.size() && s_[i_ + 1] == '"') {  // "" escapes a quote
              v += '"';
              ++i_;
              continue;
            }
            break;
          }
          v += s_[i_];
        }
        if (i_ >= s_.size()) return false;
        ++i_;
        n.values.push_back(std::move(v));
        continue;
      }
      // A bare token or a keyword with brackets.
      const size_t t = i_;
      while (i_ < s_.size() && s_[i_] != ',' && s_[i_] != close && s_[i_] != '[' && s_[i_] != '(' &&
             !std::isspace(static_cast<unsigned char>(s_[i_])))
        ++i_;
      size_t after = i_;
      while (after < s_.size() && std::isspace(static_cast<unsigned char>(s_[after]))) ++after;
      if (after < s_.size() && (s_[after] == '[' || s_[after] == '(')) {
        i_ = t;
        n.children.emplace_back();
        if (!node(n.children.back(), depth + 1)) return false;
      } else {
        n.values.push_back(s_.substr(t, i_ - t));
      }
    }
  }
  const std::string& s_;
  size_t i_ = 0;
};

bool isProjected(const std::string& k) {
  return k == "PROJCS" || k == "PROJCRS" || k == "PROJECTEDCRS";
}
bool isGeographic(const std::string& k) {
  return k == "GEOGCS" || k == "GEOGCRS" || k == "GEOGRAPHICCRS" || k == "GEODCRS" ||
         k == "GEODETICCRS";
}

int epsgOf(const WktNode& n) {
  for (const WktNode& c : n.children)
    if ((c.keyword == "AUTHORITY" || c.keyword == "ID") && c.values.size() >= 2 &&
        (c.values[0] == "EPSG" || c.values[0] == "epsg")) {
      try {
        return std::stoi(c.values[1]);
      } catch (...) {
        return 0;
      }
    }
  return 0;
}

// A linear unit from its name and factor to metres: the factor decides (names vary by writer:
// "Foot_US", "US survey foot", "foot_survey_us").
void setUnit(CrsInfo& info, const std::string& name, double factor) {
  info.metresPerUnit = factor;
  if (std::abs(factor - 1) < 1e-12)
    info.unitName = "metre";
  else if (std::abs(factor - 0.3048) < 1e-12)
    info.unitName = "foot";
  else if (std::abs(factor - 1200.0 / 3937.0) < 1e-12)
    info.unitName = "US survey foot";
  else
    info.unitName = name;
}

const WktNode* linearUnit(const WktNode& n) {
  if (const WktNode* u = n.child({"UNIT", "LENGTHUNIT"})) return u;
  // WKT 2 may state the unit per axis.
  for (const WktNode& c : n.children)
    if (c.keyword == "AXIS")
      if (const WktNode* u = c.child({"UNIT", "LENGTHUNIT"})) return u;
  if (const WktNode* cs = n.child({"CS"}))
    if (const WktNode* u = cs->child({"UNIT", "LENGTHUNIT"})) return u;
  return nullptr;
}

void fromWkt(CrsInfo& info, const std::string& wkt) {
  WktParser p(wkt);
  const std::unique_ptr<WktNode> root = p.parse();
  if (!root) return;
  if (!root->values.empty()) info.name = root->values[0];
  info.epsg = epsgOf(*root);
  // A compound CRS (horizontal + vertical): its horizontal part has the plan unit.
  const WktNode* horizontal = root.get();
  if (root->keyword == "COMPD_CS" || root->keyword == "COMPOUNDCRS")
    for (const WktNode& c : root->children)
      if (isProjected(c.keyword) || isGeographic(c.keyword)) {
        horizontal = &c;
        break;
      }
  if (isGeographic(horizontal->keyword)) {
    info.geographic = true;
    info.unitName = "degree";
    return;
  }
  if (const WktNode* u = linearUnit(*horizontal); u && u->values.size() >= 2) {
    try {
      setUnit(info, u->values[0], std::stod(u->values[1]));
    } catch (...) {
    }
  } else if (horizontal->keyword == "GEOCCS") {
    setUnit(info, "metre", 1);
  }
}

void fromGeoTiff(CrsInfo& info, const nlohmann::json& g) {
  if (!g.is_object() || !g.contains("keys") || !g["keys"].is_array()) return;
  const nlohmann::json& k = g["keys"];
  const std::string ascii =
      g.contains("ascii") && g["ascii"].is_string() ? g["ascii"].get<std::string>() : "";
  auto number = [&](size_t i) -> int64_t {
    return i < k.size() && k[i].is_number_integer() ? k[i].get<int64_t>() : -1;
  };
  const int64_t count = number(3);
  std::string citation;
  for (int64_t e = 0; e < count; ++e) {
    const size_t at = 4 + 4 * size_t(e);
    const int64_t id = number(at), location = number(at + 1), n = number(at + 2),
                  value = number(at + 3);
    if (id < 0 || location < 0) break;
    if (location == 0) {
      if (id == 3072 && value > 0 && value < 32767 && !info.epsg) info.epsg = int(value);
      if (id == 2048 && value > 0 && value < 32767 && !info.epsg) {
        info.epsg = int(value);
        info.geographic = true;
        if (info.unitName.empty()) info.unitName = "degree";
      }
      if (id == 3076 && info.metresPerUnit == 0) {
        if (value == 9001) setUnit(info, "metre", 1);
        if (value == 9002) setUnit(info, "foot", 0.3048);
        if (value == 9003) setUnit(info, "US survey foot", 1200.0 / 3937.0);
      }
    } else if (location == 34737 && (id == 3073 || id == 1026) && value >= 0 && n > 0 &&
               size_t(value) < ascii.size()) {
      std::string c = ascii.substr(size_t(value), size_t(n));
      while (!c.empty() && (c.back() == '|' || c.back() == '\0')) c.pop_back();
      if (id == 3073 || citation.empty()) citation = c;
    }
  }
  if (info.name.empty()) info.name = citation.substr(0, citation.find('|'));
}

}  // namespace

std::string CrsInfo::unitSymbol() const {
  if (unitName == "metre") return "m";
  if (unitName == "foot") return "ft";
  if (unitName == "US survey foot") return "US ft";
  if (unitName == "degree") return "deg";
  return unitName.empty() ? "units" : unitName;
}

std::string CrsInfo::summary() const {
  if (!known) return "none stated (coordinates in the inputs' own units)";
  std::string s = name.empty() ? "unnamed" : "\"" + name + "\"";
  if (epsg) s += " (EPSG:" + std::to_string(epsg) + ")";
  s += ", unit " + (unitName.empty() ? std::string("not stated") : unitName);
  if (metresPerUnit > 0 && unitName != "metre") {
    char b[64];
    std::snprintf(b, sizeof b, " (%.12g m)", metresPerUnit);
    s += b;
  }
  return s + ", from " + source;
}

CrsInfo describeCrs(const nlohmann::json& crs) {
  CrsInfo info;
  if (!crs.is_object() || crs.empty()) return info;
  const bool wkt = crs.contains("wkt") && crs["wkt"].is_string();
  const bool geotiff = crs.contains("geotiff");
  info.known = wkt || geotiff || crs.contains("epsg");
  info.source = wkt && geotiff ? "WKT and GeoTIFF keys"
                : wkt          ? "WKT"
                : geotiff      ? "GeoTIFF keys"
                               : "EPSG code";
  // WKT first (it names the unit with its factor); the keys fill in what it left unsaid.
  if (wkt) fromWkt(info, crs["wkt"].get<std::string>());
  if (geotiff) fromGeoTiff(info, crs["geotiff"]);
  if (!info.epsg && crs.contains("epsg") && crs["epsg"].is_number_integer())
    info.epsg = crs["epsg"].get<int>();
  return info;
}

}  // namespace nestlight
