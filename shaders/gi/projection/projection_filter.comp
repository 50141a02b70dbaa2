// The post filter (Maletz, Wang and Bowers 2011, section 4: joint bilateral 7 x 7, 3 x 3 where
// glossy): each receiver pixel's irradiance and glossy rest averaged over its window with the
// cells' joint bilateral weights (a Gaussian in pixels times the normals' agreement to the 8th
// power times the neighbour's distance from the pixel's tangent plane, zero beyond 2% of the
// pixel's distance from the camera), so the filter smooths the gather's noise without carrying
// light across creases and depth edges. Reads PROJECTION_SSBO_PIXELS, writes the same layout to
// PROJECTION_SSBO_FILTERED.
layout(local_size_x = 8, local_size_y = 8) in;
#include "projection_common.glsl"
#include "projection_upsample_weights.glsl"
layout(std430, binding = PROJECTION_SSBO_FILTERED) writeonly buffer Filtered { vec4 filtered[]; };
uniform int uRadius;        // the window's half side (3: 7 x 7)
uniform int uGlossyRadius;  // where the receiver is glossy (1: 3 x 3)

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  ivec2 size = ivec2(frame.tile.zw);
  if (px.x >= size.x || px.y >= size.y) return;
  uint i = uint(px.y * size.x + px.x);
  vec4 a = pixels[2u * i], b = pixels[2u * i + 1u];
  if (a.w == PROJECTION_UNSET) {
    filtered[2u * i] = a;
    filtered[2u * i + 1u] = b;
    return;
  }
  vec3 emission;
  MaterialParams m = gbufferMaterial(texelFetch(uBaseColour, px, 0).rgb, texelFetch(uMaterial, px, 0), emission);
  bool glossy = m.type != NL_MATERIAL_LAMBERT && m.roughness < 0.5;
  int r = glossy ? uGlossyRadius : uRadius;
  vec3 pc = positionAt(px), nc = normalAt(px);
  float footprint = 0.02 * max(length(pc - frame.eye.xyz), 1e-6);
  float sigma2 = max(float(r * r), 1.0) * 0.5;
  vec3 E = vec3(0.0), rest = vec3(0.0);
  float sum = 0.0;
  for (int dy = -r; dy <= r; ++dy)
    for (int dx = -r; dx <= r; ++dx) {
      ivec2 q = px + ivec2(dx, dy);
      if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
      uint j = uint(q.y * size.x + q.x);
      if (pixels[2u * j].w == PROJECTION_UNSET) continue;
      float plane = abs(dot(positionAt(q) - pc, nc));
      float w = exp(-float(dx * dx + dy * dy) / (2.0 * sigma2)) * pow(max(dot(normalAt(q), nc), 0.0), 8.0) *
                max(1.0 - plane / footprint, 0.0);
      E += w * pixels[2u * j].rgb;
      rest += w * pixels[2u * j + 1u].rgb;
      sum += w;
    }
  filtered[2u * i] = sum > 0.0 ? vec4(E / sum, a.w) : a;
  filtered[2u * i + 1u] = sum > 0.0 ? vec4(rest / sum, b.w) : b;
}
