// Radiance-cache mode, the first generation: each warped sample's scan point becomes an emitting
// VPL. A point of radiance L standing for area A emits L A cos towards each direction on its
// side: recorded as a white Lambert surface lit along its normal by flux pi L A / (count x
// probability). Its side is the one facing the inserted objects (a scan's normals may point
// either way; the reference's discs emit on both sides, and the objects see only one).
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "../common/brdf.glsl"
#include "../../common/octahedral.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = VPL_SSBO_POOL) readonly buffer Pool { PoolPoint pool[]; };
layout(std430, binding = VPL_SSBO_SAMPLES) readonly buffer Samples { WarpSample samples[]; };
layout(std430, binding = VPL_SSBO_RECORDS) writeonly buffer Vpls { VplRecord vpls[]; };
uniform int uCount, uSide;   // uSide: the pyramid's level-0 side
uniform vec3 uObjectsCentre; // where the inserted objects are
void main() {
  int k = int(gl_GlobalInvocationID.x);
  if (k >= uCount) return;
  WarpSample s = samples[k];
  VplRecord v;
  v.position = vec4(0.0);
  v.normal = vec4(0.0, 0.0, 1.0, 1.0);
  v.flux = vec4(0.0);
  v.incident = vec4(0.0, 0.0, 1.0, VPL_EMITTER);
  v.baseColour = vec4(1.0, 1.0, 1.0, float(NL_MATERIAL_LAMBERT));
  if (s.texel.w == 1 && s.where.z > 0.0) {
    PoolPoint q = pool[s.texel.y * uSide + s.texel.x];
    vec3 c = vec3(unpackHalf2x16(q.surface.y), unpackHalf2x16(q.surface.z & 0xffffu).x);
    vec3 n = decodeNormal(q.surface.x);
    vec3 toObjects = uObjectsCentre - q.position.xyz;
    if (!(dot(n, n) > 0.0)) n = dot(toObjects, toObjects) > 0.0 ? normalize(toObjects) : vec3(0.0, 0.0, 1.0);
    if (dot(n, toObjects) < 0.0) n = -n;
    v.position = q.position;
    v.normal = vec4(n, 1.0);
    v.flux = vec4(kPi * c * uintBitsToFloat(q.surface.w) / (float(uCount) * s.where.z), 0.0);
    v.incident = vec4(n, VPL_EMITTER);
  }
  vpls[k] = v;
}
