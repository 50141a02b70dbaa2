// The distance impostor's faces as rendered into the cube map the queries read, holes filled
// (the second half of the pull-push: impostor_pull.comp). A texel no splat covered takes the
// covered mean of the smallest square about it, at most 2^uFillLevels texels wide, that is at
// least 70% covered: gaps between splats close, while a region the splats leave empty (the sky
// of an outdoor scan, beyond the silhouettes) stays empty and shows the environment at infinity
// (distance kImpostorFar); a square across a straight silhouette is about half covered, so the
// silhouettes do not grow into the sky.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../common/brdf.glsl"
#include "../common/environment.glsl"
#include "diffrender_interface.glsl"
#include "impostor_direction.glsl"
layout(binding = 0) uniform sampler2DArray uRaw;
layout(binding = 1) uniform sampler2DArray uColourSum;    // (rgb w, w) and their mips
layout(binding = 2) uniform sampler2DArray uDistanceSum;  // distance w and its mips
layout(rgba32f, binding = 0) uniform writeonly imageCube uFilled;
uniform int uSize;
uniform int uFillLevels;

void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID.xyz);
  if (p.x >= uSize || p.y >= uSize) return;
  vec4 v = texelFetch(uRaw, p, 0);
  if (v.a <= 0.0) {
    v = vec4(environment(impostorDirection(p, uSize)), kImpostorFar);
    for (int level = 1; level <= uFillLevels && (uSize >> level) > 0; ++level) {
      ivec3 q = ivec3(p.xy >> level, p.z);
      vec4 c = texelFetch(uColourSum, q, level);
      if (c.a >= 0.7) {
        v = vec4(c.rgb / c.a, texelFetch(uDistanceSum, q, level).r / c.a);
        break;
      }
    }
  }
  imageStore(uFilled, p, v);
}
