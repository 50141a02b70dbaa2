#include "nestlight/octree/measurement.h"

#include <cmath>
#include <cstdio>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight {
namespace {

Vec3d sub(const Vec3d& a, const Vec3d& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
double norm(const Vec3d& v) {
  return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}

std::string number(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// "a distance", "an area": for messages.
std::string withArticle(Measurement::Kind k) {
  const bool vowel = k == Measurement::Kind::Area || k == Measurement::Kind::Angle;
  return std::string(vowel ? "an " : "a ") + measurementKindName(k);
}

}  // namespace

double distance(const Vec3d& a, const Vec3d& b) {
  return norm(sub(b, a));
}

double polylineLength(const std::vector<Vec3d>& p) {
  double l = 0;
  for (size_t i = 0; i + 1 < p.size(); ++i) l += distance(p[i], p[i + 1]);
  return l;
}

double planArea(const std::vector<Vec3d>& p) {
  if (p.size() < 3) return 0;
  double twice = 0;
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const Vec3d a = sub(p[i], p[0]), b = sub(p[i + 1], p[0]);
    twice += a.x * b.y - a.y * b.x;
  }
  return std::abs(twice) / 2;
}

double area3d(const std::vector<Vec3d>& p) {
  if (p.size() < 3) return 0;
  Vec3d n{0, 0, 0};
  for (size_t i = 1; i + 1 < p.size(); ++i) {
    const Vec3d a = sub(p[i], p[0]), b = sub(p[i + 1], p[0]);
    n.x += a.y * b.z - a.z * b.y;
    n.y += a.z * b.x - a.x * b.z;
    n.z += a.x * b.y - a.y * b.x;
  }
  return norm(n) / 2;
}

double angleDegrees(const Vec3d& a, const Vec3d& vertex, const Vec3d& b) {
  const Vec3d u = sub(a, vertex), v = sub(b, vertex);
  const double nu = norm(u), nv = norm(v);
  if (nu == 0 || nv == 0) return 0;
  // atan2 of |u x v| and u.v: accurate near 0 and 180 degrees, where acos is not.
  const Vec3d c{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  return std::atan2(norm(c), u.x * v.x + u.y * v.y + u.z * v.z) * 180.0 / M_PI;
}

const char* measurementKindName(Measurement::Kind k) {
  switch (k) {
    case Measurement::Kind::Distance:
      return "distance";
    case Measurement::Kind::Polyline:
      return "polyline";
    case Measurement::Kind::Area:
      return "area";
    case Measurement::Kind::Height:
      return "height";
    case Measurement::Kind::Angle:
      return "angle";
  }
  return "?";
}

size_t Measurement::minimumPoints(Kind k) {
  switch (k) {
    case Kind::Area:
      return 3;
    case Kind::Angle:
      return 3;
    default:
      return 2;
  }
}

bool Measurement::complete() const {
  const size_t n = points.size();
  if (kind == Kind::Distance || kind == Kind::Height) return n == 2;
  if (kind == Kind::Angle) return n == 3;
  return n >= minimumPoints(kind);
}

Measurement::Result Measurement::measure() const {
  if (!complete())
    throw Error(withArticle(kind) + " measurement needs " +
                (kind == Kind::Polyline || kind == Kind::Area ? "at least " : "") +
                std::to_string(minimumPoints(kind)) + " points, got " +
                std::to_string(points.size()));
  Result r;
  switch (kind) {
    case Kind::Distance:
    case Kind::Polyline: {
      r.value = polylineLength(points);
      for (size_t i = 0; i + 1 < points.size(); ++i)
        r.horizontal += std::hypot(points[i + 1].x - points[i].x, points[i + 1].y - points[i].y);
      r.vertical = points.back().z - points.front().z;
      break;
    }
    case Kind::Area:
      r.value = area3d(points);
      r.horizontal = planArea(points);
      break;
    case Kind::Height:
      r.value = points[1].z - points[0].z;
      r.horizontal = std::hypot(points[1].x - points[0].x, points[1].y - points[0].y);
      break;
    case Kind::Angle:
      r.value = angleDegrees(points[0], points[1], points[2]);
      break;
  }
  return r;
}

std::string Measurement::describe(const std::string& unit) const {
  const Result r = measure();
  const std::string u = " " + unit;
  switch (kind) {
    case Kind::Distance:
      return "distance " + number(r.value) + u + " (plan " + number(r.horizontal) + u +
             ", height " + number(r.vertical) + u + ")";
    case Kind::Polyline:
      return "polyline " + number(r.value) + u + " over " + std::to_string(points.size()) +
             " points (plan " + number(r.horizontal) + u + ")";
    case Kind::Area:
      return "area " + number(r.value) + u + "\xC2\xB2 (in plan " + number(r.horizontal) + u +
             "\xC2\xB2)";
    case Kind::Height:
      return "height difference " + number(r.value) + u + " (plan distance " +
             number(r.horizontal) + u + ")";
    case Kind::Angle:
      return "angle " + number(r.value) + " degrees";
  }
  return "";
}

Measurement Measurement::fromJson(const JsonField& f) {
  f.expectObject({"type", "name", "points"});
  Measurement m;
  const std::string t = f.at("type").choice({"distance", "polyline", "area", "height", "angle"});
  for (Kind k : {Kind::Distance, Kind::Polyline, Kind::Area, Kind::Height, Kind::Angle})
    if (t == measurementKindName(k)) m.kind = k;
  if (f.has("name")) m.name = f.at("name").string();
  const JsonField pf = f.at("points");
  for (size_t i = 0, n = pf.arraySize(); i < n; ++i) {
    const auto v = pf.at(i).vec3();
    m.points.push_back({v[0], v[1], v[2]});
  }
  if (!m.complete())
    pf.fail(withArticle(m.kind) + " needs " +
            (m.kind == Kind::Polyline || m.kind == Kind::Area ? "at least " : "") +
            std::to_string(minimumPoints(m.kind)) + " points, got " +
            std::to_string(m.points.size()));
  return m;
}

nlohmann::json Measurement::toJson() const {
  nlohmann::json p = nlohmann::json::array();
  for (const Vec3d& v : points) p.push_back({v.x, v.y, v.z});
  nlohmann::json j{{"type", measurementKindName(kind)}, {"points", p}};
  if (!name.empty()) j["name"] = name;
  return j;
}

}  // namespace nestlight
