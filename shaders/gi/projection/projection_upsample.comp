// The pixels this level interpolates (projection_select.comp): their irradiance and glossy rest
// from the corners of their cell by joint bilateral upsampling (Kopf et al. 2007), so each
// re-applies its own albedo in projection_compose.comp.
layout(local_size_x = 8, local_size_y = 8) in;
#include "projection_common.glsl"
#include "projection_upsample_weights.glsl"
uniform int uStep;

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = ivec2(frame.tile.zw);
  if (px.x >= size.x || px.y >= size.y || !onGrid(px, uStep, size)) return;
  uint i = uint(px.y * size.x + px.x);
  if (pixels[2u * i].w != PROJECTION_INTERPOLATED) return;
  Corners c = cornersOf(px, uStep, size);
  vec3 E = vec3(0.0), rest = vec3(0.0);
  for (int k = 0; k < 4; ++k) {
    uint j = uint(c.at[k].y * size.x + c.at[k].x);
    E += c.weight[k] * pixels[2u * j].rgb;
    rest += c.weight[k] * pixels[2u * j + 1u].rgb;
  }
  pixels[2u * i] = vec4(E, PROJECTION_INTERPOLATED);
  pixels[2u * i + 1u] = vec4(rest, 0.0);
}
