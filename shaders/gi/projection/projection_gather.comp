// Final gathering by importance-driven point projection (Maletz, Wang and Bowers, "Importance-
// Driven Point Projection for GPU-based Final Gathering", 2011, sections 3.2 and 4): one
// workgroup per listed pixel (projection_select.comp's list), its invocations sharing the
// clusters; it writes the pixel's irradiance and the rest of its BSDF's light apart. Per cluster, N_rnd random
// points give the cluster's importance (eq. 1: the projected solid angle, |cos| at the source, so
// that back-facing points, which still shadow, count) and are splatted; the importances, taken as
// a pdf, share N_s = samples_per_cluster x K importance samples among the clusters (allocateSamples,
// projection_allocate.glsl), each drawn uniformly in its cluster and splatted with the solid angle
// it stands for (eq. 3 in eq. 5's disc form, bounded as the point nears the receiver). The
// micro-buffer is the hemi-octahedral map of the receiver's upper hemisphere (eq. 2), depth-tested
// by atomicMin on (quantised distance << 12 | sample); its texels' radiance times the BSDF, the
// cosine and the texel's solid angle is the gathered light. Empty texels are the environment
// (the gather owns the sky then) or black.
//
// Glossy (section 3.2, eq. 4): a glossy receiver's importance is times its BSDF toward the point;
// a glossy surfel with lobes (glossy_to_glossy, projection_light.comp) sends each receiver its
// diffuse radiance plus what its lobes reflect toward it, and its importance grows by that.
//
// `sampling` random: every sample uniform over S (p_k of each cluster its share of the points);
// brute: all of S, each point its own area (the reference micro-buffer).
layout(local_size_x = 64) in;
#include "projection_common.glsl"
#include "projection_map.glsl"
#include "projection_upsample_weights.glsl"
layout(std430, binding = PROJECTION_SSBO_LIST) readonly buffer List { uint list[]; };

#ifndef PROJECTION_K
#define PROJECTION_K 512  // clusters: the method compiles with its own; this is for validators
#endif
#ifndef PROJECTION_SAMPLES
#define PROJECTION_SAMPLES 3072  // K x (random + importance samples per cluster)
#endif
#define PROJECTION_ALLOCATE_K PROJECTION_K

layout(std430, binding = PROJECTION_SSBO_POINTS) readonly buffer Points { ProjectionPoint points[]; };
layout(std430, binding = PROJECTION_SSBO_CLUSTERS) readonly buffer Clusters { uint clusterFirst[]; };
layout(std430, binding = PROJECTION_SSBO_SOLID) readonly buffer Solid { float texelSolidAngle[]; };
layout(std430, binding = PROJECTION_SSBO_RADIANCE) readonly buffer Radiance { vec4 radiance[]; };
layout(std430, binding = PROJECTION_SSBO_STATS) buffer Stats { uint stats[]; };
// dump_pixels: the listed pixels' micro-buffers, M x M texels each (rgb: the light the texel
// sends, a: 1 where a sample covers it, 0 for a hole), written instead of their light.
layout(std430, binding = PROJECTION_SSBO_FILTERED) writeonly buffer Dump { vec4 dumpTexels[]; };
uniform bool uDump;

uniform int uRandomPerCluster;   // N_rnd
uniform int uSamplesPerCluster;  // N_s / K
uniform int uSampling;           // 0 importance, 1 random, 2 brute
uniform int uSplat;              // 0 adaptive (eq. 3), else a fixed square of this side
uniform float uMaxDistance;      // the depth words' range: the scene's diagonal
uniform bool uSkyOwned;          // empty texels are the environment
uniform uint uSeed;
uniform int uFillPasses;         // hole-filling passes over the micro-buffer
uniform uint uRowItems;          // list entries per row of workgroups (the dispatch's x size)
uniform uint uListOffset;        // the list entries this dispatch gathers: [offset, end)
uniform uint uListEnd;
uniform bool uPointReceivers;    // the list holds points of S (further bounces), not pixels
uniform bool uHasLobes;          // S holds glossy surfels with lobes (glossy_to_glossy)

shared uint sKey[M * M];
shared uint sSample[PROJECTION_SAMPLES];
shared uint sTexelPoint[M * M];  // brute force: the point each texel shows; else the fill's copy
shared float sWeight[PROJECTION_K];
// Each cluster's sample count from the allocation, then (in place) its first sample slot, with
// the end after the last: one array, as llvmpipe gives a workgroup 32 KiB of shared memory and
// 4,096 samples with 512 clusters need all but 2 KiB of it.
shared int sBase[PROJECTION_K + 1];
shared float sTotal;
shared bool sWeighted;
shared vec3 sSum[64], sRest[64];
shared uint sTruncated;

// llvmpipe ends the loops of an invocation, silently, once they have made 65,535 iterations in
// all (its loop limiter is shared by an invocation's loops). The main loops check, after they end,
// that they ran to their bound: where one did not, the receiver is counted truncated (a summary
// line; a dumped micro-buffer says so) instead of reading as if its micro-buffer held everything.
// Brute force over all of a large S met it (a ceiling pixel's map 61 of 1024 texels covered).
void truncatedUnless(bool ranToTheEnd) {
  if (!ranToTheEnd) atomicOr(sTruncated, 1u);
}

float allocateWeight(int k) { return sWeight[k]; }
void allocateStore(int k, int n) { sBase[k] = n; }
int allocateLoad(int k) { return sBase[k]; }
#include "projection_allocate.glsl"

uint hashU(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
uint gRng;
uint nextU() {
  gRng = hashU(gRng);
  return gRng;
}
float nextF() { return float(nextU() >> 8) * (1.0 / 16777216.0); }

Receiver gR;
mat3 gShadeFromWorld;  // the receiver's BSDF frame (rows: tangent, bitangent, normal)
vec3 gWoLocal;
bool gGlossyReceiver;
vec2 gFootT;     // the last footprint's centre (texels)
float gFootR2;   // its disc's squared radius (texels; negative: a square)
mat3 gLocalFromWorld;  // rows: tangent, normal, bitangent (the map's +y is the normal)

MaterialParams recordMaterial(MaterialRecord r) {
  MaterialParams m;
  m.type = int(r.baseColor.w);
  m.baseColor = r.baseColor.rgb;
  m.roughness = r.params.x, m.metallic = r.params.y, m.specular = r.params.z;
  m.specularTint = r.params.w, m.sheen = r.params2.x, m.sheenTint = r.params2.y;
  m.clearcoat = r.params2.z, m.clearcoatGloss = r.params2.w;
  return m;
}

// What a glossy surfel's lobes reflect toward `toReceiver` (unit, from the point): per lobe its
// BSDF's glossy part (less the diffuse lobe, which its radiance holds) times the irradiance its
// light gives. 0 for the other points.
vec3 lobesToward(ProjectionPoint P, vec3 toReceiver) {
  uint slot = P.source.y;
  if (slot == 0u || P.source.x == 0u) return vec3(0.0);
  uint word = floatBitsToUint(P.normalColour.x);
  if (word == 0u) return vec3(0.0);
  mat3 f = frameFromNormal(decodeNormal(word));
  vec3 woL = toReceiver * f;
  if (woL.z <= 0.0) return vec3(0.0);
  MaterialParams m = recordMaterial(materials[P.source.x - 1u]);
  vec3 lambert = diffuseAlbedo(m) * kInvPi;
  uint count = clusterFirst[PROJECTION_K];
  uint at = count + uint(2 * PROJECTION_LOBES) * (slot - 1u);
  vec3 L = vec3(0.0);
  for (int j = 0; j < PROJECTION_LOBES; ++j) {
    vec3 E = radiance[at + uint(2 * j) + 1u].rgb;
    if (E == vec3(0.0)) continue;
    vec3 wiL = radiance[at + uint(2 * j)].xyz * f;
    L += max(evalBsdf(m, woL, wiL) - lambert, vec3(0.0)) * E;
  }
  return L;
}

// Eq. 1's term for point s: max(cos at the receiver, 0) |cos at s| dA / d^2; 0 below the
// receiver's horizon and within the point's own radius of the receiver (its own surface). Eq. 4:
// a glossy receiver's BSDF toward s times it; a glossy source's lobes toward the receiver over
// its diffuse radiance add to it (capped: a surfel without diffuse light would take all).
float importanceOf(ProjectionPoint s, uint index) {
  vec3 d = s.positionArea.xyz - gR.x;
  float d2 = dot(d, d);
  float area = s.positionArea.w;
  if (d2 <= area * (1.0 / kPi)) return 0.0;
  float inv = inversesqrt(d2);
  float cosP = dot(gR.n, d) * inv;
  if (cosP <= 0.0) return 0.0;
  uint word = floatBitsToUint(s.normalColour.x);
  float cosS = word != 0u ? abs(dot(decodeNormal(word), d)) * inv : 1.0;
  float w = cosP * cosS * area / d2;
  if (gGlossyReceiver) w *= luminance(evalBsdf(gR.mat, gWoLocal, gShadeFromWorld * (d * inv)));
  if (s.source.y != 0u) {
    float glossy = luminance(lobesToward(s, -d * inv));
    float diffuse = luminance(radiance[index].rgb);
    w *= 1.0 + min(glossy / max(diffuse, 1e-6 * glossy + 1e-30), 64.0);
  }
  return w;
}

// Where point `index`, standing for `area` of surface, lands in the micro-buffer: the texels
// [lo, hi), its quantised distance q and whether it shows the receiver its back. False: below
// the horizon, or the receiver's own surface (within the point's radius).
bool footprint(uint index, float area, out ivec2 lo, out ivec2 hi, out uint q, out bool back) {
  ProjectionPoint s = points[index];
  vec3 d = s.positionArea.xyz - gR.x;
  float d2 = dot(d, d);
  lo = hi = ivec2(0);
  q = 0u;
  back = false;
  if (d2 <= s.positionArea.w * (1.0 / kPi)) return false;
  vec3 w = gLocalFromWorld * d;
  if (w.y <= 0.0) return false;
  float dist = sqrt(d2);
  uint word = floatBitsToUint(s.normalColour.x);
  vec3 n = word != 0u ? decodeNormal(word) : -d / dist;
  float cosS = abs(dot(n, d)) / dist;
  back = word != 0u && dot(n, d) > 0.0;
  vec2 t = hemiOctEncode(w) * float(M);
  ivec2 c = clamp(ivec2(t), ivec2(0), ivec2(M - 1));
  q = uint(clamp(dist / uMaxDistance, 0.0, 1.0) * 1048575.0);
  gFootT = t;
  int side = uSplat;
  if (side == 0) {
    // Eq. 5: the disc-to-point solid angle, bounded as the point nears the receiver; over the
    // texel's solid angle, the texels it covers: a disc of that area about the sample, which
    // covers the texels whose centres it holds (its radius at least 0.36 texels, so that a lone
    // sample lands somewhere 41% of the time and holes close by the fill). The paper writes a
    // square of at least one texel: every texel a point falls in then counts whole, and a
    // surface's outline grows by half a texel all round (the side face of a box under a half
    // sphere of emitters read 3.4% bright at 32 x 32 with every point splatted, 1.8% now).
    float omega = 2.0 * kPi * area * max(cosS, 1e-3) / (area + 2.0 * kPi * d2);
    float texels = omega / texelSolidAngle[c.y * M + c.x];
    float r = max(sqrt(texels / kPi), 0.36);
    gFootR2 = r * r;
    lo = clamp(ivec2(floor(t - r)), ivec2(0), ivec2(M - 1));
    hi = clamp(ivec2(ceil(t + r)), ivec2(0), ivec2(M));
    return true;
  }
  gFootR2 = -1.0;  // a fixed square
  lo = clamp(ivec2(floor(t - 0.5 * float(side) + 0.5)), ivec2(0), ivec2(M - 1));
  hi = min(lo + ivec2(side), ivec2(M));
  return true;
}

// Whether the last footprint covers texel (x, y).
bool covers(int x, int y) {
  if (gFootR2 < 0.0) return true;
  vec2 d = vec2(x, y) + 0.5 - gFootT;
  return dot(d, d) <= gFootR2;
}

uint keyAt(ivec2 c) {
  return all(greaterThanEqual(c, ivec2(0))) && all(lessThan(c, ivec2(M))) ? sKey[c.y * M + c.x]
                                                                           : PROJECTION_NO_SAMPLE;
}

// The nearer sample of an empty texel's neighbours when two opposite ones are covered.
uint holeFill(ivec2 c) {
  const ivec2 dirs[4] = ivec2[4](ivec2(1, 0), ivec2(0, 1), ivec2(1, 1), ivec2(1, -1));
  uint best = PROJECTION_NO_SAMPLE;
  for (int i = 0; i < 4; ++i) {
    uint a = keyAt(c + dirs[i]), b = keyAt(c - dirs[i]);
    if (a != PROJECTION_NO_SAMPLE && b != PROJECTION_NO_SAMPLE) best = min(best, min(a, b));
  }
  return best;
}

// Splats sample `slot` (point `index`, standing for `area`): the nearest sample wins each texel.
void splat(uint index, uint slot, float area) {
  ivec2 lo, hi;
  uint q;
  bool back;
  if (!footprint(index, area, lo, hi, q, back)) return;
  sSample[slot] = index | (back ? PROJECTION_BACK_FACING : 0u);
  uint key = (q << 12) | slot;
  int y = lo.y;
  for (; y < hi.y; ++y)
    for (int x = lo.x; x < hi.x; ++x)
      if (covers(x, y)) atomicMin(sKey[y * M + x], key);
  truncatedUnless(y >= hi.y);
  if (!uPointReceivers && !uDump) atomicAdd(stats[3], 1u);
}

void main() {
  uint item = uListOffset + gl_WorkGroupID.y * uRowItems + gl_WorkGroupID.x;
  uint lid = gl_LocalInvocationID.x;
  if (item >= min(list[0], uListEnd)) return;
  uint word = list[4u + item];
  ivec2 px = ivec2(int(word & 0xffffu), int(word >> 16));
  if (uPointReceivers) {
    // A further bounce (paper section 3.1): a point of S gathers, from a splat radius and a half
    // above its surface along its normal, the light its diffuse reflection then sends on.
    ProjectionPoint P = points[word];
    uint nw = floatBitsToUint(P.normalColour.x);
    if (nw == 0u) {
      if (lid == 0u) pixels[2u * item] = vec4(0.0);
      return;
    }
    gR.n = decodeNormal(nw);
    gR.x = P.positionArea.xyz + gR.n * 1.5 * sqrt(P.positionArea.w * kInvPi);
    gR.wo = gR.n;
    gR.mat.type = NL_MATERIAL_LAMBERT;
    gR.mat.baseColor = vec3(1.0);
    px = ivec2(int(word % 65536u), int(word / 65536u) + 65536);
  } else {
    if (uDump && !isReceiver(px)) {  // nothing gathers there: say so
      for (uint t = lid; t <= uint(M * M); t += 64u) dumpTexels[item * uint(M * M + 1) + t] = vec4(-1.0);
      return;
    }
    gR = receiverAt(px);
  }
  mat3 f = frameFromNormal(gR.n);  // columns: tangent, bitangent, normal
  gLocalFromWorld = transpose(mat3(f[0], f[2], f[1]));
  gShadeFromWorld = transpose(f);
  gWoLocal = gShadeFromWorld * gR.wo;
  gGlossyReceiver = gR.mat.type != NL_MATERIAL_LAMBERT;
  uint filled = 0u;
  ivec2 g = px + ivec2(frame.tile.xy);  // the full image's pixel: tiles draw the same samples
  gRng = hashU(uint(g.x) * 73856093u ^ uint(g.y) * 19349663u ^ hashU(uSeed) ^ lid * 83492791u);
  for (uint t = lid; t < uint(M * M); t += 64u) sKey[t] = PROJECTION_NO_SAMPLE;
  if (lid == 0u) sTruncated = 0u;
  barrier();

  const int K = PROJECTION_K;
  uint total = clusterFirst[K];
  if (uSampling == 2) {
    // Brute force: every point, its own area; too many to tell apart by the depth word's 12
    // bits, so the nearest distance first, then the point at it.
    uint i = lid;
    for (; i < total; i += 64u) {
      ivec2 lo, hi;
      uint q;
      bool back;
      if (!footprint(i, points[i].positionArea.w, lo, hi, q, back)) continue;
      for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x)
          if (covers(x, y)) atomicMin(sKey[y * M + x], q << 12);
    }
    truncatedUnless(i >= total);
    barrier();
    for (i = lid; i < total; i += 64u) {
      ivec2 lo, hi;
      uint q;
      bool back;
      if (!footprint(i, points[i].positionArea.w, lo, hi, q, back)) continue;
      for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x)
          if (covers(x, y) && sKey[y * M + x] == q << 12) sTexelPoint[y * M + x] = i | (back ? PROJECTION_BACK_FACING : 0u);
    }
    truncatedUnless(i >= total);
  } else {
    int nRnd = uRandomPerCluster;
    int k = int(lid);
    for (; k < K; k += 64) {
      uint first = clusterFirst[k], size = clusterFirst[k + 1] - first;
      float w = 0.0;
      for (int j = 0; j < nRnd && size > 0u; ++j) {
        uint index = first + nextU() % size;
        ProjectionPoint s = points[index];
        w += importanceOf(s, index);
        splat(index, uint(k * nRnd + j), float(size) * s.positionArea.w / float(nRnd));
      }
      // Random sampling: each cluster by its share of the points.
      sWeight[k] = uSampling == 1 ? float(size) : w;
    }
    truncatedUnless(k >= K);
    barrier();
    if (lid == 0u) {
      sWeighted = allocateSamples(K * uSamplesPerCluster, nextF());
      float sum = 0.0;
      for (int k = 0; k < K; ++k) sum += sWeight[k];
      sTotal = sum;
      int base = K * nRnd;
      for (int k = 0; k < K; ++k) {
        int count = sBase[k];
        sBase[k] = base, base += count;
      }
      sBase[K] = base;
      if (!sWeighted && !uDump) atomicAdd(stats[1], 1u);
    }
    barrier();
    float ns = float(K * uSamplesPerCluster);
    for (k = int(lid); k < K; k += 64) {
      uint first = clusterFirst[k], size = clusterFirst[k + 1] - first;
      int n = sBase[k + 1] - sBase[k];
      if (size == 0u || n == 0) continue;
      // N_s p_k: the samples this cluster expects (uniform pdf: N_s / K).
      float expected = sWeighted ? ns * sWeight[k] / sTotal : ns / float(K);
      for (int j = 0; j < n; ++j) {
        uint index = first + nextU() % size;
        splat(index, uint(sBase[k] + j), float(size) * points[index].positionArea.w / expected);
      }
    }
    truncatedUnless(k >= K);
  }
  barrier();
  // Holes between splats: samples drawn at random in their clusters do not tile the map, and
  // the texels between them would read as empty (the sky, or black: the furnace read 4.4% dark
  // with 92% of its texels covered). A texel nothing covered whose neighbours on two opposite
  // sides are covered lies inside a surface: it takes the nearer of its neighbours' samples.
  // Twice, so holes up to about three texels across close; a surface's outline, covered on one
  // side only, does not grow.
  if (uSampling != 2) {
    for (int pass = 0; pass < uFillPasses; ++pass) {
      for (uint t = lid; t < uint(M * M); t += 64u) {
        uint key = sKey[t];
        if (key == PROJECTION_NO_SAMPLE) key = holeFill(ivec2(int(t) % M, int(t) / M));
        sTexelPoint[t] = key;
      }
      barrier();
      for (uint t = lid; t < uint(M * M); t += 64u) {
        if (sKey[t] == PROJECTION_NO_SAMPLE && sTexelPoint[t] != PROJECTION_NO_SAMPLE) filled++;
        sKey[t] = sTexelPoint[t];
      }
      barrier();
    }
  }

  // The texels' light through the receiver's BSDF.
  mat3 worldFromMap = transpose(gLocalFromWorld);
  mat3 shadeFrame = frameFromNormal(gR.n);
  vec3 woLocal = transpose(shadeFrame) * gR.wo;
  vec3 sum = vec3(0.0), rest = vec3(0.0);
  vec3 lambert = diffuseAlbedo(gR.mat) * kInvPi;
  uint empty = 0u;
  uint t = lid;
  for (; t < uint(M * M); t += 64u) {
    ivec2 c = ivec2(int(t) % M, int(t) / M);
    vec3 w = worldFromMap * hemiOctDecode((vec2(c) + 0.5) / float(M));
    uint key = sKey[t];
    vec3 L;
    if (key == PROJECTION_NO_SAMPLE) {
      // Points of S have the sky (unshadowed) in their direct light already.
      L = uSkyOwned && !uPointReceivers ? environment(w) : vec3(0.0);
      empty++;
    } else {
      uint s = uSampling == 2 ? sTexelPoint[t] : sSample[key & 4095u];
      uint at = s & 0x7fffffffu;
      if ((s & PROJECTION_BACK_FACING) != 0u) {
        L = vec3(0.0);
      } else {
        L = radiance[at].rgb;
        // The point's record only where S has glossy surfels: this loop runs for every texel.
        if (uHasLobes) {
          ProjectionPoint P = points[at];
          if (P.source.y != 0u) L += lobesToward(P, normalize(gR.x - P.positionArea.xyz));
        }
      }
    }
    if (uDump)  // alpha: 1 covered, 0 a hole
      dumpTexels[item * uint(M * M + 1) + t] = vec4(L, key == PROJECTION_NO_SAMPLE ? 0.0 : 1.0);
    vec3 wiLocal = transpose(shadeFrame) * w;
    if (wiLocal.z <= 0.0) continue;
    // Irradiance (the diffuse lobe's, re-applied with each pixel's own albedo after
    // interpolation) and the rest of the BSDF's light apart.
    vec3 e = L * wiLocal.z * texelSolidAngle[t];
    sum += e;
    rest += e * (evalBsdf(gR.mat, woLocal, wiLocal) - lambert);
  }
  truncatedUnless(t >= uint(M * M));
  sSum[lid] = sum;
  sRest[lid] = rest;
  // The counters describe the pixels' micro-buffers (the points' of further bounces are not).
  if (empty > 0u && !uPointReceivers && !uDump) atomicAdd(stats[2], empty);
  if (filled > 0u && !uPointReceivers && !uDump) atomicAdd(stats[4], filled);
  barrier();
  // After each dumped map, whether its receiver was truncated.
  if (uDump && lid == 0u) dumpTexels[item * uint(M * M + 1) + uint(M * M)] = vec4(float(sTruncated));
  if (lid == 0u && !uDump) {
    vec3 e = vec3(0.0), r = vec3(0.0);
    for (int i = 0; i < 64; ++i) e += sSum[i], r += sRest[i];
    if (uPointReceivers) {
      pixels[2u * item] = vec4(e, 0.0);
    } else {
      atomicAdd(stats[0], 1u);
      if (sTruncated != 0u) atomicAdd(stats[6], 1u);
      uint i = uint(px.y * int(frame.tile.z) + px.x);
      pixels[2u * i] = vec4(e, PROJECTION_GATHERED);
      pixels[2u * i + 1u] = vec4(r, 0.0);
    }
  }
}
