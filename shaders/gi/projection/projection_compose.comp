// The tile's output: direct light, plus at every receiver its own diffuse albedo times the
// gathered (or interpolated) irradiance over pi and the glossy rest.
layout(local_size_x = 8, local_size_y = 8) in;
#include "projection_common.glsl"
#include "projection_upsample_weights.glsl"
layout(std430, binding = PROJECTION_SSBO_STATS) buffer Stats { uint stats[]; };

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = ivec2(frame.tile.zw);
  if (px.x >= size.x || px.y >= size.y) return;
  uint i = uint(px.y * size.x + px.x);
  vec4 direct = texelFetch(uDirect, px, 0);
  if (pixels[2u * i].w == PROJECTION_UNSET) {
    imageStore(uOut, px, direct);
    return;
  }
  atomicAdd(stats[5], 1u);  // receivers, gathered or interpolated
  imageStore(uOut, px, vec4(outgoingAt(px, size), direct.a));
}
