// High-quality splatting of the scans into the GI frame's G-buffer (Botsch, Hornung, Zwicker,
// Kobbelt, "High-Quality Surface Splatting on Today's GPUs", 2005, section 3), pass 1 of 3: round
// splats write only depth, pushed back by `uDepthEpsilon` splat radii, over the meshes' depth.
flat in vec3 vViewPos;
flat in float vRadius;
uniform mat4 uClipFromView;   // the tile's
uniform float uDepthEpsilon;
void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  if (dot(d, d) > 1.0) discard;
  vec4 clip = uClipFromView * vec4(vViewPos.xy, vViewPos.z - uDepthEpsilon * vRadius, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
