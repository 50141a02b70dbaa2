// The compute rasteriser for the GI frame's G-buffer (Schütz, Kerbl, Wimmer, "Rendering Point
// Clouds with Compute Shaders and Vertex Order Optimization", 2021; the two-pass 32-bit variant,
// which every GL 4.5 device runs): one pixel per point, the nearest depth per pixel by atomicMin
// on the float's bits, then the colours of the points within 1% of it summed (their average is
// the pixel's colour), their normal and splat radius kept. Positions in the scene's local frame.
#include "../../common/point_data.glsl"
#include "../../points/splat_size.glsl"

layout(local_size_x = 128) in;

layout(std430, binding = NL_SSBO_SCAN_DEPTH) buffer ScanDepth { uint depth[]; } sd;
layout(std430, binding = NL_SSBO_SCAN_ACCUM) buffer ScanAccum { uint accum[]; } sa;    // r, g, b, count
layout(std430, binding = NL_SSBO_SCAN_NORMAL) buffer ScanNormal { uint normal[]; } sn;
layout(std430, binding = NL_SSBO_SCAN_RADIUS) buffer ScanRadius { float radius[]; } sr;

uniform ivec2 uViewport;         // the tile
uniform vec3 uNodeOrigin;        // the node's cube origin, scene-local
uniform mat4 uClipFromWorld;     // the tile's
uniform mat4 uViewFromWorld;

bool projectPoint(uint i, out uint pixel, out float linearDepth) {
  vec3 world = uNodeOrigin + pointLocal(i);
  vec4 clip = uClipFromWorld * vec4(world, 1.0);
  if (clip.w <= 0.0) return false;
  vec3 ndc = clip.xyz / clip.w;
  if (any(lessThan(ndc, vec3(-1.0))) || any(greaterThanEqual(ndc, vec3(1.0)))) return false;
  ivec2 p = clamp(ivec2((ndc.xy * 0.5 + 0.5) * vec2(uViewport)), ivec2(0), uViewport - 1);
  pixel = uint(p.y * uViewport.x + p.x);
  linearDepth = -(uViewFromWorld * vec4(world, 1.0)).z;
  return true;
}
