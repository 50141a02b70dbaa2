// A point's colour word (nestlight/frame/gl_node_store.h): the recorded colour as sRGB RGBA8, or,
// when the store draws a colour layer (uHdrColour), linear RGB9E5 (nestlight/octree/rgb9e5.h).
// Every program that reads colour words sets uHdrColour from its store.
#include "srgb.glsl"
uniform bool uHdrColour;

// EXT_texture_shared_exponent's decoding: 9-bit mantissas times 2^(exponent - 15 - 9).
vec3 decodeRgb9e5(uint w) {
  return vec3(uvec3(w, w >> 9u, w >> 18u) & 511u) * exp2(float(w >> 27u) - 24.0);
}

vec3 colourWordLinear(uint w) { return uHdrColour ? decodeRgb9e5(w) : srgbDecode(unpackUnorm4x8(w).rgb); }

// The compute rasterisers average the colours of the points nearest a pixel with 32-bit integer
// atomics (no float atomics in GL 4.5). The recorded colour sums its 8-bit sRGB codes as it always
// has; an HDR colour sums log2(1 + x) in 1/4096 steps (x <= 65504 gives at most 65535 per point,
// so 65536 points fit a pixel): rounding moves x by at most 8.5e-5 (1 + x), 1.7e-4 absolute below
// 1 and 8.5e-5 relative far above it. The average is a geometric one: the points within 1% of a pixel's nearest depth are neighbours on one
// surface, whose colours differ little.
uvec3 colourWordToSum(uint w) {
  if (!uHdrColour) return uvec3(round(unpackUnorm4x8(w).rgb * 255.0));
  return uvec3(round(log2(1.0 + min(decodeRgb9e5(w), vec3(65504.0))) * 4096.0));
}
vec3 colourSumToLinear(vec3 sum, float count) {
  if (!uHdrColour) return srgbDecode(sum / (255.0 * count));
  return exp2(sum / (4096.0 * count)) - 1.0;
}
