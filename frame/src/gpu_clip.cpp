#include "nestlight/frame/gpu_clip.h"

#include <algorithm>
#include <cmath>

#include "nestlight/octree/error.h"

namespace nestlight::frame {

namespace {
// Float of a bound that may be infinite: GLSL compares with it as with any large number.
float clampedFloat(double v) {
  return float(std::clamp(v, -1e30, 1e30));
}
}  // namespace

ClipBlock encodeClipBlock(const ClipSet& set, const Vec3d& o) {
  ClipBlock b{};
  if (set.volumes.size() > NL_MAX_CLIP_VOLUMES)
    throw Error("clipping: " + std::to_string(set.volumes.size()) +
                " volumes; the viewer and renderer draw at most " +
                std::to_string(NL_MAX_CLIP_VOLUMES) + " (export and info take any number)");
  int vertices = 0, anyInside = 0;
  for (size_t v = 0; v < set.volumes.size(); ++v) {
    const ClipVolume& c = set.volumes[v];
    ClipVolumeRecord& r = b.clipVolumes[v];
    const bool outside = c.mode == ClipVolume::Mode::Outside;
    anyInside |= outside ? 0 : 1;
    r.shape = {c.kind == ClipVolume::Kind::Box       ? NL_CLIP_BOX
               : c.kind == ClipVolume::Kind::Polygon ? NL_CLIP_POLYGON
                                                     : NL_CLIP_CORRIDOR,
               outside ? 1 : 0, vertices, 0};
    if (c.kind == ClipVolume::Kind::Box) {
      // Box coordinate i of a frame position p: axes[i] . (p + origin - centre) / half[i].
      const Vec3d d{o.x - c.center.x, o.y - c.center.y, o.z - c.center.z};
      glm::mat4 m(0.0f);
      for (int i = 0; i < 3; ++i) {
        const double inv = 1.0 / std::max(c.half[i], 1e-300);
        for (int j = 0; j < 3; ++j) m[j][i] = float(c.axes[i][j] * inv);
        const Vec3d& a = c.axes[i];
        m[3][i] = float((a.x * d.x + a.y * d.y + a.z * d.z) * inv);
      }
      m[3][3] = 1.0f;
      r.boxFromFrame = m;
      continue;
    }
    const int n = int(c.points.size());
    if (vertices + n > NL_MAX_CLIP_VERTICES)
      throw Error("clipping: the polygons and corridors have more than " +
                  std::to_string(NL_MAX_CLIP_VERTICES) +
                  " vertices together; the viewer and renderer draw at most that many");
    for (int k = 0; k < n; ++k) {
      const float x = float(c.points[size_t(k)][0] - o.x), y = float(c.points[size_t(k)][1] - o.y);
      glm::vec4& pair = b.clipVertices[(vertices + k) / 2];
      if ((vertices + k) % 2 == 0)
        pair.x = x, pair.y = y;
      else
        pair.z = x, pair.w = y;
    }
    r.shape.w = n;
    r.range = {clampedFloat(c.zMin - o.z), clampedFloat(c.zMax - o.z), float(c.width / 2), 0.0f};
    vertices += n;
  }
  b.clipCounts = {int(set.volumes.size()), anyInside, 0, 0};
  return b;
}

void GpuClip::bind(const ClipSet& set, const Vec3d& frameOrigin) {
  if (set.empty()) return;
  const ClipBlock b = encodeClipBlock(set, frameOrigin);
  if (!ubo_) ubo_ = gl::Buffer(sizeof(ClipBlock));
  ubo_.upload(&b, sizeof b);
  ubo_.bindBase(GL_UNIFORM_BUFFER, NL_UBO_CLIP);
}

}  // namespace nestlight::frame
