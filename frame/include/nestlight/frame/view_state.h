// A view state: everything needed to come back to a view or hand it to a colleague, in one JSON
// file (docs/VIEWER.md, "View states"): the camera, the colouring, the streaming budgets, the
// splatting, the clipping volumes, the measurements, the annotations and the GI method with its
// parameters, plus the bounds and CRS of the octree it was saved from (loading it on another
// octree warns when the two do not overlap). Validated like scene files: errors name the field
// (`view.json: camera.eye[2]: expected a number, got string`). Fields left out keep their
// defaults, so a hand-written state may hold only a camera, or only clipping volumes (the
// `clipping` array is the same one `export --clip` reads).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/point_view.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/geometry.h"
#include "nestlight/octree/measurement.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::frame {

// A label at a point of the scan: a title shown in the view and a text shown on demand.
struct Annotation {
  Vec3d position;  // world coordinates (the source's system)
  std::string title;
  std::string text;
};

struct ViewState {
  static constexpr int kVersion = 1;

  std::string octree;                 // the octree's folder when saved (informative)
  std::optional<Box3d> octreeBounds;  // its bounds when saved
  std::string crs;                    // its CRS summary when saved (informative)

  std::optional<Camera> camera;
  std::optional<ColourMode> colour;
  std::string colourLayer = kHdrLayerName;
  streaming::Budgets budgets;
  RenderSettings settings;
  ClipSet clipping;
  std::vector<Measurement> measurements;
  std::vector<Annotation> annotations;
  nlohmann::json gi;  // {"method": "...", "parameters": {...}}: checked by the GI registry

  // Throws nestlight::Error naming `file` and the field.
  static ViewState fromJson(const nlohmann::json& j, const std::string& file);
  static ViewState load(const std::filesystem::path& file);
  nlohmann::json toJson() const;
  // Written beside `file` and renamed over it: a crash never leaves half a state.
  void save(const std::filesystem::path& file) const;
  // A warning when the state was saved from an octree whose bounds do not overlap `bounds`; empty
  // when they overlap or the state does not say.
  std::string boundsWarning(const Box3d& bounds) const;
};

}  // namespace nestlight::frame
