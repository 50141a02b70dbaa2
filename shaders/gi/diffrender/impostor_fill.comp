// The distance impostor's faces as rendered (a 2D array, one layer a face) into the cube map the
// queries read: texels no splat covered take the mean of their covered neighbours when those
// surround them (gaps between splats), else the environment at infinity (distance kImpostorFar).
// A stand-in for the paper's push-pull filling (Marroquim, Kraus and Cavalcanti 2007) that closes
// one-texel gaps only.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../common/brdf.glsl"
#include "../common/environment.glsl"
#include "diffrender_interface.glsl"
#include "impostor_direction.glsl"
layout(binding = 0) uniform sampler2DArray uRaw;
layout(rgba32f, binding = 0) uniform writeonly imageCube uFilled;
uniform int uSize;

void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID.xyz);
  if (p.x >= uSize || p.y >= uSize) return;
  vec4 v = texelFetch(uRaw, p, 0);
  if (v.a <= 0.0) {
    vec4 sum = vec4(0.0);
    int covered = 0;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        ivec2 q = p.xy + ivec2(dx, dy);
        if ((dx == 0 && dy == 0) || any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(uSize)))) continue;
        vec4 n = texelFetch(uRaw, ivec3(q, p.z), 0);
        if (n.a > 0.0) sum += n, covered++;
      }
    v = covered >= 5 ? sum / float(covered) : vec4(environment(impostorDirection(p, uSize)), kImpostorFar);
  }
  imageStore(uFilled, p, v);
}
