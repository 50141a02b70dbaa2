// Hierarchical sample warping (Clarberg, Jarosz, Akenine-Moeller and Jensen 2005, "Wavelet
// Importance Sampling: Efficiently Evaluating Products of Complex Functions", section 4): points
// of the 2D Halton sequence (bases 2 and 3) descend the importance sum pyramid from its top, at
// each level split first in x by the two columns' sums, then in y by the chosen column's two
// cells, the coordinate rescaled to [0, 1) after each split. The warped points keep the Halton
// points' stratification and land in each texel with probability importance / total, as
// Preiner's VPL placement asks. Layers (light views) are chosen first, by their totals, with the
// x coordinate.
layout(local_size_x = 64) in;
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "pyramid.glsl"
layout(std430, binding = VPL_SSBO_PYRAMID) readonly buffer Pyramid { float pyramid[]; };
layout(std430, binding = VPL_SSBO_SAMPLES) writeonly buffer Samples { WarpSample samples[]; };
uniform int uSize, uLayers, uCount;
uniform int uFirstIndex;  // Halton index of sample 0 (the sequence skips 0)

float radicalInverse(uint i, uint base) {
  float inv = 1.0 / float(base), f = inv, r = 0.0;
  while (i > 0u) {
    r += float(i % base) * f;
    i /= base;
    f *= inv;
  }
  return r;
}

// Splits u between weights a and b: returns 0 or 1 and rescales u within the chosen part.
int split(float a, float b, inout float u) {
  float p = a + b > 0.0 ? a / (a + b) : 0.5;
  if (u < p) {
    u = p > 0.0 ? min(u / p, 0.99999994) : 0.0;
    return 0;
  }
  u = p < 1.0 ? min((u - p) / (1.0 - p), 0.99999994) : 0.0;
  return 1;
}

void main() {
  int k = int(gl_GlobalInvocationID.x);
  if (k >= uCount) return;
  uint index = uint(uFirstIndex + k);
  vec2 u = vec2(radicalInverse(index, 2u), radicalInverse(index, 3u));
  int stride = pyramidLayerStride(uSize), top = 0;
  for (int s = uSize; s > 1; s >>= 1) ++top;
  float total = 0.0;
  for (int l = 0; l < uLayers; ++l) total += pyramid[l * stride + pyramidLevelOffset(uSize, top)];
  WarpSample w;
  w.texel = ivec4(0);
  w.where = vec4(0.0);
  if (!(total > 0.0)) {
    samples[k] = w;
    return;
  }
  // The layer, by its share of the total.
  int layer = 0;
  float acc = 0.0, target = u.x * total, share = 0.0;
  for (int l = 0; l < uLayers; ++l) {
    share = pyramid[l * stride + pyramidLevelOffset(uSize, top)];
    layer = l;
    if (acc + share > target || l == uLayers - 1) break;
    acc += share;
  }
  u.x = share > 0.0 ? clamp((target - acc) / share, 0.0, 0.99999994) : 0.0;
  int base = layer * stride;
  ivec2 t = ivec2(0);
  for (int level = top; level > 0; --level) {
    int s = uSize >> (level - 1);
    int off = base + pyramidLevelOffset(uSize, level - 1);
    ivec2 c = 2 * t;
    float a00 = pyramid[off + c.y * s + c.x], a10 = pyramid[off + c.y * s + c.x + 1];
    float a01 = pyramid[off + (c.y + 1) * s + c.x], a11 = pyramid[off + (c.y + 1) * s + c.x + 1];
    int i = split(a00 + a01, a10 + a11, u.x);
    int j = i == 0 ? split(a00, a01, u.y) : split(a10, a11, u.y);
    t = c + ivec2(i, j);
  }
  float leaf = pyramid[base + t.y * uSize + t.x];
  w.texel = ivec4(t, layer, leaf > 0.0 ? 1 : 0);
  w.where = vec4(u, leaf / total, 0.0);
  samples[k] = w;
}
