// Measurements on a scan: distance, polyline length, polygon area (in plan and in 3D), height
// difference and angle, between points given in the source's world coordinates (the viewer snaps
// them to real points of the scan). Everything is computed in double precision relative to the
// first point, so six-digit national-grid eastings lose nothing to cancellation beyond the
// coordinates' own precision (1e-10 m there): a 1 cm square at easting 512345 has its area to
// 1e-8 of itself, where the textbook shoelace formula on raw coordinates is off by more than the
// area.
//
// A measurement keeps its points as coordinates, not as references to nodes: it survives the
// nodes' eviction and is saved as is in a view state (docs/VIEWER.md).
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nestlight/octree/geometry.h"

namespace nestlight {

class JsonField;

struct Measurement {
  enum class Kind { Distance, Polyline, Area, Height, Angle };
  Kind kind = Kind::Distance;
  std::string name;
  std::vector<Vec3d> points;

  // Distance and Height: 2 points; Angle: 3 (the angle at the second); Polyline: at least 2;
  // Area: at least 3 (an implicitly closed polygon).
  static size_t minimumPoints(Kind k);
  bool complete() const;

  struct Result {
    double value = 0;       // the measurement: length, area (3D), height difference, degrees
    double horizontal = 0;  // distance and polyline: in plan; area: projected on the xy plane
    double vertical = 0;    // distance and polyline: the height change end to end
  };
  // Throws nestlight::Error when the measurement has too few points.
  Result measure() const;
  // "distance 12.345 m (plan 12.001 m, height 2.890 m)" in `unit` ("m", "ft", "units").
  std::string describe(const std::string& unit) const;

  // {"type": "distance", "points": [[x, y, z], ...], "name": "..."}; errors name the field.
  static Measurement fromJson(const JsonField& f);
  nlohmann::json toJson() const;
};

const char* measurementKindName(Measurement::Kind k);

// The pieces, for the viewer's live overlay while points are being placed.
double distance(const Vec3d& a, const Vec3d& b);
double polylineLength(const std::vector<Vec3d>& points);
// Area of the polygon's projection on the xy plane (shoelace) and its area in 3D (half the norm of
// its vector area, Newell's method: exact for a planar polygon, the area seen along the best
// normal for a nearly planar one).
double planArea(const std::vector<Vec3d>& points);
double area3d(const std::vector<Vec3d>& points);
// The angle at `vertex` between the directions to `a` and `b`, in degrees (0 for a degenerate
// leg).
double angleDegrees(const Vec3d& a, const Vec3d& vertex, const Vec3d& b);

}  // namespace nestlight
