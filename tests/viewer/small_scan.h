// Small scans for the headless splat tests: an XYZ text file (x y z r g b) converted by the real
// builder, and a render job that waits for the whole cut, without eye-dome lighting (so covered
// pixels are exactly those not of the background colour).
#pragma once

#include <filesystem>
#include <glm/glm.hpp>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/converters/builder.h"
#include "nestlight/converters/reader.h"
#include "nestlight/frame/camera.h"
#include "nestlight/viewer/headless.h"

namespace nestlight::viewer::test_scan {

// `xyz` converted into `name`.octree beside it, nodes of at most `maxNodePoints`.
inline std::filesystem::path convertXyz(const std::filesystem::path& xyz, const std::string& name,
                                        uint32_t maxNodePoints) {
  ReadOptions ro;
  ro.columns = "x,y,z,r,g,b";
  std::vector<std::unique_ptr<PointReader>> r;
  r.push_back(openReader(xyz.string(), ro));
  BuildOptions o;
  o.output = xyz.parent_path() / (name + ".octree");
  o.progress = ProgressMode::Quiet;
  o.maxNodePoints = maxNodePoints;
  buildOctree(std::move(r), o);
  return o.output;
}

// 128 x 96 from `eye` towards `target`, complete cut, no EDL.
inline RenderJob headlessJob(const std::filesystem::path& octree, const std::string& out,
                             const glm::dvec3& eye, const glm::dvec3& target) {
  RenderJob j;
  j.octree = octree;
  j.output = out;
  j.width = 128;
  j.height = 96;
  j.waitComplete = true;
  j.timeoutSeconds = 60;
  j.quiet = true;
  j.settings.edlStrength = 0;
  frame::Camera c;
  c.eye = eye;
  c.target = target;
  j.camera = c;
  return j;
}

}  // namespace nestlight::viewer::test_scan
