// `nestlight render`: streams an octree headless and writes images, one still or a camera path.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/picking.h"
#include "nestlight/frame/point_view.h"
#include "nestlight/frame/view_state.h"
#include "nestlight/gi/camera_path.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::viewer {

struct RenderJob {
  std::filesystem::path octree;
  std::string output;  // .png or .exr; with a path, "%04d" (or _NNNN appended)
  int width = 1280, height = 720;
  std::optional<frame::Camera> camera;  // none: framing the scan from azimuth/elevation
  double azimuth = 35, elevation = 30, fovYDegrees = 60;
  std::optional<gi::CameraPath>
      path;              // a `--path` file (gi::loadCameraPath); its "fov" wins over fovYDegrees
  std::string statsCsv;  // per-frame stats, optional
  bool waitComplete = false;    // render a frame only once its cut is fully resident
  double timeoutSeconds = 120;  // for waitComplete
  int warmupFrames = 30;        // without waitComplete: streamer updates before a still
  frame::RenderSettings settings;
  streaming::Budgets budgets;
  std::optional<frame::ColourMode> colour;         // none: rgb when the scan has it, else elevation
  std::string colourLayer = frame::kHdrLayerName;  // the colour layer ColourMode::Hdr draws
  bool quiet = false;
  // Pixels to pick in the still (column, row from the top-left; the pixel's centre), each
  // answered in RenderedFrame::picks: the scan point under it (frame/picking.h).
  std::vector<std::array<double, 2>> picks;
  int pickRadius = 4;                          // the search window, pixels each side
  std::vector<frame::Annotation> annotations;  // drawn over the image (a view state's)
  std::vector<Measurement> measurements;       // likewise, with their values
};

struct RenderedFrame {
  std::string file;
  streaming::FrameStats stats;
  double msDraw = 0;
  bool complete = false;
  std::vector<std::optional<frame::PickedPoint>>
      picks;  // one per RenderJob::picks; none: background
};

// Opens the octree first (a bad or unknown-version octree fails before any GL work), then a
// headless context. Throws nestlight::Error.
std::vector<RenderedFrame> renderHeadless(const RenderJob& job);

}  // namespace nestlight::viewer
