#include "nestlight/frame/picking.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "nestlight/octree/attribute.h"

namespace nestlight::frame {

std::string PickedPoint::coordinates(const Vec3d& scale) const {
  std::string s;
  for (int a = 0; a < 3; ++a) {
    // As many decimals as one step of the scale needs (0.001 -> 3), so nothing is rounded away.
    const int digits = std::clamp(int(std::ceil(-std::log10(scale[a]) - 1e-9)), 0, 9);
    char b[64];
    std::snprintf(b, sizeof b, "%.*f", digits, position[a]);
    s += (a ? " " : "") + std::string(b);
  }
  return s;
}

nlohmann::json pointAttributes(const PointLayout& layout, const PointBuffer& buffer, size_t i) {
  nlohmann::json j = nlohmann::json::object();
  const uint8_t* p = buffer.attrs.data() + i * buffer.stride;
  for (size_t a = 0; a < layout.size(); ++a) {
    const Attribute& at = layout[a];
    const uint8_t* v = p + layout.offset(a);
    auto value = [&](uint32_t c) {
      const double d = loadAsDouble(at.type, v + c * scalarSize(at.type));
      return isFloat(at.type) ? nlohmann::json(d) : nlohmann::json(int64_t(d));
    };
    if (at.components == 1) {
      j[at.name] = value(0);
    } else {
      nlohmann::json arr = nlohmann::json::array();
      for (uint32_t c = 0; c < at.components; ++c) arr.push_back(value(c));
      j[at.name] = arr;
    }
  }
  return j;
}

double DepthWindow::at(int x, int y) const {
  if (x < x0 || y < y0 || x >= x0 + width || y >= y0 + height) return INFINITY;
  return depth[size_t(y - y0) * width + (x - x0)];
}
double DepthWindow::nearest() const {
  double d = INFINITY;
  for (double v : depth) d = std::min(d, v);
  return d;
}
double DepthWindow::farthestDrawn() const {
  double d = 0;
  for (double v : depth)
    if (std::isfinite(v)) d = std::max(d, v);
  return d;
}

std::optional<PickedPoint> pickPoint(OctreeReader& reader,
                                     const std::vector<streaming::DrawNode>& nodes,
                                     const Camera& camera, int width, int height, double x,
                                     double y, const DepthWindow& dw, const PickOptions& o) {
  const double nearest = dw.nearest(), farthest = dw.farthestDrawn();
  if (!std::isfinite(nearest) || width <= 0 || height <= 0) return std::nullopt;
  const Metadata& meta = reader.metadata();
  const double aspect = double(width) / height;
  const glm::dmat4 viewRot = camera.viewRotation(), proj = camera.projection(aspect);
  const double tanY = std::tan(glm::radians(camera.fovYDegrees) * 0.5);
  const double pixelsPerUnit = height / (2.0 * tanY);
  const double r = std::max(0, o.windowRadius);
  // A splat's diameter in world units at `depth`, drawn for a node of `spacing` (splat_size.glsl).
  auto splat = [&](double spacing, double depth) {
    const double px = o.fixedPointSize > 0
                          ? o.fixedPointSize
                          : std::clamp(spacing * o.sizeScale * pixelsPerUnit / depth,
                                       o.minPointSize, o.maxPointSize);
    return std::max(px, 1.0) * depth / pixelsPerUnit;
  };
  // The window's frustum between the depths drawn in it, as a world box: nodes that miss it
  // (widened by the largest splat) cannot hold a point seen in the window.
  const glm::dmat3 worldFromView = glm::transpose(glm::dmat3(viewRot));
  Box3d reach;
  for (int c = 0; c < 8; ++c) {
    const double px = x + ((c & 1) ? r + 1 : -r - 1), py = y + ((c & 2) ? r + 1 : -r - 1);
    const double d = (c & 4) ? farthest : nearest;
    const glm::dvec3 v((2 * px / width - 1) * tanY * aspect * d, (1 - 2 * py / height) * tanY * d,
                       -d);
    const glm::dvec3 p = camera.eye + worldFromView * v;
    reach.extend(p.x, p.y, p.z);
  }
  const double widen = o.maxPointSize * farthest / pixelsPerUnit;
  using Rank = std::tuple<double, double, NodeKey, uint32_t>;  // distance, depth, node, index
  std::optional<Rank> best;
  PickedPoint out;
  for (const streaming::DrawNode& n : nodes) {
    const Box3d& b = n.worldBounds;
    bool misses = false;
    for (int a = 0; a < 3; ++a)
      misses = misses || b.max[a] < reach.min[a] - widen || b.min[a] > reach.max[a] + widen;
    if (misses) continue;
    const PointBuffer buf = reader.readNode(n.key);
    for (size_t i = 0; i < buf.size(); ++i) {
      const Vec3d p = meta.worldPoint(&buf.pos[3 * i]);
      const glm::dvec3 v = glm::dmat3(viewRot) * (glm::dvec3(p.x, p.y, p.z) - camera.eye);
      const double depth = -v.z;
      if (!(depth > 0)) continue;
      const glm::dvec4 clip = proj * glm::dvec4(v, 1.0);
      const double px = (clip.x / clip.w * 0.5 + 0.5) * width;
      const double py = (0.5 - clip.y / clip.w * 0.5) * height;
      if (std::abs(px - x) > r + 0.5 || std::abs(py - y) > r + 0.5) continue;
      // Seen: what was drawn at its pixel is not nearer than it by more than its splat (splats
      // of the same surface overlap it; a wall in front hides it).
      const double drawn = dw.at(int(std::floor(px)), int(std::floor(py)));
      if (!std::isfinite(drawn) || depth > drawn + splat(n.pointSpacing, depth)) continue;
      if (o.clip && !o.clip->keeps(p)) continue;
      const double dist = std::hypot(px - x, py - y);
      const Rank rank{dist, depth, n.key, uint32_t(i)};
      if (best && !(rank < *best)) continue;
      best = rank;
      out.position = p;
      out.node = n.key;
      out.index = uint32_t(i);
      out.pixelDistance = dist;
      out.depth = depth;
      out.attributes = pointAttributes(meta.layout, buf, i);
    }
  }
  if (!best) return std::nullopt;
  return out;
}

std::optional<PickedPoint> nearestPoint(OctreeReader& reader,
                                        const std::vector<streaming::DrawNode>& nodes,
                                        const Vec3d& target, double maxDistance,
                                        const ClipSet* clip, std::vector<NodeKey>* skip) {
  const Metadata& meta = reader.metadata();
  std::optional<PickedPoint> best;
  double bestD2 = maxDistance * maxDistance;
  for (const streaming::DrawNode& n : nodes) {
    if (skip && std::find(skip->begin(), skip->end(), n.key) != skip->end()) continue;
    const Box3d& b = n.worldBounds;
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = target[a];
      const double e = c < b.min[a] ? b.min[a] - c : (c > b.max[a] ? c - b.max[a] : 0.0);
      d2 += e * e;
    }
    if (d2 > bestD2) continue;
    if (skip) skip->push_back(n.key);
    const PointBuffer buf = reader.readNode(n.key);
    for (size_t i = 0; i < buf.size(); ++i) {
      const Vec3d p = meta.worldPoint(&buf.pos[3 * i]);
      const double dx = p.x - target.x, dy = p.y - target.y, dz = p.z - target.z;
      const double e2 = dx * dx + dy * dy + dz * dz;
      if (e2 > bestD2 || (best && e2 == bestD2 && !(n.key < best->node))) continue;
      if (clip && !clip->keeps(p)) continue;
      bestD2 = e2;
      PickedPoint q;
      q.position = p;
      q.node = n.key;
      q.index = uint32_t(i);
      q.depth = std::sqrt(e2);  // here: the distance from the target
      q.attributes = pointAttributes(meta.layout, buf, i);
      best = std::move(q);
    }
  }
  return best;
}

std::string describeAttributes(const nlohmann::json& attributes) {
  std::string s;
  for (const auto& [k, v] : attributes.items()) s += (s.empty() ? "" : ", ") + k + " " + v.dump();
  return s;
}

}  // namespace nestlight::frame
