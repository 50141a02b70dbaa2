// The albedo mode's radiance of the points of S (Maletz, Wang and Bowers 2011, section 4: direct
// light at the scene points through the lights' shadow maps): Lambert reflectors of their colour
// clamped to 1, as the raster frame's G-buffer treats scan points, lit by the scene's lights
// through the frame's shadow maps and by the environment's unshadowed irradiance, as raster's
// direct light lights diffuse lobes (pbgi_light.comp lights its hierarchies alike). In the
// radiance-cache mode a scan point's colour is its radiance; the meshes' surfels are lit in both
// modes (from the front only, their albedo the material's directional albedo) and add their
// material's emission.
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
  vec3 E = vec3(0.0);
  for (int l = 0; l < frame.counts.x; ++l) {
    LightSample s = sampleLight(l, p);
    vec3 n = hasNormal ? axis : s.wi;
    float c = dot(n, s.wi);
    if (c < 0.0 && mesh) continue;  // a mesh's surfel is lit from the front only
    if (c < 0.0) n = -n, c = -c;    // scanned surfaces are lit from either side, as the G-buffer's
    if (c <= 0.0) continue;
    E += s.radiance * c * visibility(l, p, n, splat, s);
  }
  if (uHasEnvironment) E += hasNormal ? irradiance(axis) : max(uEnvSh[0], vec3(0.0));
  radiance[i] = vec4(min(colour, vec3(1.0)) * kInvPi * E +
                        (mesh ? materials[P.source.x - 1u].emission.rgb : vec3(0.0)),
                    0.0);
}
