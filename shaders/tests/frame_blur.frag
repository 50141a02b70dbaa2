// Test pass (tests/frame): a 5 x 5 box filter, clamped at the target's edges, declared with a
// margin of 2 so tiles overlap enough to equal the untiled frame.
#include "../interface/frame_interface.glsl"
layout(binding = 0) uniform sampler2D uInput;
layout(location = 0) out vec4 outColour;
void main() {
  ivec2 size = ivec2(frame.tile.zw);
  vec4 sum = vec4(0.0);
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx)
      sum += texelFetch(uInput, clamp(ivec2(gl_FragCoord.xy) + ivec2(dx, dy), ivec2(0), size - 1), 0);
  outColour = sum / 25.0;
}
