// `nestlight export`.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "nestlight/converters/export.h"
#include "nestlight/converters/potree_export.h"
#include "nestlight/converters/progress.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/error.h"

namespace nestlight::cli {
namespace fs = std::filesystem;

namespace {

// The format -o implies: its extension, or potree for a directory or a name without extension.
std::string formatOf(const std::string& out) {
  const fs::path p(out);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".las") return "las";
  if (ext == ".laz") return "laz";
  if (ext == ".ply") return "ply";
  std::error_code ec;
  if (ext.empty() || fs::is_directory(p, ec)) return "potree";
  throw Error(out, "",
              "cannot tell the output format from the extension '" + ext +
                  "': name a .las, .laz or .ply file, or a directory, or pass --format "
                  "las|laz|ply|potree");
}

}  // namespace

void addExport(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "export",
      "Write an octree's points to LAS, LAZ or PLY (all, or one level), or as a Potree 2.0 "
      "dataset");
  cmd->footer(
      "Formats: las, laz (LASzip; point formats 0-3 and 6-8; docs/LAZ.md) and ply write one file "
      "of\n"
      "points (all nodes, or --level N). potree writes a directory that the Potree web viewer\n"
      "(1.8 and later) opens: metadata.json, hierarchy.bin and octree.bin, with the octree's own\n"
      "nodes and sampling (no reconversion) and positions exact in its integer grid. Without\n"
      "--format the format follows -o: .las, .laz, .ply, else (a directory or a name without\n"
      "extension) potree. An existing non-empty directory is refused unless --force.\n"
      "Attribute mapping and limits: docs/POTREE_EXPORT.md.");
  auto dir = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto level = std::make_shared<int>(-1);
  auto format = std::make_shared<std::string>();
  auto force = std::make_shared<bool>(false);
  auto progress = std::make_shared<std::string>("auto");
  auto potree = std::make_shared<PotreeExportOptions>();
  cmd->add_option("octree", *dir, "Octree folder")->required();
  cmd->add_option("-o,--output", *out, "Output file (.las, .laz, .ply) or directory (potree)")
      ->required();
  cmd->add_option("--format", *format, "las, laz, ply or potree (default: from -o)")
      ->check(CLI::IsMember({"las", "laz", "ply", "potree"}));
  auto clip = std::make_shared<std::string>();
  cmd->add_option("--level", *level, "las/laz/ply: only the nodes of this level (0 = root)");
  cmd->add_option("--clip", *clip,
                  "las/laz/ply: only the points that clipping volumes keep, from every level: a "
                  "JSON file with a\n\"clipping\" array of boxes, polygons and corridors, or a "
                  "view state saved by the viewer\n(docs/VIEWER.md). Streams node by node; nodes "
                  "outside are never read");
  cmd->add_flag(
      "--force", *force,
      "potree: write into a non-empty directory: its Potree files are replaced by a dataset built "
      "beside\n"
      "it and swapped in when complete (a failure leaves the old one), its other files are kept");
  cmd->add_option("--hierarchy-step", potree->stepSize, "potree: levels per hierarchy chunk")
      ->check(CLI::Range(1u, 16u))
      ->capture_default_str();
  cmd->add_option("--name", potree->name,
                  "potree: dataset name (default: the octree folder's name)");
  cmd->add_option("--threads", potree->threads, "potree: nodes decoded in parallel (0: all cores)")
      ->capture_default_str();
  cmd->add_option("--progress", *progress, "auto, terminal, json or quiet")
      ->check(CLI::IsMember({"auto", "terminal", "json", "quiet"}))
      ->capture_default_str();
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "export");
    const std::string f = format->empty() ? formatOf(*out) : *format;
    if (f == "potree") {
      if (*level >= 0)
        throw Error(
            "--level does not apply to --format potree: a Potree dataset holds every level");
      if (!clip->empty())
        throw Error(
            "--clip does not apply to --format potree (a clipped Potree dataset needs a new "
            "octree: export --clip to LAS and convert that)");
      PotreeExportOptions o = *potree;
      o.overwrite = *force;
      o.progress = parseProgress(*progress);
      PotreeExportReport r = exportPotree(*dir, *out, o);
      std::printf("wrote %llu points in %llu nodes to %s (Potree 2.0: %llu hierarchy chunks, %s)\n",
                  (unsigned long long)r.points, (unsigned long long)r.nodes, out->c_str(),
                  (unsigned long long)r.chunks,
                  humanBytes(double(r.octreeBytes + r.hierarchyBytes)).c_str());
      for (const auto& a : r.attributes) {
        std::string names;
        for (const auto& n : a.potree) names += (names.empty() ? "" : ", ") + n;
        std::printf("  %-20s -> %s (%s)%s%s\n", a.source.c_str(), names.c_str(), a.type.c_str(),
                    a.note.empty() ? "" : ": ", a.note.c_str());
      }
      if (r.rgbLifted)
        std::printf("  %llu dark 16-bit colour components (1..255) written as 256\n",
                    (unsigned long long)r.rgbLifted);
      exitCode = 0;
      return;
    }
    // las, laz, ply: the writer follows the extension, which must agree with --format.
    const std::string ext = fs::path(*out).extension().string();
    std::string lower = ext;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    if (lower != "." + f)
      throw Error(*out, "", "--format " + f + " needs an output file ending in ." + f);
    ExportOptions o;
    if (*level >= 0) o.level = static_cast<uint32_t>(*level);
    std::optional<ClipSet> clipSet;
    if (!clip->empty()) {
      clipSet = ClipSet::load(*clip);
      o.clip = &*clipSet;
    }
    Progress bar(parseProgress(*progress));
    o.progress = &bar;
    const ExportReport r = exportOctree(*dir, *out, o);
    std::printf("wrote %llu points to %s\n", (unsigned long long)r.points, out->c_str());
    if (clipSet)
      std::printf(
          "  clipped by %s: %llu nodes tested point by point, %llu inside whole, %llu "
          "outside (never read)\n",
          clip->c_str(), (unsigned long long)(r.nodes - r.nodesWhole),
          (unsigned long long)r.nodesWhole, (unsigned long long)r.nodesSkipped);
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
