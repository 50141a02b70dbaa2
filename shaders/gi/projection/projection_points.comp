// The point set S of the `projection` method (Maletz, Wang and Bowers 2011, section 3.1): one cut
// node's points, every uStride-th (the lights' cut thinned to the `points` budget), into the
// unsorted list at uOffset. The areas are the host's (from the points' spacing); the clusters
// reorder the list after it is read back. A point the scan's clipping volumes remove is marked
// with area -1: the host drops it after the read-back.
layout(local_size_x = 64) in;
#include "../../common/point_data.glsl"
#include "projection_interface.glsl"
#include "../../common/clip_volumes.glsl"
layout(std430, binding = PROJECTION_SSBO_POINTS) writeonly buffer Points { ProjectionPoint points[]; };
uniform vec3 uOrigin;  // the node cube's origin, scene-local
uniform uint uStride;
uniform uint uOffset;
uniform uint uKept;
uniform float uColourScale;

void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= uKept) return;
  uint i = j * uStride;
  ProjectionPoint p;
  p.positionArea = vec4(uOrigin + pointLocal(i), 0.0);
  if (!clipKeeps(p.positionArea.xyz)) p.positionArea.w = -1.0;
  p.normalColour = vec4(uintBitsToFloat(pointNormalWord(i)), pointLinearColour(i) * uColourScale);
  p.source = uvec4(0u);
  points[uOffset + j] = p;
}
