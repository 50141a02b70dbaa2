// Classic point-based GI (Christensen 2008; micro-rendering, Ritschel et al. 2009) as Sabbadin et
// al., "High Dynamic Range Point Clouds for Real-Time Relighting" (2019), section 5.2, build it:
// per receiver, a depth-first traversal of the bounding-sphere hierarchy of the resident cut (the
// top tree over the cut's nodes, then each node's own hierarchy) fills a micro-buffer, an
// M x M paraboloid map of the hemisphere about the receiver's normal, with colour and distance;
// eq. 7 convolves it with the receiver's BRDF (section 5.3).
//
// Per node A at distance d with sphere radius r:
// - wholly below the receiver's tangent plane (n . (p_A - x) < -r): discarded;
// - facing away (eq. 5), made conservative for a node of angular radius beta = asin(r / d): the
//   paper tests the direction to the centre only, which drops a near node whose far side faces
//   the receiver; here A is discarded when the angle between -w and its cone axis exceeds
//   alpha + pi/2 + beta;
// - eq. 4: Omega(A) = 2 pi (1 - sqrt(1 - (r/d)^2)) against the m-pixel solid angle 2 pi / M^2
//   (4 x that with the paper's over-conservative option): larger nodes are refined, smaller ones
//   (and leaves) rasterised; a receiver inside a node's sphere always refines it.
// Rasterising: a node no wider than about an m-pixel lands in the m-pixel of its centre's
// direction at distance d - r; a wider one covers the m-pixels whose central ray hits it: a leaf
// as its disc (its normal, its disc radius), an inner node as its sphere's silhouette at the depth of
// its mean plane; one that covers no m-pixel centre still lands in its centre's m-pixel.
// Empty m-pixels take uEmpty (the paper: the cloud's average colour, for holes in the cloud), or
// the environment's radiance in their direction (open scenes: what no point covers is sky).
//
// Receivers are G-buffer pixels, or (uNodeReceivers, the albedo mode's further bounces) hierarchy
// nodes listed by pbgi_bounce_select.comp: a node receives at its centre, on the side of its cone's
// axis (a node without normals faces +z), lifted 1.5 leaf disc radii, through a white Lambert
// BRDF (its irradiance / pi), into PBGI_SSBO_BOUNCE; its empty m-pixels stay black (the nodes'
// direct light already has the sky, unshadowed).
//
// One invocation per receiver; the traversal is resumable. llvmpipe ends every loop of a shader
// invocation after 65,535 iterations in all (Mesa's LP_MAX_TGSI_LOOP_ITERATIONS, shared by every
// loop), and a traversal takes more at fine micro-buffers: so the traversal is one flat loop
// (a node, or one m-pixel of a wide node's splat, per step) of at most uBudget steps per
// dispatch, its stack, micro-buffer and splat in progress kept in buffers between dispatches,
// and the frame dispatches until every receiver has finished.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
#include "pbgi_nodes.glsl"
layout(std430, binding = PBGI_SSBO_LIST_HEAD) readonly buffer ListHead { uint listHead[]; };
layout(std430, binding = PBGI_SSBO_LIST) readonly buffer List { uvec4 list[]; };
layout(std430, binding = PBGI_SSBO_MICRO) readonly buffer Micro { vec4 micro[]; };
layout(std430, binding = PBGI_SSBO_STATE) buffer State { PbgiTraversal states[]; };
layout(std430, binding = PBGI_SSBO_STACK) buffer Stack { uvec2 stacks[]; };
layout(std430, binding = PBGI_SSBO_MB) buffer Mb { vec4 mbs[]; };
layout(std430, binding = PBGI_SSBO_BOUNCE) buffer Bounce { vec4 gathered[]; };
uniform int uNodeReceivers;   // 1: receivers are hierarchy nodes (tree, node), 0: pixels
uniform int uFirst;           // first receiver of this chunk
uniform int uCount;           // receivers in this chunk
uniform int uInit;            // 1: the chunk's first dispatch (clear micro-buffers, push the root)
uniform int uBudget;          // traversal steps per dispatch
uniform int uTopCount;        // nodes in the top tree (0: nothing resident)
uniform float uOmegaCut;      // the refinement threshold (m-pixel solid angle, x 4 conservative)
uniform vec3 uEmpty;          // radiance of an m-pixel nothing covered (uEmptyEnvironment 0)
uniform int uLists;           // 1: start from the receiver's list of sub-trees (MIP-PBGI, X-PBGI), 0: from the root
// 1: an m-pixel nothing covered sees the environment; the gather then owns the environment's
// light on receivers (direct light leaves the sky off their diffuse lobes: unshadowed, it would
// count the sky behind the scan).
uniform int uEmptyEnvironment;

const float kFar = 3.0e38;
const float kTwoPi = 6.2831853;
uint mbBase, stackBase;

// The nearest sample wins; at equal depth the smaller colour (red, then green, then blue), so that
// the m-pixel does not depend on the order samples arrive in: X-PBGI's receiver lists are built
// by atomics, in whatever order the pairs ran, and coincident discs tie.
void writeM(int k, vec3 c, float t) {
  uint a = mbBase + uint(k);
  vec4 m = mbs[a];
  bool wins = t < m.a ||
              (t == m.a && (c.r < m.r || (c.r == m.r && (c.g < m.g || (c.g == m.g && c.b < m.b)))));
  if (wins) mbs[a] = vec4(c, t);
}

// The m-pixel of direction wl (receiver frame).
void pointSplat(vec3 wl, vec3 col, float t) {
  if (wl.z <= 0.0) return;
  vec2 s = wl.xy / (1.0 + wl.z);
  ivec2 p = clamp(ivec2((s * 0.5 + 0.5) * float(M)), ivec2(0), ivec2(M - 1));
  int k = p.y * M + p.x;
  if (micro[k].w > 0.0) writeM(k, col, t);
}

// r: the node's sphere; disc: a leaf's disc radius (at most r).
void startSplat(Receiver R, mat3 F, vec3 c, float r, float disc, vec3 nrm, bool leaf, vec3 col, inout PbgiTraversal st) {
  vec3 d = c - R.x;
  float dist = length(d);
  vec3 wl = (d / max(dist, 1e-30)) * F;
  float beta = dist > r ? asin(r / dist) : kTwoPi;
  // |d map / d angle| <= 1 in the upper hemisphere: the node spans at most beta M / 2 m-pixels
  // either side of its centre's.
  float halfWidth = beta * float(M) * 0.5;
  if (halfWidth < 1.0) {
    pointSplat(wl, col, max(dist - r, 0.0));
    return;
  }
  vec2 s = wl.xy / max(1.0 + wl.z, 1e-3);
  vec2 centre = (s * 0.5 + 0.5) * float(M);
  ivec2 lo = clamp(ivec2(floor(centre - halfWidth - 1.0)), ivec2(0), ivec2(M - 1));
  ivec2 hi = clamp(ivec2(ceil(centre + halfWidth + 1.0)), ivec2(0), ivec2(M - 1));
  if (dist <= r) lo = ivec2(0), hi = ivec2(M - 1);
  st.header.yzw = uvec3(1u, 0u, 0u);
  st.sphere = vec4(c, r);
  st.colour = vec4(col, leaf ? 1.0 : 0.0);
  st.normal = vec4(nrm, disc);
  st.box = ivec4(lo, hi);
}

// One m-pixel of the splat in progress.
void splatStep(Receiver R, mat3 F, inout PbgiTraversal st) {
  ivec4 b = st.box;
  int w = b.z - b.x + 1, h = b.w - b.y + 1;
  int cur = int(st.header.z);
  int k = (b.y + cur / w) * M + b.x + cur % w;
  vec3 c = st.sphere.xyz;
  float r = st.sphere.w;
  vec3 nrm = st.normal.xyz;
  vec3 d = c - R.x;
  float dist = length(d);
  vec3 wdir = d / max(dist, 1e-30);
  vec4 m = micro[k];
  if (m.w > 0.0) {
    vec3 dir = F * normalize(m.xyz);
    float denom = dot(dir, nrm);
    float t = -1.0;
    if (st.colour.w > 0.5) {  // a leaf: its disc
      if (abs(denom) >= 1e-6) {
        float tt = dot(d, nrm) / denom;
        if (tt > 0.0 && length(R.x + tt * dir - c) <= st.normal.w) t = tt;
      }
    } else {  // an inner node: its silhouette, at its mean plane's depth
      float cosB = dist > r ? sqrt(max(1.0 - (r / dist) * (r / dist), 0.0)) : -1.0;
      if (dot(dir, wdir) >= cosB) {
        t = abs(denom) > 1e-6 ? dot(d, nrm) / denom : dist;
        t = clamp(t, max(dist - r, 0.0), dist + r);
      }
    }
    if (t >= 0.0) {
      writeM(k, st.colour.rgb, t);
      st.header.w = 1u;
    }
  }
  st.header.z = uint(cur + 1);
  if (cur + 1 >= w * h) {
    st.header.y = 0u;
    if (st.header.w == 0u) pointSplat(wdir * F, st.colour.rgb, max(dist - r, 0.0));
  }
}

Receiver nodeReceiver(uvec2 e) {
  BshNode A = fetchNode(e);
  Receiver R;
  R.n = A.links.w != 0u ? decodeNormal(A.links.w) : vec3(0.0, 0.0, 1.0);
  R.wo = R.n;
  R.x = A.sphere.xyz + R.n * (1.5 * uintBitsToFloat(cutNodes[e.y - 1u].range.w));
  R.mat.type = NL_MATERIAL_LAMBERT;
  R.mat.baseColor = vec3(1.0);
  R.mat.roughness = 1.0, R.mat.metallic = 0.0, R.mat.specular = 0.5, R.mat.specularTint = 0.0;
  R.mat.sheen = 0.0, R.mat.sheenTint = 0.5, R.mat.clearcoat = 0.0, R.mat.clearcoatGloss = 1.0;
  return R;
}

void main() {
  int idx = int(gl_GlobalInvocationID.x);
  if (idx >= uCount) return;
  uint receiver = uint(uFirst + idx);
  uvec2 node = uvec2(0u);
  ivec2 px = ivec2(0);
  if (uNodeReceivers != 0) {
    node = uvec2(receivers[5u + 2u * receiver], receivers[4u + 2u * receiver]);  // (index, tree)
  } else {
    uint p = receivers[4u + receiver];
    px = ivec2(int(p & 0xffffu), int(p >> 16));
  }
  mbBase = uint(idx) * uint(M * M);
  stackBase = uint(idx) * uint(PBGI_STACK);
  PbgiTraversal st;
  if (uInit != 0) {
    for (int k = 0; k < M * M; ++k) mbs[mbBase + uint(k)] = vec4(0.0, 0.0, 0.0, kFar);
    st.header = uvec4(uTopCount > 0 && uLists == 0 ? 1u : 0u, 0u, 0u, 0u);
    stacks[stackBase] = uvec2(0u, 0u);
    st.list = uvec4(uLists != 0 ? listHead[uint(px.y) * uint(frame.tile.z) + uint(px.x)] : PBGI_END, 0u, 0u, 0u);
  } else {
    st = states[idx];
  }
  if (st.header.x == PBGI_DONE) return;
  Receiver R = uNodeReceivers != 0 ? nodeReceiver(node) : receiverAt(px);
  mat3 F = frameFromNormal(R.n);

  bool finished = false;
  for (int step = 0; step < uBudget; ++step) {
    if (st.header.y != 0u) {
      splatStep(R, F, st);
      continue;
    }
    uvec2 e;
    if (st.header.x == 0u) {
      if (st.list.x == PBGI_END) {
        finished = true;
        break;
      }
      uvec4 entry = list[st.list.x];  // the next sub-tree the pairs left this receiver
      e = entry.xy;
      st.list.x = entry.z;
    } else {
      st.header.x--;
      e = stacks[stackBase + st.header.x];
    }
    BshNode A = fetchNode(e);
    vec3 c = A.sphere.xyz;
    float r = A.sphere.w;
    vec3 d = c - R.x;
    float dist = length(d);
    if (dot(d, R.n) < -r) continue;  // wholly below the tangent plane
    bool hasAxis = A.links.w != 0u;
    vec3 axis = hasAxis ? decodeNormal(A.links.w) : vec3(0.0);
    bool inside = dist <= r;
    if (!inside && hasAxis) {
      float bound = A.colour.w + 1.5707963 + asin(r / dist);
      if (bound < 3.14159265 && acos(clamp(dot(-d / dist, axis), -1.0, 1.0)) > bound) continue;  // eq. 5
    }
    bool leaf = A.links.x == BSH_LEAF;
    if (leaf && e.y == 0u) {  // a top-tree leaf: enter that node's own hierarchy
      stacks[stackBase + st.header.x++] = uvec2(0u, A.links.y + 1u);
      continue;
    }
    float omega = inside ? kTwoPi : kTwoPi * (1.0 - sqrt(max(1.0 - (r / dist) * (r / dist), 0.0)));
    if (leaf || omega <= uOmegaCut) {
      float disc = leaf ? min(uintBitsToFloat(A.links.y), r) : r;
      startSplat(R, F, c, r, disc, hasAxis ? axis : -d / max(dist, 1e-30), leaf, A.colour.rgb, st);
    } else if (st.header.x + 2u <= uint(PBGI_STACK)) {
      stacks[stackBase + st.header.x++] = uvec2(A.links.y, e.y);
      stacks[stackBase + st.header.x++] = uvec2(A.links.x, e.y);
    } else {
      atomicAdd(receivers[2], 1u);  // cannot happen within BSH_MAX_DEPTH; counted, never silent
    }
  }
  if (!finished && st.header.x == 0u && st.header.y == 0u && st.list.x == PBGI_END) finished = true;

  if (finished) {
    // Eq. 7: L = sum brdf(w_ij, wo) C_ij Omega_ij cos(theta_ij).
    vec3 woL = R.wo * F;
    vec3 L = vec3(0.0);
    for (int k = 0; k < M * M; ++k) {
      vec4 m = micro[k];
      if (m.w <= 0.0) continue;
      vec4 b = mbs[mbBase + uint(k)];
      vec3 wi = normalize(m.xyz);
      vec3 C = b.a < kFar ? b.rgb : (uEmptyEnvironment != 0 ? environmentOver(F * wi, m.w) : uEmpty);
      L += evalBsdf(R.mat, woL, wi) * C * m.w * m.z;
    }
    if (uNodeReceivers != 0) {
      gathered[cutNodes[node.y - 1u].range.x + node.x] = vec4(L, 1.0);
    } else {
      vec4 direct = texelFetch(uDirect, px, 0);
      imageStore(uOut, px, vec4(direct.rgb + L, direct.a));
    }
    st.header.x = PBGI_DONE;
  } else {
    atomicAdd(receivers[1], 1u);
  }
  states[idx] = st;
}
