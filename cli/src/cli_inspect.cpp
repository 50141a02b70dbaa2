// `nestlight info` and `nestlight verify`.
#include <algorithm>
#include <cstdio>
#include <vector>

#include "cli.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/verify.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/crs.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/octree/spacing.h"

namespace nestlight::cli {

void addInfo(CLI::App& app, int& exitCode) {
  auto* cmd =
      app.add_subcommand("info", "Describe an octree: points, accounting, bounds, attributes");
  auto dir = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  cmd->add_option("octree", *dir, "Octree folder")->required();
  auto clip = std::make_shared<std::string>();
  auto level = std::make_shared<int>(-1);
  cmd->add_flag("--json", *json, "Print the metadata as JSON");
  cmd->add_option("--clip", *clip,
                  "Count the points that clipping volumes keep: a JSON file with a \"clipping\" "
                  "array (or a view state; docs/VIEWER.md). Nodes wholly inside are counted from "
                  "the hierarchy, the others read and tested point by point");
  cmd->add_option("--level", *level, "With --clip: only the nodes of this level (0 = root)");
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "info");
    OctreeReader r(*dir);
    const Metadata& m = r.metadata();
    std::optional<ClipSet> clipSet;
    nlohmann::json clipJson;
    if (*level >= 0 && clip->empty()) throw Error("--level needs --clip");
    if (!clip->empty()) {
      clipSet = ClipSet::load(*clip);
      ExportOptions o;
      o.clip = &*clipSet;
      if (*level >= 0) o.level = uint32_t(*level);
      const ExportReport c = countOctree(*dir, o);
      clipJson = {{"file", *clip},
                  {"points", c.points},
                  {"nodes_read", c.nodes - c.nodesWhole},
                  {"nodes_whole", c.nodesWhole},
                  {"nodes_skipped", c.nodesSkipped},
                  {"points_tested", c.pointsTested}};
    }
    if (*json) {
      nlohmann::json j = m.toJson();
      if (clipSet) j["clip"] = clipJson;
      std::printf("%s\n", j.dump(2).c_str());
      exitCode = 0;
      return;
    }
    const Accounting& a = m.accounting;
    std::printf("octree     %s (format version %d, %s)\n", dir->c_str(), m.version,
                m.generator.c_str());
    std::printf("points     %llu stored\n", (unsigned long long)m.points);
    std::printf("accounting %llu input = %llu kept + %llu duplicates merged + %llu rejected\n",
                (unsigned long long)a.input, (unsigned long long)a.kept,
                (unsigned long long)a.duplicatesMerged, (unsigned long long)a.rejectedTotal());
    for (auto& [why, n] : a.rejected)
      std::printf("           rejected %llu: %s\n", (unsigned long long)n, why.c_str());
    if (!m.bounds.empty())
      std::printf("bounds     [%.4f %.4f %.4f] - [%.4f %.4f %.4f]\n", m.bounds.min.x,
                  m.bounds.min.y, m.bounds.min.z, m.bounds.max.x, m.bounds.max.y, m.bounds.max.z);
    if (m.scale.x == m.scale.y && m.scale.y == m.scale.z)
      std::printf("grid       offset [%.4f %.4f %.4f], scale %.17g, cube %u steps (%.3f units)\n",
                  m.offset.x, m.offset.y, m.offset.z, m.scale.x, m.cubeSize, m.cubeWorldSize());
    else
      std::printf(
          "grid       offset [%.4f %.4f %.4f], scale per axis [%.17g %.17g %.17g], cube %u steps "
          "(%.3f units "
          "on its longest axis)\n",
          m.offset.x, m.offset.y, m.offset.z, m.scale.x, m.scale.y, m.scale.z, m.cubeSize,
          m.cubeWorldSize());
    if (m.build.is_object() && m.build.contains("notes") && m.build["notes"].is_array())
      for (const auto& n : m.build["notes"])
        if (n.is_string()) std::printf("           note: %s\n", n.get<std::string>().c_str());
    if (m.sourceOffset)
      std::printf("           the inputs' LAS offset [%.17g %.17g %.17g], written back by export\n",
                  m.sourceOffset->x, m.sourceOffset->y, m.sourceOffset->z);
    std::printf("tree       %llu nodes, depth %u, root spacing %g\n", (unsigned long long)m.nodes,
                m.depth, m.spacing);
    if (m.version >= 2) {  // version 1 measured nothing
      // Per level, the median over its nodes of the measured spacing (docs/FORMAT.md, byte 3):
      // how dense the scan really is where each level is the finest drawn. Reads the whole
      // hierarchy (kilobytes per thousand nodes).
      std::vector<std::vector<double>> perLevel(m.depth + 1);
      for (const auto& [key, e] : r.allNodes())
        if (const double s = measuredSpacing(m, key.level, e); s > 0 && key.level <= m.depth)
          perLevel[key.level].push_back(s);
      std::printf("spacing    measured (median per level):");
      for (size_t l = 0; l < perLevel.size(); ++l) {
        auto& v = perLevel[l];
        if (v.empty()) continue;
        std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
        std::printf(" L%zu %.4g", l, v[v.size() / 2]);
      }
      std::printf("\n");
    }
    std::printf("payload    %s (%.2f bytes/point), hierarchy %s, codec %s\n",
                humanBytes(double(m.payloadBytes)).c_str(),
                m.points ? double(m.payloadBytes) / m.points : 0.0,
                humanBytes(double(m.hierarchyBytes)).c_str(),
                m.build.value("codec", std::string("?")).c_str());
    std::printf("attributes");
    if (m.layout.size() == 0) std::printf(" none");
    for (const auto& at : m.layout.attributes())
      std::printf(" %s:%s%s", at.name.c_str(), scalarName(at.type),
                  at.components > 1 ? ("x" + std::to_string(at.components)).c_str() : "");
    std::printf("\n");
    for (const auto& l : m.layers) {
      std::printf("layer      %s: %s colour, %llu points in %llu nodes, %s (%s, %s)",
                  l.name.c_str(), l.kind == "colour" ? "linear RGB" : l.kind.c_str(),
                  (unsigned long long)l.points, (unsigned long long)l.nodes, l.encoding.c_str(),
                  l.file.c_str(), humanBytes(double(l.bytes)).c_str());
      if (l.scale != 1) std::printf(", values x %g", l.scale);
      std::printf("\n");
      if (l.build.is_object())
        for (const char* key : {"command", "mode", "photo", "exposure_log2", "expanded_points",
                                "infilled_points", "island_points", "max_luminance", "max_value",
                                "bounded_values", "exposure", "warnings"})
          if (l.build.contains(key))
            std::printf("           %s: %s\n", key, l.build[key].dump().c_str());
    }
    if (m.normalsEstimated)
      std::printf("normals    estimated (%s)\n", m.normalEstimation.dump().c_str());
    std::printf("crs        %s\n", describeCrs(m.crs).summary().c_str());
    if (clipSet)
      std::printf(
          "clip       %s: %llu points kept%s (%llu nodes tested point by point, %llu inside whole, "
          "%llu outside)\n",
          clip->c_str(), (unsigned long long)clipJson["points"].get<uint64_t>(),
          *level >= 0 ? (" at level " + std::to_string(*level)).c_str() : "",
          (unsigned long long)clipJson["nodes_read"].get<uint64_t>(),
          (unsigned long long)clipJson["nodes_whole"].get<uint64_t>(),
          (unsigned long long)clipJson["nodes_skipped"].get<uint64_t>());
    for (const auto& s : m.sources) {
      std::printf("source     %s (%s, %llu points)\n", s.path.c_str(), s.format.c_str(),
                  (unsigned long long)s.points);
      for (const auto& w : s.warnings) std::printf("           warning: %s\n", w.c_str());
    }
    exitCode = 0;
  });
}

void addVerify(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "verify",
      "Check an octree: structure, checksums, point accounting, points inside their nodes, "
      "attribute layers (HDR colour)");
  auto dir = std::make_shared<std::string>();
  cmd->add_option("octree", *dir, "Octree folder")->required();
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "verify");
    VerifyReport r = verifyOctree(*dir);
    for (const auto& f : r.failures) std::fprintf(stderr, "FAIL %s\n", f.c_str());
    for (const auto& n : r.notes) std::fprintf(stderr, "note %s\n", n.c_str());
    if (r.ok()) {
      std::printf("OK %s: %llu nodes, %llu points, %s of payload checked", dir->c_str(),
                  (unsigned long long)r.nodes, (unsigned long long)r.points,
                  humanBytes(double(r.payloadBytes)).c_str());
      if (r.layers) std::printf(", %llu layer(s) checked", (unsigned long long)r.layers);
      std::printf("\n");
      exitCode = 0;
    } else {
      std::fprintf(stderr, "verify failed: %zu problem(s) in %s\n", r.failures.size(),
                   dir->c_str());
      exitCode = kExitCheckFailed;
    }
  });
}

}  // namespace nestlight::cli
