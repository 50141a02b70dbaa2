// GL_POINTS path: vertex pulling from the node's buffer, splat size from the node's spacing.
#include "../common/point_data.glsl"

uniform float uSpacing;          // the node's point spacing, world units
uniform float uPixelsPerUnit;    // pixels of one world unit at distance 1
uniform float uSizeScale;        // splat diameter in spacings
uniform vec2 uSizeRange;         // min, max diameter in pixels
uniform float uFixedSize;        // > 0: every splat this many pixels

out vec4 vColour;
out vec3 vNormal;

void main() {
  uint i = uint(gl_VertexID);
  vec4 view = uViewFromCamRel * vec4(pointCamRel(i), 1.0);
  gl_Position = uClipFromView * view;
  float depth = max(-view.z, 1e-6);
  gl_PointSize = uFixedSize > 0.0 ? uFixedSize
                                  : clamp(uSpacing * uSizeScale * uPixelsPerUnit / depth, uSizeRange.x, uSizeRange.y);
  vColour = unpackUnorm4x8(pointColour(i));
  vNormal = mat3(uViewFromCamRel) * decodeNormal(pointNormalWord(i));
}
