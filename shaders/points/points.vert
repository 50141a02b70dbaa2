// GL_POINTS path: vertex pulling from the node's buffer; each splat's diameter follows the
// measured spacing of the finest drawn node at its position (splat_size.glsl).
#include "../common/point_data.glsl"
#include "splat_size.glsl"

uniform float uPixelsPerUnit;    // pixels of one world unit at distance 1
uniform float uSizeScale;        // splat diameter in spacings
uniform vec2 uSizeRange;         // min, max diameter in pixels
uniform float uFixedSize;        // > 0: every splat this many pixels

out vec4 vColour;
out vec3 vNormal;
flat out vec3 vViewPos;
flat out float vRadius;          // the drawn splat's radius in world units at its depth

void main() {
  uint i = uint(gl_VertexID);
  vec3 local = pointLocal(i);
  vec4 view = uViewFromCamRel * vec4(uNodeOffset + local, 1.0);
  gl_Position = uClipFromView * view;
  float depth = max(-view.z, 1e-6);
  float size = uFixedSize > 0.0
                   ? uFixedSize
                   : clamp(finestSpacing(local) * uSizeScale * uPixelsPerUnit / depth, uSizeRange.x, uSizeRange.y);
  gl_PointSize = size;
  vRadius = 0.5 * size * depth / uPixelsPerUnit;
  vViewPos = view.xyz;
  vColour = vec4(pointLinearColour(i), 1.0);
  vNormal = mat3(uViewFromCamRel) * decodeNormal(pointNormalWord(i));
}
