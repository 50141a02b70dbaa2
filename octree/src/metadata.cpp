#include "nestlight/octree/metadata.h"

#include <cmath>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight {

using nlohmann::json;

void Accounting::add(const Accounting& o) {
  input += o.input;
  kept += o.kept;
  duplicatesMerged += o.duplicatesMerged;
  for (auto& [k, v] : o.rejected) rejected[k] += v;
}

Box3d Metadata::nodeBounds(uint32_t level, uint32_t x, uint32_t y, uint32_t z) const {
  const double steps = static_cast<double>(cubeSize >> level);
  Box3d b;
  b.min = {offset.x + x * steps * scale.x, offset.y + y * steps * scale.y,
           offset.z + z * steps * scale.z};
  b.max = {b.min.x + steps * scale.x, b.min.y + steps * scale.y, b.min.z + steps * scale.z};
  return b;
}

namespace {
json vec(const Vec3d& v) {
  return json::array({v.x, v.y, v.z});
}
json box(const Box3d& b) {
  return {{"min", vec(b.min)}, {"max", vec(b.max)}};
}

Vec3d vec3Of(const JsonField& f) {
  const auto v = f.vec3();
  return {v[0], v[1], v[2]};
}
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
    json js = {
        {"path", s.path}, {"format", s.format}, {"points", s.points}, {"warnings", s.warnings}};
    if (s.declaredPoints) js["declared_points"] = *s.declaredPoints;
    if (s.unreadable) js["unreadable"] = s.unreadable;
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
      // One number when the axes share it (as every octree before per-axis scales).
      {"scale", scale.x == scale.y && scale.y == scale.z ? json(scale.x) : vec(scale)},
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
  if (!layers.empty()) {
    json jl = json::array();
    for (const auto& l : layers)
      jl.push_back(
          {{"name", l.name},
           {"kind", l.kind},
           {"encoding", l.encoding},
           {"file", l.file},
           {"bytes", l.bytes},
           {"index",
            {{"offset", l.indexOffset}, {"bytes", l.indexBytes}, {"checksum", l.indexChecksum}}},
           {"nodes", l.nodes},
           {"points", l.points},
           {"scale", l.scale},
           {"build", l.build}});
    j["layers"] = jl;
  }
  if (sourceOffset) j["source_offset"] = vec(*sourceOffset);
  return j;
}

Metadata Metadata::fromJson(const json& j, const std::string& file) {
  if (!j.is_object()) throw Error(file, "", "metadata is not a JSON object");
  const JsonField f(j, "", file);
  Metadata m;
  if (f.at("format").string() != "nestlight-octree")
    f.at("format").fail("is not 'nestlight-octree'");
  const JsonField version = f.at("version");
  m.version = static_cast<int>(version.integer(0, 1 << 20));
  if (m.version < kOldestReadableVersion || m.version > kFormatVersion)
    version.fail("is " + std::to_string(m.version) + "; this build reads versions " +
                 std::to_string(kOldestReadableVersion) + " to " + std::to_string(kFormatVersion));
  if (j.contains("generator") && j["generator"].is_string()) m.generator = j["generator"];
  m.points = f.at("points").count();
  m.nodes = f.at("nodes").count();
  if (!f.at("bounds").value().is_null()) {
    m.bounds.min = vec3Of(f.at("bounds").at("min"));
    m.bounds.max = vec3Of(f.at("bounds").at("max"));
  }
  m.offset = vec3Of(f.at("offset"));
  if (j.contains("source_offset")) m.sourceOffset = vec3Of(f.at("source_offset"));
  if (f.at("scale").value().is_array()) {
    const auto v = f.at("scale").vec3(0, INFINITY);
    m.scale = {v[0], v[1], v[2]};
  } else {
    const double v = f.at("scale").number();
    m.scale = {v, v, v};
  }
  for (int a = 0; a < 3; ++a)
    if (!(m.scale[a] > 0) || !std::isfinite(m.scale[a])) f.at("scale").fail("must be positive");
  const uint64_t cube = f.at("cube_size").count();
  if (cube == 0 || cube > (uint64_t(1) << 31) || (cube & (cube - 1)))
    f.at("cube_size").fail("must be a power of two no larger than 2^31");
  m.cubeSize = static_cast<uint32_t>(cube);
  m.depth = static_cast<uint32_t>(f.at("depth").integer(0, 31));
  m.spacing = f.at("spacing").number();
  const JsonField attrs = f.at("attributes");
  for (size_t i = 0, n = attrs.arraySize(); i < n; ++i) {
    const JsonField a = attrs.at(i);
    Attribute attr;
    attr.name = a.at("name").string();
    auto t = parseScalarName(a.at("type").string());
    if (!t) a.at("type").fail("is not a known scalar type");
    attr.type = *t;
    attr.components = static_cast<uint32_t>(a.at("components").integer(1, 64));
    if (a.has("description") && a.value()["description"].is_string())
      attr.description = a.value()["description"];
    if (m.layout.has(attr.name)) a.at("name").fail("repeats attribute '" + attr.name + "'");
    m.layout.add(attr);
  }
  if (j.contains("rgb_source_bits") && j["rgb_source_bits"].is_number_integer())
    m.rgbSourceBits = j["rgb_source_bits"];
  if (j.contains("normals_estimated") && j["normals_estimated"].is_boolean())
    m.normalsEstimated = j["normals_estimated"];
  if (j.contains("normal_estimation")) m.normalEstimation = j["normal_estimation"];
  const JsonField acc = f.at("accounting");
  m.accounting.input = acc.at("input").count();
  m.accounting.kept = acc.at("kept").count();
  m.accounting.duplicatesMerged = acc.at("duplicates_merged").count();
  const JsonField rej = acc.at("rejected");
  if (!rej.value().is_object()) rej.fail("must be an object");
  for (auto it = rej.value().begin(); it != rej.value().end(); ++it)
    m.accounting.rejected[it.key()] = rej.at(it.key()).count();
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
      if (s.contains("unreadable") && s["unreadable"].is_number_unsigned())
        r.unreadable = s["unreadable"];
      if (s.contains("warnings") && s["warnings"].is_array())
        for (const auto& w : s["warnings"])
          if (w.is_string()) r.warnings.push_back(w);
      if (s.contains("details")) r.details = s["details"];
      m.sources.push_back(std::move(r));
    }
  }
  const JsonField pl = f.at("payload"), h = f.at("hierarchy");
  m.payloadFile = pl.at("file").string();
  m.payloadBytes = pl.at("bytes").count();
  m.hierarchyFile = h.at("file").string();
  m.hierarchyStep = static_cast<uint32_t>(h.at("step").integer(1, 8));
  m.hierarchyBytes = h.at("bytes").count();
  m.rootChunkSize = h.at("root_chunk_size").count();
  m.rootChunkChecksum = h.at("root_chunk_checksum").count();
  auto plainName = [](const JsonField& name) {
    const std::string n = name.string();
    if (n.empty() || n.find('/') != std::string::npos || n.find("..") != std::string::npos)
      name.fail("must be a plain file name inside the octree folder");
    return n;
  };
  plainName(pl.at("file"));
  plainName(h.at("file"));
  if (f.has("layers")) {
    const JsonField ls = f.at("layers");
    for (size_t i = 0, n = ls.arraySize(); i < n; ++i) {
      const JsonField l = ls.at(i);
      LayerRecord r;
      r.name = l.at("name").string();
      if (m.layer(r.name)) l.at("name").fail("repeats layer '" + r.name + "'");
      r.kind = l.at("kind").choice({"colour"});
      r.encoding = l.at("encoding").choice({"half_rgb_zstd"});
      r.file = plainName(l.at("file"));
      r.bytes = l.at("bytes").count();
      const JsonField idx = l.at("index");
      r.indexOffset = idx.at("offset").count();
      r.indexBytes = idx.at("bytes").count();
      r.indexChecksum = idx.at("checksum").count();
      if (r.indexOffset + r.indexBytes > r.bytes || r.indexOffset + r.indexBytes < r.indexOffset)
        idx.fail("lies beyond the layer file's " + std::to_string(r.bytes) + " bytes");
      r.nodes = l.at("nodes").count();
      r.points = l.at("points").count();
      r.scale = l.at("scale").number(1e-30, 1e30);
      if (l.has("build")) r.build = l.value()["build"];
      m.layers.push_back(std::move(r));
    }
  }
  return m;
}

}  // namespace nestlight
