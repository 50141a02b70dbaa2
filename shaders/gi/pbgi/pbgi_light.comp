// Lighting the hierarchies' nodes: in the albedo mode every node (scan and meshes), in the
// radiance-cache mode the meshes' surfels only (uFirstTree: the first table entry to light). Each
// node's radiance from the scene's lights, as the scan's points reflect it (Lambert, their colour
// as albedo clamped to 1, as the raster frame's G-buffer treats scan points; a mesh's surfels by
// their material's directional albedo, lit from the front only, plus its emission): the lights through the frame's shadow maps at the node's centre
// with its cone axis as normal (a node whose normals bound nothing faces each light), and the
// environment's unshadowed irradiance as raster's direct light gives diffuse lobes. Leaves only
// (a point or a uniform cluster, shaded at its centroid); inner nodes then take their children's
// mean (pbgi_light_up.comp): an inner node's centre can lie far off its surface (the middle of a
// curved wall, or on the light itself). Writes a copy of the nodes with the radiance as colour.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
#include "../common/lights.glsl"
layout(std430, binding = PBGI_SSBO_TABLE) readonly buffer Table { PbgiNode cutNodes[]; };
layout(std430, binding = PBGI_SSBO_LIGHT_IN) readonly buffer In { BshNode nodesIn[]; };
layout(std430, binding = PBGI_SSBO_LIGHT_OUT) writeonly buffer Out { BshNode nodesOut[]; };
uniform int uFirstTree;

void main() {
  PbgiNode cn = cutNodes[gl_WorkGroupID.y + uint(uFirstTree)];
  bool mesh = cn.range.z > 0u;  // material + 1
  if (gl_GlobalInvocationID.x >= cn.range.y) return;
  uint i = cn.range.x + gl_GlobalInvocationID.x;
  vec3 origin = cn.origin.xyz;
  float scale = cn.origin.w;
  BshNode A = nodesIn[i];
  if (A.links.x != BSH_LEAF) {
    nodesOut[i] = A;  // its children's mean, by the sweep
    return;
  }
  vec3 p = origin + A.sphere.xyz;
  vec3 albedo = mesh ? A.colour.rgb : min(A.colour.rgb * scale, vec3(1.0));
  bool hasAxis = A.links.w != 0u;
  vec3 axis = hasAxis ? decodeNormal(A.links.w) : vec3(0.0);
  float splat = min(uintBitsToFloat(A.links.y), A.sphere.w);
  vec3 E = vec3(0.0);
  for (int l = 0; l < frame.counts.x; ++l) {
    LightSample s = sampleLight(l, p);
    vec3 n = hasAxis ? axis : s.wi;
    float c = dot(n, s.wi);
    if (c < 0.0 && mesh) continue;
    if (c < 0.0) n = -n, c = -c;  // scanned surfaces are lit from either side, as the G-buffer's
    if (c <= 0.0) continue;
    E += s.radiance * c * visibility(l, p, n, splat, s);
  }
  // Without normals: the irradiance averaged over all orientations, the harmonics' constant term.
  if (uHasEnvironment) E += hasAxis ? irradiance(axis) : max(uEnvSh[0], vec3(0.0));
  A.colour.rgb = albedo * kInvPi * E + (mesh ? materials[cn.range.z - 1u].emission.rgb : vec3(0.0));
  nodesOut[i] = A;
}
