// The pixels this level interpolates (projection_select.comp): their irradiance and glossy rest
// from the corners of their cell by joint bilateral upsampling (Kopf et al. 2007), so each
// re-applies its own albedo in projection_compose.comp. A progressive frame's pixels listed but
// not gathered yet are interpolated too, for the frame; with uFallback (levels that do not
// gather) a pixel no corner is like takes its corners' bilinear weights alone, until gathered.
layout(local_size_x = 8, local_size_y = 8) in;
#include "projection_common.glsl"
#include "projection_upsample_weights.glsl"
uniform int uStep;
uniform bool uFallback;

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = ivec2(frame.tile.zw);
  if (px.x >= size.x || px.y >= size.y || !onGrid(px, uStep, size)) return;
  uint i = uint(px.y * size.x + px.x);
  float state = pixels[2u * i].w;
  if (state != PROJECTION_INTERPOLATED && state != PROJECTION_LISTED) return;
  Corners c = cornersOf(px, uStep, size);
  if (uFallback && c.weightSum <= 0.0) {
    // The corners' bilinear weights (t from the cell, as cornersOf) over those that hold light.
    int s2 = 2 * uStep;
    ivec2 g = px + ivec2(frame.tile.xy);
    vec2 t = vec2(g % s2) / float(s2);
    float bilinear[4] = float[4]((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    float sum = 0.0;
    for (int k = 0; k < 4; ++k) {
      uint j = uint(c.at[k].y * size.x + c.at[k].x);
      c.weight[k] = pixels[2u * j].w != PROJECTION_UNSET ? bilinear[k] + 1e-3 : 0.0;
      sum += c.weight[k];
    }
    for (int k = 0; k < 4; ++k) c.weight[k] = sum > 0.0 ? c.weight[k] / sum : 0.0;
  }
  vec3 E = vec3(0.0), rest = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    uint j = uint(c.at[k].y * size.x + c.at[k].x);
    E += c.weight[k] * pixels[2u * j].rgb;
    rest += c.weight[k] * pixels[2u * j + 1u].rgb;
  }
  pixels[2u * i] = vec4(E, state);
  pixels[2u * i + 1u] = vec4(rest, 0.0);
}
