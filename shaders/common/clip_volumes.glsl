// The clipping volumes' test on the GPU, the same as ClipSet::keeps in
// nestlight/octree/clip_volume.h but in float and in the frame the shader's positions are in (the
// CPU encodes each volume relative to that frame's origin, in double, so large coordinates lose
// nothing): a point is kept when it lies inside at least one inside volume (if there is any) and
// inside no outside volume. Polygons use the even-odd rule with half-open edges, as on the CPU.
#include "../interface/frame_interface.glsl"

// 0: the node lies wholly inside what is kept (the CPU checked its cube), no test; 1: test.
uniform int uClipTest;

vec2 clipVertex(int k) {
  vec4 pair = clipSet.clipVertices[k >> 1];
  return (k & 1) == 0 ? pair.xy : pair.zw;
}

bool clipVolumeContains(int v, vec3 p) {
  ClipVolumeRecord r = clipSet.clipVolumes[v];
  if (r.shape.x == NL_CLIP_BOX) {
    vec3 b = (r.boxFromFrame * vec4(p, 1.0)).xyz;
    return all(lessThanEqual(abs(b), vec3(1.0)));
  }
  if (p.z < r.range.x || p.z > r.range.y) return false;
  int first = r.shape.z, count = r.shape.w;
  if (r.shape.x == NL_CLIP_POLYGON) {
    bool inside = false;
    vec2 a = clipVertex(first + count - 1);
    for (int k = 0; k < count; ++k) {
      vec2 b = clipVertex(first + k);
      // Half-open in y: an edge counts when the point's y lies in [min, max).
      if ((a.y <= p.y) != (b.y <= p.y)) {
        float x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
        if (p.x < x) inside = !inside;
      }
      a = b;
    }
    return inside;
  }
  // Corridor: plan distance to the polyline at most the half width.
  float h2 = r.range.z * r.range.z;
  for (int k = 0; k + 1 < count; ++k) {
    vec2 a = clipVertex(first + k), b = clipVertex(first + k + 1);
    vec2 ab = b - a;
    float t = dot(ab, ab) > 0.0 ? clamp(dot(p.xy - a, ab) / dot(ab, ab), 0.0, 1.0) : 0.0;
    vec2 d = p.xy - (a + t * ab);
    if (dot(d, d) <= h2) return true;
  }
  return false;
}

bool clipKeeps(vec3 p) {
  if (uClipTest == 0) return true;
  bool inInside = false;
  for (int v = 0; v < clipSet.clipCounts.x; ++v) {
    bool outside = clipSet.clipVolumes[v].shape.y != 0;
    bool contains = clipVolumeContains(v, p);
    if (outside && contains) return false;
    if (!outside && contains) inInside = true;
  }
  return clipSet.clipCounts.y == 0 || inInside;
}
