// The window's heritage tools (viewer-internal): picking, measurements, annotations, clipping
// volumes and saving the view, with their panel section and their overlay. Every point placed is
// picked from the resident cut (frame/picking.h) and snapped to a real point of the scan; as
// finer nodes arrive each vertex snaps again to the point nearest where it was placed, so a
// measurement is never left on a coarse node's point when a nearer one is resident. Vertices are
// kept as coordinates: evicting their nodes changes nothing.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/frame/picking.h"
#include "nestlight/frame/point_view.h"
#include "nestlight/frame/view_state.h"
#include "nestlight/octree/measurement.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/viewer/window_app.h"

namespace nestlight::viewer {

class HeritageTools {
 public:
  enum class Tool {
    None,
    Pick,
    Distance,
    Polyline,
    Area,
    Height,
    Angle,
    Annotate,
    ClipPolygon,
    Profile
  };

  HeritageTools(const ViewerOptions& opt, OctreeReader& reader);

  // Chooses the tool by name ("pick", "distance", ..., "annotate", "clip-polygon"); throws
  // nestlight::Error for an unknown one.
  void setTool(const std::string& name);
  static std::vector<std::string> toolNames();

  // A click at pixel (x, y) (top-left origin) of the frame `view` last drew: picks, and places
  // the point with the current tool. Returns false when nothing was under the cursor.
  bool click(frame::PointView& view, const std::vector<streaming::DrawNode>& nodes,
             const frame::Camera& camera, int width, int height, double x, double y,
             const frame::RenderSettings& settings);
  // Snaps every vertex again when the drawn nodes changed (finer ones arrived).
  void refine(const std::vector<streaming::DrawNode>& nodes, const frame::RenderSettings& settings);
  // Finishes a polyline, an area or a clipping polygon being placed.
  void finish(frame::RenderSettings& settings);

  // The panel's section; `settings.clip` follows the clipping volumes.
  void panel(frame::RenderSettings& settings, const frame::Camera& camera, double extent);
  // Lines, points, values and labels over the window (Dear ImGui's foreground).
  void drawOverlay(const frame::Camera& camera, int width, int height) const;
  // The same into an image (screenshots).
  void drawInto(frame::Image& image, const frame::Camera& camera) const;

  // The view state of what is open now, as the panel's button and the key save it.
  frame::ViewState state(const frame::Camera& camera, frame::ColourMode colour,
                         const streaming::Budgets& budgets,
                         const frame::RenderSettings& settings) const;
  void save(const std::string& file, const frame::ViewState& state);
  const std::string& stateFile() const { return stateFile_; }
  std::string status;  // the last action, for the panel

  const std::vector<Measurement>& measurements() const { return measurements_; }
  size_t profilePoints() const { return profile_.size(); }

 private:
  struct Vertex {
    Vec3d target;                   // where it was placed: the surface under the cursor
    double snapDistance = 0;        // from target to the snapped point
    std::vector<NodeKey> searched;  // nodes already searched for it
  };
  void place(const frame::PickedPoint& p, const Vec3d& target);
  // The section along profileLine_ from the drawn nodes (the resident cut), for the panel's plot.
  void computeProfile(const std::vector<streaming::DrawNode>& nodes, const ClipSet* clip);
  void profilePanel();

  struct ProfilePoint {
    float along, z;
    uint32_t colour;  // ImU32
  };
  std::vector<std::array<double, 2>> profileLine_;  // 0, 1 or 2 plan points
  double profileWidth_ = 0;
  std::vector<ProfilePoint> profile_;
  bool profilePending_ = false;

  const ViewerOptions& opt_;
  OctreeReader& reader_;
  std::string unit_;
  Tool tool_ = Tool::None;
  std::vector<Measurement> measurements_;      // the last may be in progress
  std::vector<std::vector<Vertex>> vertices_;  // per measurement
  bool placing_ = false;                       // the last measurement is being placed
  std::vector<frame::Annotation> annotations_;
  std::vector<std::array<double, 2>> clipPolygon_;  // a polygon being placed
  ClipSet clipping_;
  std::optional<frame::PickedPoint> lastPick_;
  size_t drawnSignature_ = 0;
  char title_[128] = "note";
  std::string stateFile_;
};

}  // namespace nestlight::viewer
