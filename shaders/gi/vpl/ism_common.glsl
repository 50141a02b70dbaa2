// Imperfect shadow maps (Ritschel, Grosch, Kim, Seidel, Dachsbacher and Kautz 2008, "Imperfect
// Shadow Maps for Efficient Computation of Indirect Illumination"), as Preiner uses them for
// point clouds: one paraboloid map (Brabec, Annen and Seidel 2002, "Shadow Mapping for
// Hemispherical and Omnidirectional Light Sources") per VPL over its hemisphere, splatted from a
// few thousand points, all VPLs' maps in one atlas.
//
// Beyond the paper: each VPL takes its points by level of detail. The pool holds the lights' cut
// (the nested octree's nodes: a node's points together with its ancestors' cover its cube at the
// node's spacing) and the meshes' surfels. A VPL takes a node when its parent's spacing is
// coarser than an ISM texel's footprint at the node's distance, so near surfaces come from fine
// levels and far ones from coarse levels: the ISM is equally well covered whatever the scan's
// size, and the points a VPL splats stay near the texel count. When they still exceed the
// budget, every stride-th point is taken and splats grow by sqrt(stride) to cover the same area.
#include "../../interface/frame_interface.glsl"
#include "vpl_interface.glsl"
#include "../common/brdf.glsl"
layout(std430, binding = VPL_SSBO_POOL) readonly buffer Pool { PoolPoint pool[]; };
layout(std430, binding = VPL_SSBO_POOL_NODES) readonly buffer PoolNodes { PoolNode poolNodes[]; };
uniform int uNodeCount;
uniform int uIsmSize;        // texels per side of one ISM
uniform float uLodScale;     // wanted spacing in ISM texel footprints
uniform uint uPointBudget;   // points one ISM splats at most

// The angle one ISM texel spans at the paraboloid's pole (the finest; 2/size at the rim).
float ismTexelAngle() { return 4.0 / float(uIsmSize); }

float boxDistance(vec3 p, vec4 box) {
  vec3 d = max(abs(p - box.xyz) - vec3(box.w), vec3(0.0));
  return length(d);
}

bool nodeIncluded(int k, vec3 vplPos) {
  PoolNode n = poolNodes[k];
  float wanted = boxDistance(vplPos, n.box) * ismTexelAngle() * uLodScale;
  return n.lod.y > wanted;
}

// The spacing a point of node k stands for at distance d: the wanted one, or its node's own when
// the node is a leaf of the cut too coarse for the distance.
float pointSpacing(int k, float d) { return max(d * ismTexelAngle() * uLodScale, poolNodes[k].lod.z); }

// Paraboloid coordinates in [-1, 1]^2 of a direction in the VPL's frame (z along the normal).
vec2 paraboloid(vec3 local) { return local.xy / (1.0 + local.z); }

// How many texels per unit of angle the map has around a direction (1 / (1 + z) of the pole's).
float paraboloidScale(vec3 local) { return 1.0 / max(1.0 + local.z, 1e-3); }

// Pool points a workgroup's VPL would splat: their count, summed over its nodes (shared).
shared uint sIncluded;
uint includedPoints(vec3 vplPos) {
  if (gl_LocalInvocationIndex == 0u) sIncluded = 0u;
  barrier();
  uint local = 0u;
  for (int k = int(gl_LocalInvocationIndex); k < uNodeCount; k += int(gl_WorkGroupSize.x))
    if (nodeIncluded(k, vplPos)) local += uint(poolNodes[k].range.y);
  atomicAdd(sIncluded, local);
  barrier();
  return sIncluded;
}

uint hashU(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}
