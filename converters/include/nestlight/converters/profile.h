// `nestlight profile`: a section through a scan along a polyline with a width. Every point of the
// corridor (no cap: streamed node by node from every level) goes to a point file with its
// distance along the line, and a plot shows distance against height, coloured as in the viewer.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "nestlight/converters/export.h"

namespace nestlight {

struct ProfileOptions {
  std::vector<std::array<double, 2>> line;  // plan-view vertices, world coordinates
  double width = 1;                         // the corridor: within width / 2 of the line
  double zMin = -std::numeric_limits<double>::infinity();
  double zMax = std::numeric_limits<double>::infinity();
  // .las, .laz, .ply: the points, with a float64 attribute "distance" (along the line); .png:
  // the plot; .svg: the plot with axes, ticks and labels (the points embedded as a PNG).
  std::vector<std::filesystem::path> outputs;
  int imageWidth = 1600;        // plot pixels along the line
  double exaggeration = 1;      // vertical scale against horizontal
  std::string colour = "auto";  // rgb, elevation, intensity; auto: rgb when the scan has it
  std::string unit;             // axis labels; empty: the octree's CRS unit ("units" if none)
  Progress* progress = nullptr;
  unsigned threads = 0;
};

struct ProfileReport {
  uint64_t points = 0;
  double length = 0;                                      // of the line
  double zMin = 0, zMax = 0, alongMin = 0, alongMax = 0;  // of the points kept (0 when none)
  int imageWidth = 0, imageHeight = 0;
  std::string colour;  // what the plot was coloured by
  std::string unit;    // what its axes are labelled in
  ExportReport walk;   // the first pass's
};

// Throws nestlight::Error: a line of fewer than 2 distinct points, a width that is not positive,
// an output whose extension names no format.
ProfileReport profileOctree(const std::filesystem::path& dir, const ProfileOptions& options);

}  // namespace nestlight
