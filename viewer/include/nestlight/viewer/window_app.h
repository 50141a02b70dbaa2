// `nestlight view`: the interactive viewer (GLFW window, Dear ImGui panel).
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/gi/scene.h"
#include "nestlight/viewer/headless.h"

namespace nestlight::viewer {

struct ViewerOptions {
  std::filesystem::path octree;
  int width = 1280, height = 800;
  std::optional<frame::Camera> camera;  // none: framing the scan from azimuth/elevation
  double azimuth = 35, elevation = 30, fovYDegrees = 60;
  frame::RenderSettings settings;
  streaming::Budgets budgets;
  std::optional<frame::ColourMode> colour;
  std::string colourLayer = frame::kHdrLayerName;  // what ColourMode::Hdr draws
  // A scene file (`nestlight view scene.json`): its gi.method (the command line's --method,
  // variant and parameters applied) renders the window, a GL method in real time, the path tracer
  // progressively; the panel switches between every registered method, variant and parameter
  // (re-making the method), and the point view stays one click away. The panel's state is kept in
  // $XDG_CONFIG_HOME/nestlight/imgui.ini (else ~/.config/nestlight/).
  std::shared_ptr<const gi::Scene> scene;
  bool startWithPoints = false;  // with a scene: open on the point view instead of the method
  // Scripted runs (tests, demos): stop after this many frames (0: run until closed), turn the
  // orbit camera by this many degrees per frame, and save a screenshot at the end (a progressive
  // view once it holds the scene's samples per pixel, --spp).
  int frames = 0;
  double orbitDegreesPerFrame = 0;
  std::string screenshot;
  // A view state's annotations (drawn as labels), and the file it came from (the panel's "Save
  // view" writes there by default; else view.json beside the octree).
  std::vector<frame::Annotation> annotations;
  std::vector<Measurement> measurements;
  std::string stateFile;
  // Scripted use of the tools (tests, reproducible figures): the tool the clicks use ("distance",
  // "annotate", ...; HeritageTools), clicks at pixels (one per frame once the cut is complete),
  // and the view state saved after the last frame, as the panel's button saves it.
  std::string tool;
  std::vector<std::array<double, 2>> clicks;
  std::string saveState;
};

// The names --tool takes.
std::vector<std::string> toolNames();

// Returns the process exit code. Throws nestlight::Error when no window can be opened.
int runViewer(const ViewerOptions& options);

}  // namespace nestlight::viewer
