// Scan points into the G-buffer: splats (discs in their tangent planes, splat_surface.glsl), the
// nearest wins. The depth tested is the splat centre's, not the disc's under the fragment: discs
// of one surface overlap about coplanar, and per-fragment depths would let float rounding pick
// the winner (the frame shimmered under tiling and motion). Their material is their colour:
// emitted radiance in the radiance-cache mode, a Lambert albedo in the albedo mode.
#include "../common/gbuffer_out.glsl"
#include "splat_surface.glsl"
in vec3 vColour;
in vec3 vNormal;
void main() {
  vec3 p;
  float r2;
  if (!splatSurface(p, r2)) discard;
  writeGBuffer(vColour, vRadius, vNormal, NL_MATERIAL_LAMBERT, NL_SOURCE_SCAN, 1.0, 0.0, uint(NL_NO_MATERIAL));
}
