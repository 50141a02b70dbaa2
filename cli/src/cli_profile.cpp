// `nestlight profile`.
#include <cstdio>
#include <sstream>

#include "cli.h"
#include "nestlight/converters/profile.h"
#include "nestlight/converters/progress.h"
#include "nestlight/octree/error.h"
#include "nestlight/octree/octree_reader.h"

namespace nestlight::cli {

namespace {

// "x0,y0,x1,y1,..." as plan-view vertices; names the value at fault.
std::vector<std::array<double, 2>> parseLine(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    double d = 0;
    try {
      d = std::stod(item, &used);
    } catch (...) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(d))
      throw Error("--line", "value " + std::to_string(v.size() + 1),
                  "expected a number, got '" + item + "'");
    v.push_back(d);
  }
  if (v.size() < 4 || v.size() % 2)
    throw Error("--line", "",
                "expected x0,y0,x1,y1[,x2,y2...] (pairs of plan coordinates, at least two), got " +
                    std::to_string(v.size()) + " numbers");
  std::vector<std::array<double, 2>> line;
  for (size_t i = 0; i < v.size(); i += 2) line.push_back({v[i], v[i + 1]});
  return line;
}

}  // namespace

void addProfile(CLI::App& app, int& exitCode) {
  auto* cmd = app.add_subcommand(
      "profile",
      "Cut a section along a line: every point within --width/2 of it, to a point file and a "
      "plot");
  cmd->footer(
      "The corridor is measured in plan (x, y) in the scan's own coordinates, at every height\n"
      "unless --z limits it. Every point of it is written, from every level of the octree (no\n"
      "cap), streamed node by node; nodes outside are never read. Outputs by extension (repeat\n"
      "-o for several): .las, .laz, .ply: the points with their attributes and a float64\n"
      "\"distance\" along the line; .png: the plot (distance along the line against height,\n"
      "seen from the line's right, nearest point on top); .svg: the plot with axes and labels.\n"
      "Example: nestlight profile nave.octree --line 12.5,3,12.5,40 --width 0.2 -o s.las -o s.svg");
  auto dir = std::make_shared<std::string>();
  auto line = std::make_shared<std::string>();
  auto width = std::make_shared<double>(0);
  auto outs = std::make_shared<std::vector<std::string>>();
  auto z = std::make_shared<std::vector<double>>();
  auto o = std::make_shared<ProfileOptions>();
  auto progress = std::make_shared<std::string>("auto");
  cmd->add_option("octree", *dir, "Octree folder")->required();
  cmd->add_option("--line", *line, "The line's plan vertices: x0,y0,x1,y1[,x2,y2...]")->required();
  cmd->add_option("--width", *width, "The corridor's full width (scan units)")
      ->required()
      ->check(CLI::PositiveNumber);
  cmd->add_option("-o,--output", *outs, "Output: .las, .laz, .ply (points) or .png, .svg (plot)")
      ->required();
  cmd->add_option("--z", *z, "Only heights in zmin,zmax")->delimiter(',')->expected(2);
  cmd->add_option("--image-width", o->imageWidth, "Plot width in pixels")
      ->check(CLI::Range(16, 16384))
      ->capture_default_str();
  cmd->add_option("--exaggeration", o->exaggeration, "Vertical scale against horizontal")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--colour", o->colour, "auto (rgb when present), rgb, elevation or intensity")
      ->check(CLI::IsMember({"auto", "rgb", "elevation", "intensity"}))
      ->capture_default_str();
  cmd->add_option("--progress", *progress, "auto, terminal, json or quiet")
      ->check(CLI::IsMember({"auto", "terminal", "json", "quiet"}))
      ->capture_default_str();
  cmd->callback([=, &exitCode]() {
    requireOctreeFolder(*dir, "profile");
    ProfileOptions opts = *o;
    opts.line = parseLine(*line);
    opts.width = *width;
    if (z->size() == 2) {
      if ((*z)[0] > (*z)[1]) throw Error("--z", "", "zmin is above zmax");
      opts.zMin = (*z)[0], opts.zMax = (*z)[1];
    }
    for (const auto& p : *outs) opts.outputs.emplace_back(p);
    Progress bar(parseProgress(*progress));
    opts.progress = &bar;
    const ProfileReport r = profileOctree(*dir, opts);
    std::printf("profile: %llu points within %g of a %.6g-long line", (unsigned long long)r.points,
                opts.width / 2, r.length);
    if (r.points)
      std::printf(" (along %.6g to %.6g, heights %.6g to %.6g)", r.alongMin, r.alongMax, r.zMin,
                  r.zMax);
    std::printf("; %llu nodes read, %llu outside never read\n", (unsigned long long)r.walk.nodes,
                (unsigned long long)r.walk.nodesSkipped);
    for (const auto& p : *outs) std::printf("  wrote %s\n", p.c_str());
    if (r.imageWidth)
      std::printf("  plot %d x %d px, coloured by %s\n", r.imageWidth, r.imageHeight,
                  r.colour.c_str());
    exitCode = 0;
  });
}

}  // namespace nestlight::cli
