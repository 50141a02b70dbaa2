// Compute rasteriser (Schütz, Kerbl, Wimmer, "Rendering Point Clouds with Compute Shaders and
// Vertex Order Optimization", 2021), the two-pass 32-bit variant for GPUs without 64-bit
// atomics (llvmpipe): pass 1 keeps the nearest depth per pixel with atomicMin on the float's
// bits (positive floats order like their bit patterns); pass 2 sums the colours of the points
// within 1% of that depth (their high-quality shading), pass 3 resolves the average.
#include "../common/point_data.glsl"

layout(local_size_x = 128) in;

layout(std430, binding = NL_SSBO_RASTER_DEPTH) buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_RASTER_ACCUM) buffer Accum { uint accum[]; } acc;  // r, g, b, count per pixel
layout(std430, binding = NL_SSBO_RASTER_NORMAL) buffer Normals { uint normal[]; } nb;

uniform ivec2 uViewport;

// The pixel and linear depth of point i; false when it is off screen or behind the eye.
bool projectPoint(uint i, out uint pixel, out float linearDepth) {
  vec4 view = uViewFromCamRel * vec4(pointCamRel(i), 1.0);
  vec4 clip = uClipFromView * view;
  if (clip.w <= 0.0) return false;
  vec3 ndc = clip.xyz / clip.w;
  if (any(lessThan(ndc, vec3(-1.0))) || any(greaterThanEqual(ndc, vec3(1.0)))) return false;
  ivec2 p = ivec2((ndc.xy * 0.5 + 0.5) * vec2(uViewport));
  p = clamp(p, ivec2(0), uViewport - 1);
  pixel = uint(p.y * uViewport.x + p.x);
  linearDepth = -view.z;
  return true;
}
