// High-quality splatting (Botsch, Hornung, Zwicker, Kobbelt, "High-Quality Surface Splatting on
// Today's GPUs", 2005, section 3; as Potree's HQS), pass 1 of 3: the splats write only depth,
// pushed back by `uDepthEpsilon` splat radii. Pass 2 then blends every splat fragment that lies
// within that distance of the front surface; splats of a surface behind it fail the depth test.
//   0 (default)     round sprites at their centre's depth (the point view);
//   NL_SCENE_FRAME 1 discs in their tangent planes (splat_surface.glsl), over the meshes' depth.
#include "splat_frame.glsl"
uniform mat4 uClipFromView;   // the tile's
uniform float uDepthEpsilon;
#if NL_SCENE_FRAME
#include "splat_surface.glsl"
void main() {
  vec3 p;
  float r2;
  if (!splatSurface(p, r2)) discard;
  gl_FragDepth = windowDepth(uClipFromView, p - vec3(0.0, 0.0, uDepthEpsilon * vRadius));
}
#else
flat in vec3 vViewPos;
flat in float vRadius;

void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  if (dot(d, d) > 1.0) discard;
  vec4 clip = uClipFromView * vec4(vViewPos.xy, vViewPos.z - uDepthEpsilon * vRadius, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
#endif
