// Scan points of the resident cut (vertex pulling from the node's buffer), sized by the measured
// spacing of the finest drawn node at each point (points/splat_size.glsl), in the scene's local
// frame. Used for the camera's G-buffer and for the lights' shadow maps.
#include "../../common/point_data.glsl"
#include "../../points/splat_size.glsl"
uniform vec3 uNodeOrigin;        // the node's cube origin in the scene's local frame
uniform mat4 uClipFromWorld;
uniform mat4 uViewFromWorld;
uniform float uPixelsPerUnit;    // pixels of one world unit at distance 1 (perspective) or anywhere (ortho)
uniform bool uOrthographic;
uniform float uSizeScale;        // splat diameter in spacings
uniform vec2 uSizeRange;         // min, max diameter in pixels
uniform float uColourScale;      // the scene's colour_scale of this scan
out vec3 vColour;
out vec3 vNormal;
flat out float vRadius;   // the splat's radius, world units
flat out vec3 vViewPos;   // its centre in view space (high-quality splatting)
flat out vec3 vViewNormal;  // its normal in view space (splat_surface.glsl)
flat out float vPointSize;
void main() {
  uint i = uint(gl_VertexID);
  vec3 local = pointLocal(i);
  vec3 world = uNodeOrigin + local;
  gl_Position = uClipFromWorld * vec4(world, 1.0);
  float depth = uOrthographic ? 1.0 : max(-(uViewFromWorld * vec4(world, 1.0)).z, 1e-6);
  gl_PointSize = clamp(finestSpacing(local) * uSizeScale * uPixelsPerUnit / depth, uSizeRange.x, uSizeRange.y);
  vRadius = 0.5 * gl_PointSize * depth / uPixelsPerUnit;
  vViewPos = (uViewFromWorld * vec4(world, 1.0)).xyz;
  vColour = pointLinearColour(i) * uColourScale;
  vNormal = decodeNormal(pointNormalWord(i));
  vViewNormal = mat3(uViewFromWorld) * vNormal;
  vPointSize = gl_PointSize;
}
