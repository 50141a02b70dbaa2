// Compute rasteriser (Schütz, Kerbl, Wimmer, "Rendering Point Clouds with Compute Shaders and
// Vertex Order Optimization", 2021), the two-pass 32-bit variant for GPUs without 64-bit
// atomics (llvmpipe; every GL 4.5 device runs it): one pixel per point; pass 1 keeps the nearest
// depth per pixel with atomicMin on the float's bits (positive floats order like their bit
// patterns); pass 2 sums the colours of the points within 1% of that depth (their high-quality
// shading), pass 3 resolves the average.
//   0 (default)     the point view: positions relative to the eye;
//   NL_SCENE_FRAME 1 the GI frame: positions in the scene's local frame; pass 2 also keeps a
//                   point's splat radius (for shadow offsets).
#include "../common/point_data.glsl"
#include "../common/clip_volumes.glsl"

// As splat_frame.glsl, kept here so that the passes' include tree stays the points' own.
#ifndef NL_SCENE_FRAME
#define NL_SCENE_FRAME 0
#endif

layout(local_size_x = 128) in;

// The per-pixel buffers (nestlight/frame/point_splatting.h allocates them). The GI frame binds
// them at its method bindings, clear of the frame's lights and shadow views.
#if NL_SCENE_FRAME
layout(std430, binding = NL_SSBO_SCAN_DEPTH) buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_SCAN_ACCUM) buffer Accum { uint accum[]; } acc;  // r, g, b, count per pixel
layout(std430, binding = NL_SSBO_SCAN_NORMAL) buffer Normals { uint normal[]; } nb;
layout(std430, binding = NL_SSBO_SCAN_RADIUS) buffer Radius { float radius[]; } sr;
#else
layout(std430, binding = NL_SSBO_RASTER_DEPTH) buffer Depth { uint depth[]; } fb;
layout(std430, binding = NL_SSBO_RASTER_ACCUM) buffer Accum { uint accum[]; } acc;  // r, g, b, count per pixel
layout(std430, binding = NL_SSBO_RASTER_NORMAL) buffer Normals { uint normal[]; } nb;
#endif

uniform ivec2 uViewport;         // the tile

#if NL_SCENE_FRAME
uniform vec3 uNodeOrigin;        // the node's cube origin, scene-local
uniform mat4 uClipFromWorld;     // the tile's
uniform mat4 uViewFromWorld;

bool projectPoint(uint i, out uint pixel, out float linearDepth) {
  vec3 world = uNodeOrigin + pointLocal(i);
  if (!clipKeeps(world)) return false;
  vec4 clip = uClipFromWorld * vec4(world, 1.0);
  if (clip.w <= 0.0) return false;
  vec3 ndc = clip.xyz / clip.w;
  if (any(lessThan(ndc, vec3(-1.0))) || any(greaterThanEqual(ndc, vec3(1.0)))) return false;
  ivec2 p = clamp(ivec2((ndc.xy * 0.5 + 0.5) * vec2(uViewport)), ivec2(0), uViewport - 1);
  pixel = uint(p.y * uViewport.x + p.x);
  linearDepth = -(uViewFromWorld * vec4(world, 1.0)).z;
  return true;
}
#else
// The pixel and linear depth of point i; false when it is off screen or behind the eye.
bool projectPoint(uint i, out uint pixel, out float linearDepth) {
  if (!clipKeeps(pointCamRel(i))) return false;
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
#endif
