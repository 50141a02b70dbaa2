// `nestlight export`.
#include <cstdio>

#include "cli.h"
#include "nestlight/converters/export.h"

namespace nestlight::cli {

void addExport(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand("export", "Write an octree's points (all, or one level) to LAS or PLY");
  auto dir = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto level = std::make_shared<int>(-1);
  cmd->add_option("octree", *dir, "Octree folder")->required();
  cmd->add_option("-o,--output", *out, "Output file (.las or .ply)")->required();
  cmd->add_option("--level", *level, "Only the nodes of this level (0 = root)");
  cmd->callback([=, &exitCode]() {
    std::optional<uint32_t> l;
    if (*level >= 0) l = static_cast<uint32_t>(*level);
    uint64_t n = exportOctree(*dir, *out, l);
    std::printf("wrote %llu points to %s\n", (unsigned long long)n, out->c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
