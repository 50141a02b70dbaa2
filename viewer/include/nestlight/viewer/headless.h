// `nestlight render`: streams an octree headless and writes images, one still or a camera path.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/streaming/streamer.h"
#include "nestlight/viewer/camera.h"
#include "nestlight/viewer/frame_renderer.h"
#include "nestlight/frame/gl_node_store.h"

namespace nestlight::viewer {

// A camera path: keyframes at times (seconds), eye and target linearly interpolated, sampled at
// `fps`. JSON: {"fps": 30, "fov": 60, "keyframes": [{"time": 0, "eye": [x,y,z], "target": [x,y,z]}, ...]}
struct CameraPath {
  struct Key {
    double time = 0;
    glm::dvec3 eye{0}, target{0};
  };
  double fps = 30;
  double fovYDegrees = 60;
  std::vector<Key> keys;
  // Throws nestlight::Error naming the file and the field at fault.
  static CameraPath load(const std::string& path);
  int frames() const;
  Camera at(int frame) const;
};

struct RenderJob {
  std::filesystem::path octree;
  std::string output;                 // .png or .exr; with a path, "%04d" (or _NNNN appended)
  int width = 1280, height = 720;
  std::optional<Camera> camera;       // none: framing the scan from azimuth/elevation
  double azimuth = 35, elevation = 30, fovYDegrees = 60;
  std::optional<CameraPath> path;
  std::string statsCsv;               // per-frame stats, optional
  bool waitComplete = false;          // render a frame only once its cut is fully resident
  double timeoutSeconds = 120;        // for waitComplete
  int warmupFrames = 30;              // without waitComplete: streamer updates before a still
  RenderSettings settings;
  streaming::Budgets budgets;
  std::optional<frame::ColourMode> colour;   // none: rgb when the scan has it, else elevation
  bool quiet = false;
};

struct RenderedFrame {
  std::string file;
  streaming::FrameStats stats;
  double msDraw = 0;
  bool complete = false;
};

// Opens the octree first (a bad or unknown-version octree fails before any GL work), then a
// headless context. Throws nestlight::Error.
std::vector<RenderedFrame> renderHeadless(const RenderJob& job);

}  // namespace nestlight::viewer
