// Image-space adaptive sampling (Maletz, Wang and Bowers 2011, section 3.3), one level: the
// tile's pixels on this level's grid (the full image's, step uStep, plus its last row and column) that are
// not gathered yet are gathered where the coherence metric over the corners of their cell on the
// coarser grid (step 2 uStep) reaches uEpsilon,
//   max_i(|p_i - p_c| / (d / 2) + sqrt(2 - 2 n_i . n_c)) + lambda sum_{j<k} |L_o(p_j) - L_o(p_k)|,
// or where the joint bilateral weights of those corners all vanish (a depth edge: no weight
// crosses it); else they are interpolated (projection_upsample.comp). The first level gathers its
// whole grid. Gathered pixels are listed for projection_gather.comp (which marks them gathered).
// uInterpolateOnly (a level a progressive frame has not reached, or beyond `levels`): every
// receiver not gathered or listed is interpolated.
layout(local_size_x = 8, local_size_y = 8) in;
#include "projection_common.glsl"
#include "projection_upsample_weights.glsl"
layout(std430, binding = PROJECTION_SSBO_LIST) buffer List { uint list[]; };

uniform int uStep;
uniform bool uFirstLevel;
uniform float uEpsilon;
uniform float uLambda;
uniform float uHalfDiagonal;  // d / 2: the scene's bounding diagonal's half
uniform bool uInterpolateOnly;

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = ivec2(frame.tile.zw);
  if (px.x >= size.x || px.y >= size.y) return;
  if (!onGrid(px, uStep, size)) return;
  uint i = uint(px.y * size.x + px.x);
  float state = pixels[2u * i].w;
  if (state == PROJECTION_GATHERED || state == PROJECTION_LISTED) return;
  if (!uGathers || !isReceiver(px)) return;
  bool gather = uFirstLevel && !uInterpolateOnly;
  if (!gather && !uInterpolateOnly) {
    Corners c = cornersOf(px, uStep, size);
    gather = c.weightSum <= 0.0;
    if (!gather) {
      vec3 pc = positionAt(px), nc = normalAt(px);
      float geometric = 0.0, radiance = 0.0;
      for (int k = 0; k < 4; ++k) {
        geometric = max(geometric, length(positionAt(c.at[k]) - pc) / uHalfDiagonal +
                                       sqrt(max(2.0 - 2.0 * dot(normalAt(c.at[k]), nc), 0.0)));
        for (int j = 0; j < k; ++j) radiance += abs(c.toneMapped[k] - c.toneMapped[j]);
      }
      gather = !(geometric + uLambda * radiance < uEpsilon);
    }
  }
  if (gather) {
    pixels[2u * i].w = PROJECTION_LISTED;
    uint slot = atomicAdd(list[0], 1u);
    list[4u + slot] = uint(px.x) | (uint(px.y) << 16);
  } else {
    pixels[2u * i].w = PROJECTION_INTERPOLATED;
  }
}
