// The albedo mode's radiance of the points of S (Maletz, Wang and Bowers 2011, section 4: direct
// light at the scene points through the lights' shadow maps): Lambert reflectors of their colour
// clamped to 1, as the raster frame's G-buffer treats scan points, lit by the scene's lights
// through the frame's shadow maps and by the environment's unshadowed irradiance, as raster's
// direct light lights diffuse lobes (pbgi_light.comp lights its hierarchies alike). In the
// radiance-cache mode a scan point's colour is its radiance; the meshes' surfels are lit in both
// modes (from the front only, their albedo the material's directional albedo) and add their
// material's emission. A glossy surfel with lobes (glossy_to_glossy) reflects the lights
// diffusely by its diffuse colour and keeps, for the PROJECTION_LOBES lights that give it most
// irradiance, the light's direction and irradiance, so that each receiver evaluates the glossy
// lobe toward itself (projection_gather.comp); the environment it reflects by its directional
// albedo, as before.
layout(local_size_x = 64) in;
#include "../../interface/frame_interface.glsl"
#include "../common/gbuffer_in.glsl"
#include "../common/environment.glsl"
#include "../common/lights.glsl"
#include "../../common/octahedral.glsl"
#include "projection_interface.glsl"
layout(std430, binding = PROJECTION_SSBO_POINTS) readonly buffer Points { ProjectionPoint points[]; };
layout(std430, binding = PROJECTION_SSBO_RADIANCE) writeonly buffer Radiance { vec4 radiance[]; };
uniform uint uCount;
uniform bool uAlbedo;
uniform float uSplatScale;  // the frame's splat diameter in spacings (its splats' radius over a point's)

void storeLobe(uint slot, int j, vec3 wi, vec3 E) {
  uint at = uCount + uint(2 * PROJECTION_LOBES) * (slot - 1u) + uint(2 * j);
  radiance[at] = vec4(wi, 0.0);
  radiance[at + 1u] = vec4(E, 0.0);
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uCount) return;
  ProjectionPoint P = points[i];
  vec3 colour = P.normalColour.yzw;
  bool mesh = P.source.x != 0u;
  if (!uAlbedo && !mesh) {
    radiance[i] = vec4(colour, 0.0);
    return;
  }
  vec3 p = P.positionArea.xyz;
  uint word = floatBitsToUint(P.normalColour.x);
  bool hasNormal = word != 0u;
  vec3 axis = hasNormal ? decodeNormal(word) : vec3(0.0);
  // The shadow maps hold the scan's splats, uSplatScale spacings across: a point lies up to a
  // splat radius behind its neighbours' splats, and with its own area's radius as the offset the
  // points of a sphere lit from its centre read 10% dark (they shadowed themselves).
  float splat = uSplatScale * sqrt(P.positionArea.w / kPi);
  uint slot = mesh ? P.source.y : 0u;
  vec3 lobeWi[PROJECTION_LOBES], lobeE[PROJECTION_LOBES];
  float lobeY[PROJECTION_LOBES];
  for (int j = 0; j < PROJECTION_LOBES; ++j) lobeWi[j] = vec3(0.0), lobeE[j] = vec3(0.0), lobeY[j] = -1.0;
  vec3 E = vec3(0.0);
  for (int l = 0; l < frame.counts.x; ++l) {
    LightSample s = sampleLight(l, p);
    vec3 n = hasNormal ? axis : s.wi;
    float c = dot(n, s.wi);
    if (c < 0.0 && mesh) continue;  // a mesh's surfel is lit from the front only
    if (c < 0.0) n = -n, c = -c;    // scanned surfaces are lit from either side, as the G-buffer's
    if (c <= 0.0) continue;
    vec3 El = s.radiance * c * visibility(l, p, n, splat, s);
    E += El;
    if (slot == 0u) continue;
    // The strongest lights keep lobes: this one replaces the weakest kept if it gives more.
    float y = dot(El, vec3(0.2126, 0.7152, 0.0722));
    int weakest = 0;
    for (int j = 1; j < PROJECTION_LOBES; ++j)
      if (lobeY[j] < lobeY[weakest]) weakest = j;
    if (y > lobeY[weakest]) lobeWi[weakest] = s.wi, lobeE[weakest] = El, lobeY[weakest] = y;
  }
  vec3 emission = mesh ? materials[P.source.x - 1u].emission.rgb : vec3(0.0);
  vec3 Eenv = vec3(0.0);
  if (uHasEnvironment) Eenv = hasNormal ? irradiance(axis) : max(uEnvSh[0], vec3(0.0));
  if (slot != 0u) {
    vec3 diffuse = vec3(unpackHalf2x16(P.source.z), unpackHalf2x16(P.source.w).x);
    for (int j = 0; j < PROJECTION_LOBES; ++j) storeLobe(slot, j, lobeWi[j], lobeE[j]);
    radiance[i] = vec4(diffuse * kInvPi * E + min(colour, vec3(1.0)) * kInvPi * Eenv + emission, 0.0);
    return;
  }
  radiance[i] = vec4(min(colour, vec3(1.0)) * kInvPi * (E + Eenv) + emission, 0.0);
}
