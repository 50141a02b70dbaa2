// MIP-PBGI and X-PBGI (Sabbadin et al., "High Dynamic Range Point Clouds for Real-Time
// Relighting", 2019, section 5.2.1, Algorithm 3): the hierarchy is visited for blocks of
// receivers at once, as (node, texel of the receivers' pyramid) pairs refined in parallel, one
// generation per dispatch (compute append buffers where the paper uses geometry shaders and
// transform feedback). A pair is
// - discarded when the node is hidden from every receiver of the block: eq. 6 (the node beyond
//   every receiver's horizon: the angle between the block's normal cone and the node's
//   direction, less the node's angular radius, exceeds the cone's aperture + pi/2) and eq. 5
//   (every point of the node faces away), both widened by the block's extent so that they hold
//   for each receiver in it;
// - refined in the hierarchy (two pairs, same texel) while the node's solid angle, seen from the
//   block's nearest point, exceeds uOmegaTr (X-PBGI: 32 m-pixel solid angles, the paper's
//   threshold; MIP-PBGI: one m-pixel's, so the pairs do all the refining);
// - otherwise refined in the pyramid (four pairs, one per child texel) down to single
//   receivers, where the node joins that receiver's list: the classic traversal then continues
//   from it, per receiver (X-PBGI's switch to the classic visit).
// A node seen from inside a block's reach is refined until it is a leaf or the block a single
// receiver. Output that would overflow the pair or list buffers is counted, never written: the
// frame then gathers classically from the root instead.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
#include "pbgi_nodes.glsl"
layout(std430, binding = PBGI_SSBO_PYRAMID) readonly buffer Pyramid { vec4 pyramid[]; };
layout(std430, binding = PBGI_SSBO_PAIRS_IN) readonly buffer PairsIn { uvec4 pairsIn[]; };
layout(std430, binding = PBGI_SSBO_PAIRS_OUT) buffer PairsOut { uvec4 pairsOut[]; };
layout(std430, binding = PBGI_SSBO_LIST_HEAD) buffer ListHead { uint listHead[]; };
layout(std430, binding = PBGI_SSBO_LIST) buffer List { uvec4 list[]; };
// receivers[] (pbgi_common.glsl) counters here: [0] pairs written, [1] pairs that did not fit,
// [2] list entries written, [3] list entries that did not fit.
uniform int uInCount;
uniform uint uPairCapacity;
uniform uint uListCapacity;
uniform float uOmegaTr;
uniform int uLevelOffset[16];
uniform ivec2 uLevelSize[16];

void emitPair(uvec2 e, uint level, ivec2 t) {
  uint i = atomicAdd(receivers[0], 1u);
  if (i >= uPairCapacity) {
    atomicAdd(receivers[1], 1u);
    return;
  }
  pairsOut[i] = uvec4(e, (level << 28) | (uint(t.y) << 14) | uint(t.x), 0u);
}

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= uInCount) return;
  uvec4 p = pairsIn[i];
  uvec2 e = p.xy;
  uint level = p.z >> 28;
  ivec2 t = ivec2(int(p.z & 0x3fffu), int((p.z >> 14) & 0x3fffu));
  int k = uLevelOffset[level] + t.y * uLevelSize[level].x + t.x;
  vec4 block = pyramid[2 * k], cone = pyramid[2 * k + 1];
  if (block.w < 0.0) return;  // no receiver here
  BshNode A = fetchNode(e);
  bool leaf = A.links.x == BSH_LEAF;
  if (leaf && e.y == 0u) {  // a top-tree leaf: the node's own hierarchy, same block
    emitPair(uvec2(0u, A.links.y + 1u), level, t);
    return;
  }
  vec3 d = A.sphere.xyz - block.xyz;
  float dist = length(d);
  float r = A.sphere.w, rho = block.w;
  bool near = dist <= r + rho;
  if (!near) {
    // From any receiver of the block, every point of A lies within beta of A's centre's
    // direction from the block's centre.
    float beta = asin(min(r / (dist - rho), 1.0)) + asin(min(rho / dist, 1.0));
    vec3 w = d / dist;
    if (cone.w < kPi && acos(clamp(dot(w, cone.xyz), -1.0, 1.0)) - beta > cone.w + 1.5707963) return;  // eq. 6
    if (A.links.w != 0u && A.colour.w + 1.5707963 + beta < kPi &&
        acos(clamp(dot(-w, decodeNormal(A.links.w)), -1.0, 1.0)) > A.colour.w + 1.5707963 + beta)
      return;  // eq. 5
  }
  float sinA = near ? 1.0 : min(r / (dist - rho), 1.0);
  float omega = 6.2831853 * (1.0 - sqrt(max(1.0 - sinA * sinA, 0.0)));
  // A block within the node's reach is split first (near is always refined for one receiver).
  if (!leaf && omega > uOmegaTr && (level == 0u || !near)) {
    emitPair(uvec2(A.links.x, e.y), level, t);
    emitPair(uvec2(A.links.y, e.y), level, t);
    return;
  }
  if (level > 0u) {
    ivec2 cs = uLevelSize[level - 1u];
    for (int j = 0; j < 2; ++j)
      for (int q = 0; q < 2; ++q) {
        ivec2 c = 2 * t + ivec2(q, j);
        if (c.x < cs.x && c.y < cs.y && pyramid[2 * (uLevelOffset[level - 1u] + c.y * cs.x + c.x)].w >= 0.0)
          emitPair(e, level - 1u, c);
      }
    return;
  }
  // A single receiver: the node joins its list; the classic traversal takes it from there.
  uint n = atomicAdd(receivers[2], 1u);
  if (n >= uListCapacity) {
    atomicAdd(receivers[3], 1u);
    return;
  }
  uint px = uint(t.y) * uint(frame.tile.z) + uint(t.x);
  uint next = atomicExchange(listHead[px], n);
  list[n] = uvec4(e, next, 0u);
}
