// Clipping volumes: the regions a user keeps or removes (an oriented box around a chapel, a
// polygon drawn on a plan and extruded, the corridor of a profile), tested in the source's world
// coordinates in double precision so that national-grid eastings clip to the source's precision.
//
// The same set clips the viewer's rasterisers, `export --clip` and `info --clip`, so a region
// exported is exactly the region seen. File format (docs/VIEWER.md, "Clipping volumes"): a JSON
// object with a "clipping" array, which is also a view state's field, so a saved view clips an
// export directly:
//   {"clipping": [{"type": "box", "center": [x, y, z], "size": [sx, sy, sz],
//                  "rotation": [rx, ry, rz], "mode": "inside"},
//                 {"type": "polygon", "points": [[x, y], ...], "z": [zmin, zmax]},
//                 {"type": "corridor", "points": [[x, y], ...], "width": w}]}
#pragma once

#include <array>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/octree/geometry.h"

namespace nestlight {

class JsonField;

// How much of a box a volume (or a set) keeps. Node culling: None skips a node and its subtree,
// All keeps every point without testing one, Partial tests each. Conservative: Partial whenever
// the cheap tests cannot decide, never None or All wrongly.
enum class Overlap { None, Partial, All };

struct ClipVolume {
  enum class Kind { Box, Polygon, Corridor };
  enum class Mode { Inside, Outside };
  Kind kind = Kind::Box;
  Mode mode = Mode::Inside;

  // Box: centre, half extents along its own axes, and those axes in world coordinates
  // (orthonormal, from "rotation": degrees about x, then y, then z).
  Vec3d center;
  Vec3d half;
  std::array<Vec3d, 3> axes{Vec3d{1, 0, 0}, Vec3d{0, 1, 0}, Vec3d{0, 0, 1}};
  std::array<double, 3> rotationDegrees{0, 0, 0};  // as given, written back by toJson

  // Polygon and corridor: vertices in the world XY plane (plan view) and the z range kept.
  // A polygon is simple (no edge crosses another; checked on load) and implicitly closed.
  std::vector<std::array<double, 2>> points;
  double zMin = -std::numeric_limits<double>::infinity();
  double zMax = std::numeric_limits<double>::infinity();
  // Corridor: points whose plan-view distance to the polyline is at most width / 2.
  double width = 0;

  // Inside the volume itself (before its mode): the box and the corridor with their boundaries;
  // the polygon by the even-odd rule with half-open edges, so that a point on an edge shared by
  // two adjacent polygons belongs to exactly one of them.
  bool contains(const Vec3d& p) const;
  Overlap overlap(const Box3d& box) const;  // of the volume itself, before its mode

  // Corridor: distance along the polyline of the point's nearest position on it (before the
  // first vertex negative, beyond the last past the length), and the polyline's length.
  double along(const Vec3d& p) const;
  // The same and the signed plan distance from the nearest segment (positive left of the line's
  // direction), in one search: {along, across}.
  std::array<double, 2> alongAcross(const Vec3d& p) const;
  double length() const;

  static ClipVolume box(const Vec3d& center, const Vec3d& size,
                        const std::array<double, 3>& rotationDegrees = {0, 0, 0});
  static ClipVolume polygon(std::vector<std::array<double, 2>> points,
                            double zMin = -std::numeric_limits<double>::infinity(),
                            double zMax = std::numeric_limits<double>::infinity());
  static ClipVolume corridor(std::vector<std::array<double, 2>> points, double width,
                             double zMin = -std::numeric_limits<double>::infinity(),
                             double zMax = std::numeric_limits<double>::infinity());
  // Throws nestlight::Error naming the field: a polygon that crosses itself names its edges.
  static ClipVolume fromJson(const JsonField& f);
  nlohmann::json toJson() const;
  // Checks what fromJson checks (for volumes built in code); throws naming `what`.
  void validate(const std::string& file, const std::string& what) const;
};

// A point is kept when it lies inside at least one Inside volume (if the set has any) and inside
// no Outside volume. An empty set keeps everything.
struct ClipSet {
  std::vector<ClipVolume> volumes;

  bool empty() const { return volumes.empty(); }
  bool keeps(const Vec3d& p) const;
  Overlap keeps(const Box3d& box) const;

  // The "clipping" array of `j` (a clip file or a view state), or `j` itself when it is one
  // volume (an object with "type"). Errors name `file` and the field.
  static ClipSet fromJson(const nlohmann::json& j, const std::string& file);
  static ClipSet load(const std::filesystem::path& file);
  nlohmann::json toJson() const;  // the "clipping" array
};

}  // namespace nestlight
