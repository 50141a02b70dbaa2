// Picking: the scan point under a pixel, from the resident cut. The GPU's depth buffer says
// whether anything was drawn near the cursor and how far away (PointView::depthWindow, a small
// window read back); then the drawn nodes within that window's depths are read from the octree
// itself and, of their points that are seen (not behind what was drawn at their pixel), the one
// nearest the cursor wins. Its coordinates come from the
// octree's integers (offset + integer x scale, in double), never from the GPU's floats, so a
// national-grid scan picks to the source's precision; its attributes come with it.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/octree/clip_volume.h"
#include "nestlight/octree/node_key.h"
#include "nestlight/octree/octree_reader.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::frame {

struct PickedPoint {
  Vec3d position;  // world coordinates, the source's system
  NodeKey node;    // the drawn node that holds it
  uint32_t index = 0;
  double pixelDistance = 0;   // from the cursor, pixels
  double depth = 0;           // along the view direction, world units
  nlohmann::json attributes;  // name: value, or [values] for several components

  // "x y z" with the digits the octree's scale holds, e.g. "512345.678 5412345.123 310.250".
  std::string coordinates(const Vec3d& scale) const;
};

// The linear depths drawn in a window of the last frame (PointView::depthWindow): world units
// along the view, +infinity where only background shows. Image pixels, top-left origin.
struct DepthWindow {
  int x0 = 0, y0 = 0, width = 0, height = 0;
  std::vector<double> depth;
  // +infinity outside the window.
  double at(int x, int y) const;
  double nearest() const;
  double farthestDrawn() const;  // the largest finite depth; 0 when none
};

struct PickOptions {
  int windowRadius = 4;  // pixels each side of the cursor (a 9 x 9 window)
  // The splats' sizing (RenderSettings): a point counts as seen when it lies within its own
  // splat's size behind the depth drawn at its pixel.
  double sizeScale = 2.25, minPointSize = 2, maxPointSize = 64, fixedPointSize = 0;
  const ClipSet* clip = nullptr;  // points the clipping volumes hide are never picked
};

// The point nearest the pixel position (x, y) (pixel units from the top-left corner; pixel
// centres at .5) among the points of `nodes` that project into the window and are seen there: no
// deeper than the depth drawn at their own pixel plus their splat's size. Ties in distance go to
// the nearer point, then the lower node key and index, so a pick is repeatable. None when no point
// qualifies (background).
std::optional<PickedPoint> pickPoint(OctreeReader& reader,
                                     const std::vector<streaming::DrawNode>& nodes,
                                     const Camera& camera, int width, int height, double x,
                                     double y, const DepthWindow& depths,
                                     const PickOptions& options = {});

// The point of `nodes` nearest `target` in 3D within `maxDistance` (kept by `clip` when given):
// what a measurement's vertex snaps to, again as finer nodes arrive. `skip` lists nodes already
// searched for this target (their points cannot be nearer than what was found); the nodes searched
// now are appended to it. None when no point lies that close.
std::optional<PickedPoint> nearestPoint(OctreeReader& reader,
                                        const std::vector<streaming::DrawNode>& nodes,
                                        const Vec3d& target, double maxDistance,
                                        const ClipSet* clip, std::vector<NodeKey>* skip = nullptr);

// The attributes of point `i` of `buffer` as JSON (the layout's names; rgb as 3 numbers).
nlohmann::json pointAttributes(const PointLayout& layout, const PointBuffer& buffer, size_t i);
// Those attributes as one line, "name value, ...", as the viewer's panel and `render --pick` print
// them.
std::string describeAttributes(const nlohmann::json& attributes);

}  // namespace nestlight::frame
