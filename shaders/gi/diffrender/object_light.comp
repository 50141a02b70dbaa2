// The light each boundary voxel of the inserted meshes' volumes sends back (objectRadiance:
// diffuse, from the scene's queries and lights), for eq. 6's cones (Rohmer, Jendersie and Grosch
// 2017, section 7): rgb that light, a 1 on boundary voxels and 0 elsewhere, so that the mips'
// box means over a region give the mean light of its surface voxels as rgb / a. Interior voxels
// block (their occupancy) but show no surface.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
#include "../common/gbuffer_in.glsl"
#include "../common/brdf_sample.glsl"
#include "../common/environment.glsl"
#include "../common/lights.glsl"
#include "diffrender_interface.glsl"
#include "diffrender_common.glsl"

layout(rgba16f, binding = 0) uniform writeonly image3D uObjectLightOut;

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, ivec3(uVolumeSize.xy, uVolumeSize.z * uVolumeCount)))) return;
  int k = v.z / uVolumeSize.z;
  ivec3 local = ivec3(v.xy, v.z - k * uVolumeSize.z);
  vec4 s = surfaceAt(k, local);
  int material = int(s.a * 255.0 + 0.5) - 1;
  if (material < 0) {
    imageStore(uObjectLightOut, v, vec4(0.0));
    return;
  }
  vec3 n = normalize(s.xyz * 2.0 - 1.0);
  vec3 p = uVolumeLo[k] + (vec3(local) + 0.5) * volumeCell(k);
  // Half-float range: a brighter surface keeps its hue at the format's largest value.
  vec3 L = objectRadiance(p, n, material);
  float peak = max(L.r, max(L.g, L.b));
  if (peak > 65000.0) L *= 65000.0 / peak;
  imageStore(uObjectLightOut, v, vec4(max(L, vec3(0.0)), 1.0));
}
