// The splats' vertex stage, for every splatting pass: vertex pulling from the node's buffer; each
// splat's diameter follows the measured spacing of the finest drawn node at its position
// (splat_size.glsl). Two frames of reference:
//   0 (default)     the point view: positions relative to the eye (uNodeOffset, computed in
//                   double on the CPU), a fixed size on request, view-space normals;
//   NL_SCENE_FRAME 1 the GI frame: positions in the scene's local frame (uNodeOrigin), world
//                   normals, orthographic views (shadow maps), the scan's colour scale, and the
//                   disc of each splat (splat_surface.glsl). Used for the camera's G-buffer and
//                   for the lights' shadow maps.
#include "splat_frame.glsl"
#include "../common/point_data.glsl"
#include "../common/clip_volumes.glsl"
#include "splat_size.glsl"

uniform float uPixelsPerUnit;    // pixels of one world unit at distance 1 (perspective) or anywhere (ortho)
uniform float uSizeScale;        // splat diameter in spacings
uniform vec2 uSizeRange;         // min, max diameter in pixels

#if NL_SCENE_FRAME
uniform vec3 uNodeOrigin;        // the node's cube origin in the scene's local frame
uniform mat4 uClipFromWorld;
uniform mat4 uViewFromWorld;
uniform bool uOrthographic;
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
  if (!clipKeeps(world)) {  // outside GL's clip volume: the point is dropped
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    gl_PointSize = 1.0;
    return;
  }
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
#else
uniform float uFixedSize;        // > 0: every splat this many pixels

out vec4 vColour;
out vec3 vNormal;
flat out vec3 vViewPos;
flat out float vRadius;          // the drawn splat's radius in world units at its depth

void main() {
  uint i = uint(gl_VertexID);
  vec3 local = pointLocal(i);
  if (!clipKeeps(uNodeOffset + local)) {  // outside GL's clip volume: the point is dropped
    gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    gl_PointSize = 1.0;
    return;
  }
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
#endif
