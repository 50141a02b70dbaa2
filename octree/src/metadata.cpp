#include "nestlight/octree/metadata.h"

#include <cmath>

#include "nestlight/octree/error.h"

namespace nestlight {

using nlohmann::json;

void Accounting::add(const Accounting& o) {
  input += o.input;
  kept += o.kept;
  duplicatesMerged += o.duplicatesMerged;
  for (auto& [k, v] : o.rejected) rejected[k] += v;
}

Box3d Metadata::nodeBounds(uint32_t level, uint32_t x, uint32_t y, uint32_t z) const {
  const double size = static_cast<double>(cubeSize >> level) * scale;
  Box3d b;
  b.min = {offset.x + x * size, offset.y + y * size, offset.z + z * size};
  b.max = {b.min.x + size, b.min.y + size, b.min.z + size};
  return b;
}

namespace {
json vec(const Vec3d& v) { return json::array({v.x, v.y, v.z}); }
json box(const Box3d& b) { return {{"min", vec(b.min)}, {"max", vec(b.max)}}; }

struct Field {
  const json& root;
  const std::string& file;
  [[noreturn]] void fail(const std::string& path, const std::string& why) const {
    throw Error(file, "field '" + path + "'", why);
  }
  const json& get(const json& obj, const std::string& key, const std::string& path) const {
    if (!obj.is_object() || !obj.contains(key)) fail(path, "is missing");
    return obj.at(key);
  }
  double number(const json& j, const std::string& path) const {
    if (!j.is_number()) fail(path, "must be a number");
    double v = j.get<double>();
    if (!std::isfinite(v)) fail(path, "must be finite");
    return v;
  }
  uint64_t count(const json& j, const std::string& path) const {
    if (!j.is_number_unsigned() && !(j.is_number_integer() && j.get<int64_t>() >= 0))
      fail(path, "must be a non-negative integer");
    return j.get<uint64_t>();
  }
  std::string string(const json& j, const std::string& path) const {
    if (!j.is_string()) fail(path, "must be a string");
    return j.get<std::string>();
  }
  Vec3d vec3(const json& j, const std::string& path) const {
    if (!j.is_array() || j.size() != 3) fail(path, "must be an array of 3 numbers");
    return {number(j[0], path + "[0]"), number(j[1], path + "[1]"), number(j[2], path + "[2]")};
  }
  Box3d box3(const json& j, const std::string& path) const {
    Box3d b;
    b.min = vec3(get(j, "min", path + ".min"), path + ".min");
    b.max = vec3(get(j, "max", path + ".max"), path + ".max");
    return b;
  }
};
}  // namespace

json Metadata::toJson() const {
  json attrs = json::array();
  for (const auto& a : layout.attributes()) {
    json ja = {{"name", a.name}, {"type", scalarName(a.type)}, {"components", a.components}};
    if (!a.description.empty()) ja["description"] = a.description;
    attrs.push_back(ja);
  }
  json rejected = json::object();
  for (auto& [k, v] : accounting.rejected) rejected[k] = v;
  json srcs = json::array();
  for (const auto& s : sources) {
    json js = {{"path", s.path}, {"format", s.format}, {"points", s.points},
               {"warnings", s.warnings}};
    if (s.declaredPoints) js["declared_points"] = *s.declaredPoints;
    if (!s.details.is_null()) js["details"] = s.details;
    srcs.push_back(js);
  }
  json j = {
      {"format", "nestlight-octree"},
      {"version", version},
      {"generator", generator},
      {"points", points},
      {"nodes", nodes},
      {"bounds", bounds.empty() ? json(nullptr) : box(bounds)},
      {"offset", vec(offset)},
      {"scale", scale},
      {"cube_size", cubeSize},
      {"depth", depth},
      {"spacing", spacing},
      {"attributes", attrs},
      {"rgb_source_bits", rgbSourceBits},
      {"normals_estimated", normalsEstimated},
      {"accounting",
       {{"input", accounting.input},
        {"kept", accounting.kept},
        {"duplicates_merged", accounting.duplicatesMerged},
        {"rejected", rejected},
        {"rejected_total", accounting.rejectedTotal()}}},
      {"crs", crs},
      {"sources", srcs},
      {"build", build},
      {"payload", {{"file", payloadFile}, {"bytes", payloadBytes}}},
      {"hierarchy",
       {{"file", hierarchyFile},
        {"step", hierarchyStep},
        {"bytes", hierarchyBytes},
        {"root_chunk_size", rootChunkSize},
        {"root_chunk_checksum", rootChunkChecksum}}},
  };
  if (normalsEstimated) j["normal_estimation"] = normalEstimation;
  return j;
}

Metadata Metadata::fromJson(const json& j, const std::string& file) {
  Field f{j, file};
  Metadata m;
  if (!j.is_object()) throw Error(file, "", "metadata is not a JSON object");
  if (f.string(f.get(j, "format", "format"), "format") != "nestlight-octree")
    f.fail("format", "is not 'nestlight-octree'");
  m.version = static_cast<int>(f.count(f.get(j, "version", "version"), "version"));
  if (m.version < kOldestReadableVersion || m.version > kFormatVersion)
    f.fail("version", "is " + std::to_string(m.version) + "; this build reads versions " +
                          std::to_string(kOldestReadableVersion) + " to " + std::to_string(kFormatVersion));
  if (j.contains("generator") && j["generator"].is_string()) m.generator = j["generator"];
  m.points = f.count(f.get(j, "points", "points"), "points");
  m.nodes = f.count(f.get(j, "nodes", "nodes"), "nodes");
  const json& b = f.get(j, "bounds", "bounds");
  if (!b.is_null()) m.bounds = f.box3(b, "bounds");
  m.offset = f.vec3(f.get(j, "offset", "offset"), "offset");
  m.scale = f.number(f.get(j, "scale", "scale"), "scale");
  if (!(m.scale > 0)) f.fail("scale", "must be positive");
  uint64_t cube = f.count(f.get(j, "cube_size", "cube_size"), "cube_size");
  if (cube == 0 || cube > (uint64_t(1) << 31) || (cube & (cube - 1)))
    f.fail("cube_size", "must be a power of two no larger than 2^31");
  m.cubeSize = static_cast<uint32_t>(cube);
  m.depth = static_cast<uint32_t>(f.count(f.get(j, "depth", "depth"), "depth"));
  if (m.depth > 31) f.fail("depth", "must be at most 31");
  m.spacing = f.number(f.get(j, "spacing", "spacing"), "spacing");
  const json& attrs = f.get(j, "attributes", "attributes");
  if (!attrs.is_array()) f.fail("attributes", "must be an array");
  for (size_t i = 0; i < attrs.size(); ++i) {
    std::string p = "attributes[" + std::to_string(i) + "]";
    Attribute a;
    a.name = f.string(f.get(attrs[i], "name", p + ".name"), p + ".name");
    auto t = parseScalarName(f.string(f.get(attrs[i], "type", p + ".type"), p + ".type"));
    if (!t) f.fail(p + ".type", "is not a known scalar type");
    a.type = *t;
    uint64_t c = f.count(f.get(attrs[i], "components", p + ".components"), p + ".components");
    if (c < 1 || c > 64) f.fail(p + ".components", "must be between 1 and 64");
    a.components = static_cast<uint32_t>(c);
    if (attrs[i].contains("description") && attrs[i]["description"].is_string())
      a.description = attrs[i]["description"];
    if (m.layout.has(a.name)) f.fail(p + ".name", "repeats attribute '" + a.name + "'");
    m.layout.add(a);
  }
  if (j.contains("rgb_source_bits") && j["rgb_source_bits"].is_number_integer())
    m.rgbSourceBits = j["rgb_source_bits"];
  if (j.contains("normals_estimated") && j["normals_estimated"].is_boolean())
    m.normalsEstimated = j["normals_estimated"];
  if (j.contains("normal_estimation")) m.normalEstimation = j["normal_estimation"];
  const json& acc = f.get(j, "accounting", "accounting");
  m.accounting.input = f.count(f.get(acc, "input", "accounting.input"), "accounting.input");
  m.accounting.kept = f.count(f.get(acc, "kept", "accounting.kept"), "accounting.kept");
  m.accounting.duplicatesMerged = f.count(
      f.get(acc, "duplicates_merged", "accounting.duplicates_merged"), "accounting.duplicates_merged");
  const json& rej = f.get(acc, "rejected", "accounting.rejected");
  if (!rej.is_object()) f.fail("accounting.rejected", "must be an object");
  for (auto it = rej.begin(); it != rej.end(); ++it)
    m.accounting.rejected[it.key()] = f.count(it.value(), "accounting.rejected." + it.key());
  if (j.contains("crs")) m.crs = j["crs"];
  if (j.contains("build")) m.build = j["build"];
  if (j.contains("sources") && j["sources"].is_array()) {
    for (const auto& s : j["sources"]) {
      SourceRecord r;
      if (s.contains("path") && s["path"].is_string()) r.path = s["path"];
      if (s.contains("format") && s["format"].is_string()) r.format = s["format"];
      if (s.contains("points") && s["points"].is_number_unsigned()) r.points = s["points"];
      if (s.contains("declared_points") && s["declared_points"].is_number_unsigned())
        r.declaredPoints = s["declared_points"].get<uint64_t>();
      if (s.contains("warnings") && s["warnings"].is_array())
        for (const auto& w : s["warnings"])
          if (w.is_string()) r.warnings.push_back(w);
      if (s.contains("details")) r.details = s["details"];
      m.sources.push_back(std::move(r));
    }
  }
  const json& pl = f.get(j, "payload", "payload");
  m.payloadFile = f.string(f.get(pl, "file", "payload.file"), "payload.file");
  m.payloadBytes = f.count(f.get(pl, "bytes", "payload.bytes"), "payload.bytes");
  const json& h = f.get(j, "hierarchy", "hierarchy");
  m.hierarchyFile = f.string(f.get(h, "file", "hierarchy.file"), "hierarchy.file");
  m.hierarchyStep = static_cast<uint32_t>(f.count(f.get(h, "step", "hierarchy.step"), "hierarchy.step"));
  if (m.hierarchyStep < 1 || m.hierarchyStep > 8) f.fail("hierarchy.step", "must be 1..8");
  m.hierarchyBytes = f.count(f.get(h, "bytes", "hierarchy.bytes"), "hierarchy.bytes");
  m.rootChunkSize = f.count(f.get(h, "root_chunk_size", "hierarchy.root_chunk_size"),
                            "hierarchy.root_chunk_size");
  m.rootChunkChecksum = f.count(f.get(h, "root_chunk_checksum", "hierarchy.root_chunk_checksum"),
                                "hierarchy.root_chunk_checksum");
  for (const std::string* name : {&m.payloadFile, &m.hierarchyFile})
    if (name->find('/') != std::string::npos || name->find("..") != std::string::npos)
      f.fail("payload.file", "must be a plain file name inside the octree folder");
  return m;
}

}  // namespace nestlight
