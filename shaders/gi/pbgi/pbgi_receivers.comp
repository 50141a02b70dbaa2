// The tile's receivers, listed for the gather (pixels that are inserted objects, x | y << 16),
// and the tile's direct light copied to the output, which the gather adds to.
layout(local_size_x = 8, local_size_y = 8) in;
#include "pbgi_common.glsl"
void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= int(frame.tile.z) || px.y >= int(frame.tile.w)) return;
  imageStore(uOut, px, texelFetch(uDirect, px, 0));
  if (!isReceiver(px)) return;
  uint i = atomicAdd(receivers[0], 1u);
  receivers[4u + i] = uint(px.x) | (uint(px.y) << 16);
}
