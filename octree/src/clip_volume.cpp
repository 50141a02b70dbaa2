#include "nestlight/octree/clip_volume.h"

#include <algorithm>
#include <cmath>

#include "nestlight/octree/error.h"
#include "nestlight/octree/json_field.h"

namespace nestlight {
namespace {

using P2 = std::array<double, 2>;

double dot(const Vec3d& a, const Vec3d& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3d sub(const Vec3d& a, const Vec3d& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

double cross(const P2& o, const P2& a, const P2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

// Squared distance from p to the segment ab, and the parameter of its nearest point (0 at a,
// 1 at b; unclamped in `t` so that the corridor's ends can report positions beyond them).
double segmentDistance2(const P2& p, const P2& a, const P2& b, double* t = nullptr) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double l2 = dx * dx + dy * dy;
  double u = l2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2 : 0.0;
  if (t) *t = u;
  u = std::clamp(u, 0.0, 1.0);
  const double ex = a[0] + u * dx - p[0], ey = a[1] + u * dy - p[1];
  return ex * ex + ey * ey;
}

bool onSegment(const P2& a, const P2& b, const P2& p) {
  return std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) &&
         std::min(a[1], b[1]) <= p[1] && p[1] <= std::max(a[1], b[1]);
}

// Closed segments ab and cd share at least one point.
bool segmentsMeet(const P2& a, const P2& b, const P2& c, const P2& d) {
  const double d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return true;
  return (d1 == 0 && onSegment(c, d, a)) || (d2 == 0 && onSegment(c, d, b)) ||
         (d3 == 0 && onSegment(a, b, c)) || (d4 == 0 && onSegment(a, b, d));
}

// The closed segment ab meets the closed rectangle [lo, hi] (Liang-Barsky).
bool segmentMeetsRect(const P2& a, const P2& b, const P2& lo, const P2& hi) {
  double t0 = 0, t1 = 1;
  for (int axis = 0; axis < 2; ++axis) {
    const double d = b[axis] - a[axis];
    if (d == 0) {
      if (a[axis] < lo[axis] || a[axis] > hi[axis]) return false;
      continue;
    }
    double ta = (lo[axis] - a[axis]) / d, tb = (hi[axis] - a[axis]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

double rectDistance2(const P2& p, const P2& lo, const P2& hi) {
  const double dx = std::max({lo[0] - p[0], 0.0, p[0] - hi[0]});
  const double dy = std::max({lo[1] - p[1], 0.0, p[1] - hi[1]});
  return dx * dx + dy * dy;
}

// Even-odd rule with half-open edges (an edge owns its lower end, not its upper).
bool polygonContains(const std::vector<P2>& poly, double x, double y) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const P2 &a = poly[i], &b = poly[j];
    if ((a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0]) in = !in;
  }
  return in;
}

// Node cubes and their points come from the same integer grid but through different roundings;
// the box is widened by a few ulps of its coordinates, which keeps both None and All
// conservative.
Box3d widened(const Box3d& b) {
  Box3d w = b;
  for (int a = 0; a < 3; ++a) {
    const double e = 1e-9 * std::max({1.0, std::abs(b.min[a]), std::abs(b.max[a])});
    w.min[a] -= e, w.max[a] += e;
  }
  return w;
}

std::vector<P2> readPoints(const JsonField& f, size_t minimum) {
  const size_t n = f.arraySize();
  std::vector<P2> pts;
  for (size_t i = 0; i < n; ++i) {
    const JsonField p = f.at(i);
    if (p.arraySize() != 2) p.fail("expected [x, y]");
    pts.push_back({p.at(size_t(0)).number(), p.at(size_t(1)).number()});
  }
  if (pts.size() < minimum)
    f.fail("expected at least " + std::to_string(minimum) + " points, got " +
           std::to_string(pts.size()));
  return pts;
}

std::string edgeName(size_t i, size_t n) {
  return std::to_string(i) + "-" + std::to_string((i + 1) % n);
}

}  // namespace

ClipVolume ClipVolume::box(const Vec3d& center, const Vec3d& size,
                           const std::array<double, 3>& rotationDegrees) {
  ClipVolume v;
  v.kind = Kind::Box;
  v.center = center;
  v.half = {size.x / 2, size.y / 2, size.z / 2};
  v.rotationDegrees = rotationDegrees;
  // World from box: rotation about x, then y, then z (R = Rz Ry Rx); its columns are the axes.
  const double k = M_PI / 180.0;
  const double cx = std::cos(rotationDegrees[0] * k), sx = std::sin(rotationDegrees[0] * k);
  const double cy = std::cos(rotationDegrees[1] * k), sy = std::sin(rotationDegrees[1] * k);
  const double cz = std::cos(rotationDegrees[2] * k), sz = std::sin(rotationDegrees[2] * k);
  const double r[3][3] = {{cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx},
                          {sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx},
                          {-sy, cy * sx, cy * cx}};
  for (int i = 0; i < 3; ++i) v.axes[i] = {r[0][i], r[1][i], r[2][i]};
  return v;
}

ClipVolume ClipVolume::polygon(std::vector<P2> points, double zMin, double zMax) {
  ClipVolume v;
  v.kind = Kind::Polygon;
  // A ring written closed (GeoJSON's habit) and repeated vertices carry no shape.
  points.erase(std::unique(points.begin(), points.end()), points.end());
  if (points.size() > 1 && points.front() == points.back()) points.pop_back();
  v.points = std::move(points);
  v.zMin = zMin, v.zMax = zMax;
  return v;
}

ClipVolume ClipVolume::corridor(std::vector<P2> points, double width, double zMin, double zMax) {
  ClipVolume v;
  v.kind = Kind::Corridor;
  points.erase(std::unique(points.begin(), points.end()), points.end());
  v.points = std::move(points);
  v.width = width;
  v.zMin = zMin, v.zMax = zMax;
  return v;
}

void ClipVolume::validate(const std::string& file, const std::string& what) const {
  auto fail = [&](const std::string& why) { throw Error(file, what, why); };
  if (!(zMin <= zMax))
    fail("z range is empty (" + std::to_string(zMin) + " > " + std::to_string(zMax) + ")");
  switch (kind) {
    case Kind::Box:
      for (int a = 0; a < 3; ++a)
        if (!(half[a] >= 0) || !std::isfinite(half[a]) || !std::isfinite(center[a]))
          fail("a box needs a finite centre and non-negative finite sizes");
      break;
    case Kind::Polygon: {
      const size_t n = points.size();
      if (n < 3) fail("a polygon needs at least 3 distinct points, got " + std::to_string(n));
      for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j) {
          const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
          const P2 &a = points[i], &b = points[(i + 1) % n];
          const P2 &c = points[j], &d = points[(j + 1) % n];
          if (adjacent) {
            // Neighbours share a vertex; they cross only by folding back along each other.
            const P2& shared = j == i + 1 ? b : a;
            const P2& other1 = j == i + 1 ? a : b;
            const P2& other2 = j == i + 1 ? d : c;
            if (cross(shared, other1, other2) == 0 &&
                (other1[0] - shared[0]) * (other2[0] - shared[0]) +
                        (other1[1] - shared[1]) * (other2[1] - shared[1]) >
                    0)
              fail("the polygon crosses itself: edges " + edgeName(i, n) + " and " +
                   edgeName(j, n) + " fold back along each other");
          } else if (segmentsMeet(a, b, c, d)) {
            fail("the polygon crosses itself: edges " + edgeName(i, n) + " and " + edgeName(j, n) +
                 " meet");
          }
        }
      double area2 = 0;
      for (size_t i = 0; i < n; ++i) area2 += cross(points[0], points[i], points[(i + 1) % n]);
      if (area2 == 0) fail("the polygon has no area (its points lie on one line)");
      break;
    }
    case Kind::Corridor:
      if (points.size() < 2)
        fail("a corridor needs a line of at least 2 distinct points, got " +
             std::to_string(points.size()));
      if (!(width > 0) || !std::isfinite(width)) fail("a corridor needs a positive width");
      break;
  }
  for (const P2& p : points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1])) fail("points must be finite");
}

bool ClipVolume::contains(const Vec3d& p) const {
  switch (kind) {
    case Kind::Box: {
      const Vec3d d = sub(p, center);
      for (int i = 0; i < 3; ++i)
        if (!(std::abs(dot(axes[i], d)) <= half[i])) return false;
      return true;
    }
    case Kind::Polygon:
      return p.z >= zMin && p.z <= zMax && polygonContains(points, p.x, p.y);
    case Kind::Corridor: {
      if (!(p.z >= zMin && p.z <= zMax)) return false;
      const double r2 = width * width / 4;
      for (size_t i = 0; i + 1 < points.size(); ++i)
        if (segmentDistance2({p.x, p.y}, points[i], points[i + 1]) <= r2) return true;
      return false;
    }
  }
  return false;
}

Overlap ClipVolume::overlap(const Box3d& exact) const {
  if (exact.empty()) return Overlap::None;
  const Box3d b = widened(exact);
  if (kind == Kind::Box) {
    // The node's corners in the box's frame: all inside, the node is (the box is convex).
    Vec3d lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    bool all = true;
    for (int c = 0; c < 8; ++c) {
      const Vec3d corner{(c & 1) ? b.max.x : b.min.x, (c & 2) ? b.max.y : b.min.y,
                         (c & 4) ? b.max.z : b.min.z};
      const Vec3d d = sub(corner, center);
      for (int i = 0; i < 3; ++i) {
        const double q = dot(axes[i], d);
        lo[i] = std::min(lo[i], q), hi[i] = std::max(hi[i], q);
        all = all && std::abs(q) <= half[i];
      }
    }
    if (all) return Overlap::All;
    // Separated along one of the box's axes or one of the world's (6 of the 15 separating axes:
    // enough to cull, and Partial is always safe).
    for (int i = 0; i < 3; ++i)
      if (hi[i] < -half[i] || lo[i] > half[i]) return Overlap::None;
    for (int j = 0; j < 3; ++j) {
      double e = 0;
      for (int i = 0; i < 3; ++i) e += std::abs(axes[i][j]) * half[i];
      if (center[j] + e < b.min[j] || center[j] - e > b.max[j]) return Overlap::None;
    }
    return Overlap::Partial;
  }
  if (b.max.z < zMin || b.min.z > zMax) return Overlap::None;
  const bool zAll = b.min.z >= zMin && b.max.z <= zMax;
  const P2 lo{b.min.x, b.min.y}, hi{b.max.x, b.max.y};
  if (kind == Kind::Polygon) {
    const size_t n = points.size();
    for (size_t i = 0; i < n; ++i)
      if (segmentMeetsRect(points[i], points[(i + 1) % n], lo, hi)) return Overlap::Partial;
    // No edge touches the rectangle: it lies wholly inside the polygon or wholly outside.
    if (!polygonContains(points, (lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2)) return Overlap::None;
    return zAll ? Overlap::All : Overlap::Partial;
  }
  // Corridor: a union of capsules. None when every segment is farther than the radius; All when
  // one capsule (convex) holds the four corners.
  const double r2 = width * width / 4;
  const P2 corners[4] = {lo, {hi[0], lo[1]}, hi, {lo[0], hi[1]}};
  bool near = false;
  for (size_t i = 0; i + 1 < points.size(); ++i) {
    const P2 &a = points[i], &c = points[i + 1];
    bool holds = true;
    for (const P2& k : corners) holds = holds && segmentDistance2(k, a, c) <= r2;
    if (holds) return zAll ? Overlap::All : Overlap::Partial;
    if (near) continue;
    if (segmentMeetsRect(a, c, lo, hi) || rectDistance2(a, lo, hi) <= r2 ||
        rectDistance2(c, lo, hi) <= r2) {
      near = true;
      continue;
    }
    for (const P2& k : corners) near = near || segmentDistance2(k, a, c) <= r2;
  }
  return near ? Overlap::Partial : Overlap::None;
}

double ClipVolume::length() const {
  double l = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i)
    l += std::hypot(points[i + 1][0] - points[i][0], points[i + 1][1] - points[i][1]);
  return l;
}

double ClipVolume::along(const Vec3d& p) const {
  return alongAcross(p)[0];
}

std::array<double, 2> ClipVolume::alongAcross(const Vec3d& p) const {
  double best = INFINITY, start = 0;
  std::array<double, 2> result{0, 0};
  const size_t segments = points.size() < 2 ? 0 : points.size() - 1;
  for (size_t i = 0; i < segments; ++i) {
    const P2 &a = points[i], &b = points[i + 1];
    const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
    double t = 0;
    const double d2 = segmentDistance2({p.x, p.y}, a, b, &t);
    if (d2 < best) {
      best = d2;
      // Clamped between segments; open at the line's two ends.
      if (i > 0) t = std::max(t, 0.0);
      if (i + 1 < segments) t = std::min(t, 1.0);
      const double side = cross(a, b, {p.x, p.y});
      result = {start + t * len, side < 0 ? -std::sqrt(d2) : std::sqrt(d2)};
    }
    start += len;
  }
  return result;
}

ClipVolume ClipVolume::fromJson(const JsonField& f) {
  f.expectObject({"type", "mode", "name", "center", "size", "rotation", "points", "z", "width"});
  const std::string type = f.at("type").choice({"box", "polygon", "corridor"});
  ClipVolume v;
  auto zRange = [&](ClipVolume& out) {
    if (!f.has("z")) return;
    const JsonField z = f.at("z");
    if (z.arraySize() != 2) z.fail("expected [zmin, zmax]");
    out.zMin = z.at(size_t(0)).number(), out.zMax = z.at(size_t(1)).number();
    if (out.zMin > out.zMax) z.fail("zmin is above zmax");
  };
  if (type == "box") {
    const auto c = f.at("center").vec3();
    const JsonField sf = f.at("size");
    const auto s = sf.vec3(0);
    std::array<double, 3> r{0, 0, 0};
    if (f.has("rotation")) r = f.at("rotation").vec3(-360, 360);
    v = box({c[0], c[1], c[2]}, {s[0], s[1], s[2]}, r);
    v.validate(f.file(), f.path());
  } else {
    const JsonField pf = f.at("points");
    std::vector<P2> pts = readPoints(pf, type == "polygon" ? 3 : 2);
    if (type == "polygon") {
      v = polygon(std::move(pts));
    } else {
      const double w = f.at("width").number(0);
      if (w == 0) f.at("width").fail("expected a positive width");
      v = corridor(std::move(pts), w);
    }
    zRange(v);
    v.validate(f.file(), pf.path());
  }
  if (f.has("mode"))
    v.mode = f.at("mode").choice({"inside", "outside"}) == "inside" ? Mode::Inside : Mode::Outside;
  return v;
}

nlohmann::json ClipVolume::toJson() const {
  nlohmann::json j;
  j["mode"] = mode == Mode::Inside ? "inside" : "outside";
  if (kind == Kind::Box) {
    j["type"] = "box";
    j["center"] = {center.x, center.y, center.z};
    j["size"] = {2 * half.x, 2 * half.y, 2 * half.z};
    j["rotation"] = rotationDegrees;
    return j;
  }
  j["type"] = kind == Kind::Polygon ? "polygon" : "corridor";
  j["points"] = points;
  if (std::isfinite(zMin) || std::isfinite(zMax)) j["z"] = {zMin, zMax};
  if (kind == Kind::Corridor) j["width"] = width;
  return j;
}

bool ClipSet::keeps(const Vec3d& p) const {
  bool anyInside = false, inInside = false;
  for (const ClipVolume& v : volumes) {
    if (v.mode == ClipVolume::Mode::Outside) {
      if (v.contains(p)) return false;
    } else {
      anyInside = true;
      inInside = inInside || v.contains(p);
    }
  }
  return !anyInside || inInside;
}

Overlap ClipSet::keeps(const Box3d& box) const {
  bool anyInside = false, insideAll = false, insideNone = true, outsideNone = true;
  for (const ClipVolume& v : volumes) {
    const Overlap o = v.overlap(box);
    if (v.mode == ClipVolume::Mode::Outside) {
      if (o == Overlap::All) return Overlap::None;
      outsideNone = outsideNone && o == Overlap::None;
    } else {
      anyInside = true;
      insideAll = insideAll || o == Overlap::All;
      insideNone = insideNone && o == Overlap::None;
    }
  }
  if (anyInside && insideNone) return Overlap::None;
  if ((!anyInside || insideAll) && outsideNone) return Overlap::All;
  return Overlap::Partial;
}

ClipSet ClipSet::fromJson(const nlohmann::json& j, const std::string& file) {
  ClipSet set;
  const JsonField root(j, "", file);
  if (j.is_object() && j.contains("type")) {
    set.volumes.push_back(ClipVolume::fromJson(root));
    return set;
  }
  const JsonField list = root.at("clipping");
  for (size_t i = 0, n = list.arraySize(); i < n; ++i)
    set.volumes.push_back(ClipVolume::fromJson(list.at(i)));
  return set;
}

ClipSet ClipSet::load(const std::filesystem::path& file) {
  return fromJson(readJsonFile(file), file.string());
}

nlohmann::json ClipSet::toJson() const {
  nlohmann::json a = nlohmann::json::array();
  for (const ClipVolume& v : volumes) a.push_back(v.toJson());
  return a;
}

}  // namespace nestlight
