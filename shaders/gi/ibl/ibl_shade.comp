// Direct environment lighting of every receiver pixel, by one of the estimators of Kronander,
// Dahlin, Jönsson, Kok, Schön and Unger, "Real-time video based lighting using GPU raytracing"
// (2014): multiple importance sampling with the balance heuristic (section 4, eq. 2),
// bidirectional importance sampling by sampling-importance-resampling from the BSDF (section 5,
// eq. 3 and 4), and the sequential Monte Carlo sampler (section 6, eq. 5 to 8) that carries each
// pixel's samples from frame to frame (after Ghosh, Doucet and Heidrich 2006), reprojected as the
// camera moves. Visibility by rays (ibl_visibility.glsl). docs/IBL.md gives the deviations.
layout(local_size_x = 8, local_size_y = 8) in;
#include "../common/gbuffer_in.glsl"
#include "../common/brdf_sample.glsl"
#include "../common/environment.glsl"
#include "ibl_interface.glsl"
#include "ibl_environment.glsl"
#include "ibl_visibility.glsl"
#ifndef IBL_SMC_N
#define IBL_SMC_N 8
#endif
#define IBL_STATE_STRIDE (8 + 2 * IBL_SMC_N)
#define IBL_PICKS_MAX 64  // BIS: N at most (IblParameters)

layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = 4) uniform sampler2D uDirect;
layout(binding = 6) uniform sampler2D uEnvironmentPrev;  // SMC: the previous frame's map
layout(rgba32f, binding = 0) uniform image2D uOut;
layout(std430, binding = IBL_SSBO_STATS) buffer IblStats { uint stats[]; };
layout(std430, binding = IBL_SSBO_STATE_IN) readonly buffer StateIn { uint stateIn[]; };
layout(std430, binding = IBL_SSBO_STATE_OUT) writeonly buffer StateOut { uint stateOut[]; };

uniform int uEstimator;
uniform int uBrdfSamples, uEnvSamples;  // MIS: N_rho, N_L
uniform int uBisM, uBisN;               // BIS: proposals M, resampled N
uniform int uIntermediate;              // SMC: intermediate distributions per frame
uniform float uLocalProbability;        // SMC: nu, the share of local Metropolis-Hastings moves
uniform float uLocalCos;                // SMC: cos of a local move's largest angle
uniform float uReinitRatio;             // SMC: reinitialise when Z_t / Z_t-1 exceeds it...
uniform bool uReinitOnDrop;             // ...or (when set) falls below its inverse
uniform bool uVisibility;
uniform uint uSeed;
uniform bool uHasPrevious;              // SMC: the state buffer holds the previous frame's samples
uniform mat4 uPrevClipFromWorld;
uniform float uPrevEnvScale;
uniform int uStateRowWords;
uniform int uRowOffset, uRows;
// Passes: a pixel's samples are split over uPasses dispatches (at most IBL_PASS_SAMPLES BSDF and
// environment samples, or IBL_PASS_PROPOSALS BIS proposals, each), so that no invocation nears
// llvmpipe's 65,535 loop iterations; pass 0 writes direct light plus its share, the others add.
uniform int uPass, uPasses;  // the tile rows this dispatch shades (SMC: a band whose state fits the bound ranges)
uniform int uStateRowIn, uStateRowsIn;    // SMC: the image rows the bound state ranges hold (read...
uniform int uStateRowOut, uStateRowsOut;  // ...and written), each uStateRowWords words

// PCG's output permutation (O'Neill 2014) hashes a seed and steps the stream.
uint rngState;
uint pcgHash(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
float rnd() {
  rngState = pcgHash(rngState);
  return float(rngState >> 8) * (1.0 / 16777216.0);
}
vec2 rnd2() { return vec2(rnd(), rnd()); }

struct Shade {
  vec3 x, n;
  mat3 F;       // local -> world, n = +z
  vec3 woL;
  MaterialParams mat;
};
Shade S;
uint rays = 0u;

vec3 toLocal(vec3 d) { return vec3(dot(d, S.F[0]), dot(d, S.F[1]), dot(d, S.F[2])); }
float visible(vec3 d) {
  if (!uVisibility) return 1.0;
  rays++;
  return meshesOcclude(S.x, d, 1e30) || scanOccludes(S.x, d, 1e30) ? 0.0 : 1.0;
}
vec3 bsdf(vec3 wiL) { return evalBsdf(S.mat, S.woL, wiL); }
float envPrevLuminance(vec3 d) {
  ivec2 size = textureSize(uEnvironmentPrev, 0);
  float theta = atan(length(d.xy), d.z);
  float u = (atan(d.y, d.x) - uEnvRotation) / (2.0 * kPi);
  u -= floor(u);
  ivec2 t = min(ivec2(vec2(u, clamp(theta / kPi, 0.0, 1.0)) * vec2(size)), size - 1);
  return luminance(texelFetch(uEnvironmentPrev, t, 0).rgb) * uPrevEnvScale;
}
// The un-occluded target of eq. 3 at this frame, and with the previous frame's map (SMC).
float target(vec3 d) {
  vec3 wiL = toLocal(d);
  if (!(wiL.z > kMinCos)) return 0.0;
  return luminance(environment(d)) * luminance(bsdf(wiL)) * wiL.z;
}
float targetPrevious(vec3 d) {
  vec3 wiL = toLocal(d);
  if (!(wiL.z > kMinCos)) return 0.0;
  return envPrevLuminance(d) * luminance(bsdf(wiL)) * wiL.z;
}
// gamma_beta = previous^(1 - beta) target^beta: the intermediate distributions between frames.
float bridge(float previous, float current, float beta) {
  if (beta >= 1.0) return current;
  if (beta <= 0.0) return previous;
  if (previous <= 0.0 || current <= 0.0) return 0.0;
  return exp((1.0 - beta) * log(previous) + beta * log(current));
}
// L rho V / (L_Y rho_Y): a resampled direction's contribution over its target (eq. 4 and 7).
vec3 ratioContribution(vec3 d) {
  vec3 wiL = toLocal(d);
  if (!(wiL.z > kMinCos)) return vec3(0.0);
  vec3 L = environment(d), f = bsdf(wiL);
  float y = luminance(L) * luminance(f);
  if (!(y > 0.0)) return vec3(0.0);
  return L * f * (visible(d) / y);
}

// This pass's share of n samples split over uPasses.
int passShare(int n) { return n / uPasses + (uPass < n % uPasses ? 1 : 0); }

// ---- MIS (eq. 2, the balance heuristic over N_rho BSDF and N_L environment samples) ----
// This pass's share of the samples, weighted with the totals' balance heuristic: the passes' sum
// is the estimator over all N_rho + N_L samples.
vec3 estimateMis(int totalRho, int totalL) {
  int nRho = passShare(totalRho), nL = passShare(totalL);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < nRho + nL; ++i) {
    loopSteps += 20u;  // the loop and an environment sample's two binary searches
    vec3 d, wiL;
    if (i < nRho) {
      if (!sampleBsdf(S.mat, S.woL, rnd2(), rnd(), wiL)) continue;
      d = S.F * wiL;
    } else {
      if (!envSample(rnd2(), d)) continue;
      wiL = toLocal(d);
      if (!(wiL.z > kMinCos)) continue;
    }
    vec3 Lf = environment(d) * bsdf(wiL) * wiL.z;
    if (!(dot(Lf, vec3(1.0)) > 0.0)) continue;
    float denom = float(totalRho) * pdfBsdf(S.mat, S.woL, wiL) + float(totalL) * envPdf(d);
    if (!(denom > 0.0)) continue;
    sum += Lf * (visible(d) / denom);
  }
  return sum;
}

// ---- BIS (eq. 3, 4): M proposals weighted by target / q, N resampled systematically ----
// The paper proposes from the BSDF alone; its weights gamma / q = L_Y rho_Y cos / q_rho then grow
// without bound on a small bright texel (a sun a BSDF sample finds once in a thousand: the pixel
// whose proposals find it gets Z-hat a thousand times its share, the rest nothing). Here proposals
// alternate between the BSDF and the environment (M_rho = ceil(M / 2), M_L = floor(M / 2)) and are
// weighed by the balance heuristic's mixture density, q = (M_rho q_rho + M_L q_L) / M (Veach and
// Guibas 1995; Hesterberg's defensive mixture): Z-hat stays unbiased for every M, with no clamp,
// and every weight is at most min((M / M_L) P rho_Y cos, (M / M_rho) L_Y rho_Y cos / q_rho) (P: the
// map's power), the better of the two samplers' own bounds. Proposals are drawn twice from the
// same random stream (a sum, then the picks), so nothing per proposal is stored. Returns Z-hat;
// `bisPicks` receives the N directions.
vec3 bisPicks[IBL_PICKS_MAX];
uint bisEnvSteps;  // loop iterations of one environment proposal's two binary searches (each pass)
// Proposal j of M: its direction and its target over the mixture density (0: none).
float bisProposal(int j, int M, out vec3 d) {
  vec2 u = rnd2();
  float uLobe = rnd();  // drawn for every proposal: both passes over them keep one stream
  bool env = (j & 1) == 1 && !envBlack();
  int mL = envBlack() ? 0 : M / 2, mRho = M - mL;
  vec3 wiL;
  if (env) {
    loopSteps += bisEnvSteps;
    if (!envSample(u, d)) return 0.0;
    wiL = toLocal(d);
  } else {
    if (!sampleBsdf(S.mat, S.woL, u, uLobe, wiL)) return 0.0;
    d = S.F * wiL;
  }
  if (!(wiL.z > kMinCos)) return 0.0;
  float q = (float(mRho) * pdfBsdf(S.mat, S.woL, wiL) + float(mL) * envPdf(d)) / float(M);
  return q > 0.0 ? target(d) / q : 0.0;
}
float bisSample(int M, int N) {
  bisEnvSteps = uint(findMSB(envWidth()) + findMSB(envHeight()) + 2);
  uint start = rngState;
  float total = 0.0;
  vec3 d;
  for (int j = 0; j < M; ++j) {
    loopSteps += 2u;  // this pass and the next
    total += bisProposal(j, M, d);
  }
  float u0 = rnd();
  uint after = rngState;
  if (!(total > 0.0) || isinf(total)) {
    rngState = after;
    return 0.0;
  }
  rngState = start;
  float run = 0.0;
  int k = 0;
  for (int j = 0; j < M && k < N; ++j) {
    float w = bisProposal(j, M, d);
    if (!(w > 0.0)) continue;
    run += w;
    while (k < N && (float(k) + u0) / float(N) * total < run) bisPicks[k++] = d;
  }
  for (; k < N; ++k) bisPicks[k] = bisPicks[max(k - 1, 0)];  // rounding at the very end
  rngState = after;
  return total / float(M);
}

// Each pass an independent BIS estimate from its share of the proposals and samples; their mean
// over the passes.
vec3 estimateBis(int totalM, int totalN) {
  int M = max(passShare(totalM), 1), N = max(passShare(totalN), 1);
  float Z = bisSample(M, N) / float(uPasses);
  if (!(Z > 0.0)) return vec3(0.0);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < N; ++i) sum += ratioContribution(bisPicks[i]);
  return Z * sum / float(N);
}

// ---- SMC (eq. 5 to 8) ----
vec3 dirs[IBL_SMC_N];
float W[IBL_SMC_N];

uint encodeDir(vec3 d) {
  vec2 e = d.xy / (abs(d.x) + abs(d.y) + abs(d.z));
  if (d.z < 0.0) e = (1.0 - abs(e.yx)) * vec2(e.x >= 0.0 ? 1.0 : -1.0, e.y >= 0.0 ? 1.0 : -1.0);
  uvec2 q = uvec2(round(clamp(e * 0.5 + 0.5, 0.0, 1.0) * 65535.0));
  return q.x | (q.y << 16);
}
vec3 decodeDir(uint w) {
  vec2 e = vec2(float(w & 0xffffu), float(w >> 16)) / 65535.0 * 2.0 - 1.0;
  vec3 n = vec3(e.xy, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return normalize(n);
}

// The independent proposal: the BSDF's and the environment's sampling, half each.
float independentPdf(vec3 d) {
  vec3 wiL = toLocal(d);
  float qb = pdfBsdf(S.mat, S.woL, wiL);
  return envBlack() ? qb : 0.5 * qb + 0.5 * envPdf(d);
}
bool independentSample(out vec3 d) {
  if (envBlack() || rnd() < 0.5) {
    vec3 wiL;
    bool ok = sampleBsdf(S.mat, S.woL, rnd2(), rnd(), wiL);
    d = S.F * wiL;
    return ok;
  }
  return envSample(rnd2(), d);
}
// A direction uniform in the cone of cos >= uLocalCos about d (a symmetric proposal).
vec3 localMove(vec3 d) {
  vec2 u = rnd2();
  float c = 1.0 - u.x * (1.0 - uLocalCos), s = sqrt(max(0.0, 1.0 - c * c)), phi = 2.0 * kPi * u.y;
  return normalize(frameFromNormal(d) * vec3(s * cos(phi), s * sin(phi), c));
}

uint moves = 0u, accepted = 0u;
// One Metropolis-Hastings move of every sample, leaving gamma_beta invariant (eq. 6).
void mhMove(float beta) {
  for (int i = 0; i < IBL_SMC_N; ++i) {
    vec3 d = dirs[i], p;
    bool local = rnd() < uLocalProbability;
    float ratio;
    float g = bridge(targetPrevious(d), target(d), beta);
    if (local) {
      p = localMove(d);
      float gp = bridge(targetPrevious(p), target(p), beta);
      ratio = g > 0.0 ? gp / g : (gp > 0.0 ? 1.0 : 0.0);
    } else {
      if (!independentSample(p)) continue;
      float gp = bridge(targetPrevious(p), target(p), beta);
      float qp = independentPdf(p), qd = independentPdf(d);
      ratio = g > 0.0 && qp > 0.0 ? (gp * qd) / (g * qp) : (gp > 0.0 ? 1.0 : 0.0);
    }
    moves++;
    if (rnd() < ratio) {
      dirs[i] = p;
      accepted++;
    }
  }
}

// Systematic resampling: N equally weighted copies in proportion to W.
void resample() {
  vec3 copy[IBL_SMC_N];
  for (int i = 0; i < IBL_SMC_N; ++i) copy[i] = dirs[i];
  float u0 = rnd(), run = 0.0;
  int k = 0;
  for (int i = 0; i < IBL_SMC_N && k < IBL_SMC_N; ++i) {
    run += W[i];
    while (k < IBL_SMC_N && (float(k) + u0) / float(IBL_SMC_N) < run) dirs[k++] = copy[i];
  }
  for (; k < IBL_SMC_N; ++k) dirs[k] = dirs[max(k - 1, 0)];  // rounding at the very end: the last pick again
  for (int i = 0; i < IBL_SMC_N; ++i) W[i] = 1.0 / float(IBL_SMC_N);
}

// Fresh samples by BIS (the paper's first frame and its reinitialisation). Returns Z.
float smcInit() {
  float Z = bisSample(uBisM, IBL_SMC_N);
  for (int i = 0; i < IBL_SMC_N; ++i) {
    dirs[i] = bisPicks[i];
    W[i] = 1.0 / float(IBL_SMC_N);
  }
  return Z;
}

// The previous frame's samples for this shading point, where it was seen (reprojection).
bool smcLoad(ivec2 gpx, vec3 x, out float Z) {
  Z = 0.0;
  if (!uHasPrevious) return false;
  vec4 c = uPrevClipFromWorld * vec4(x, 1.0);
  if (!(c.w > 0.0)) return false;
  vec2 ndc = c.xy / c.w;
  ivec2 p = ivec2(floor((ndc * 0.5 + 0.5) * frame.image.xy));
  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, ivec2(frame.image.xy)))) return false;
  if (p.y < uStateRowIn || p.y >= uStateRowIn + uStateRowsIn) return false;
  uint base = uint((p.y - uStateRowIn) * uStateRowWords + p.x * IBL_STATE_STRIDE);
  if (stateIn[base + 5u] != 1u) return false;
  vec3 xs = uintBitsToFloat(uvec3(stateIn[base], stateIn[base + 1u], stateIn[base + 2u]));
  vec3 ns = decodeDir(stateIn[base + 4u]);
  // The same surface point: within a few pixels' footprint (or 1% of the distance) and facing alike.
  float dist = length(x - frame.eye.xyz);
  float tol = max(0.01 * dist, 4.0 * dist / frame.eye.w);
  if (length(xs - x) > tol || dot(ns, S.n) < 0.9) return false;
  Z = uintBitsToFloat(stateIn[base + 3u]);
  for (int i = 0; i < IBL_SMC_N; ++i) {
    dirs[i] = decodeDir(stateIn[base + 8u + 2u * uint(i)]);
    W[i] = uintBitsToFloat(stateIn[base + 9u + 2u * uint(i)]);
  }
  return Z > 0.0 && !isinf(Z) && !isnan(Z);
}

void smcStore(ivec2 gpx, vec3 x, float Z, bool valid) {
  if (gpx.y < uStateRowOut || gpx.y >= uStateRowOut + uStateRowsOut || gpx.x < 0 || gpx.x >= int(frame.image.x)) return;
  uint base = uint((gpx.y - uStateRowOut) * uStateRowWords + gpx.x * IBL_STATE_STRIDE);
  uvec3 xb = floatBitsToUint(x);
  stateOut[base] = xb.x, stateOut[base + 1u] = xb.y, stateOut[base + 2u] = xb.z;
  stateOut[base + 3u] = floatBitsToUint(Z);
  stateOut[base + 4u] = encodeDir(S.n);
  stateOut[base + 5u] = valid ? 1u : 0u;
  for (int i = 0; i < IBL_SMC_N; ++i) {
    stateOut[base + 8u + 2u * uint(i)] = encodeDir(dirs[i]);
    stateOut[base + 9u + 2u * uint(i)] = floatBitsToUint(W[i]);
  }
}

vec3 estimateSmc(ivec2 gpx, vec3 x) {
  float Zprev;
  float Z;
  bool carried = smcLoad(gpx, x, Zprev);
  if (carried) {
    atomicAdd(stats[IBL_STAT_REPROJECTED], 1u);
    Z = Zprev;
    int K = max(uIntermediate, 1);
    for (int k = 1; k <= K && Z > 0.0; ++k) {
      float b0 = float(k - 1) / float(K), b1 = float(k) / float(K);
      // Reweighting (eq. 5) towards the next intermediate distribution; Z by eq. 8.
      float sum = 0.0;
      for (int i = 0; i < IBL_SMC_N; ++i) {
        float gp = targetPrevious(dirs[i]), gc = target(dirs[i]);
        float from = bridge(gp, gc, b0), to = bridge(gp, gc, b1);
        W[i] = from > 0.0 ? W[i] * (to / from) : 0.0;
        sum += W[i];
      }
      Z *= sum;
      if (!(sum > 0.0) || isinf(sum)) break;
      float ess = 0.0;
      for (int i = 0; i < IBL_SMC_N; ++i) {
        W[i] /= sum;
        ess += W[i] * W[i];
      }
      if (1.0 / ess < 2.0 * float(IBL_SMC_N) / 3.0) {
        resample();
        atomicAdd(stats[IBL_STAT_RESAMPLED], 1u);
      }
      mhMove(b1);
    }
    // The paper's reinitialisation: Z_t / Z_t-1 jumped (a light switched on), or the samples
    // lost all weight (the light they sat on went out); with uReinitOnDrop also a fall by the
    // same ratio (the light moved off the samples faster than the moves could follow).
    if (!(Z > 0.0) || isinf(Z) || Z > uReinitRatio * Zprev || (uReinitOnDrop && Z * uReinitRatio < Zprev)) {
      atomicAdd(stats[IBL_STAT_REINIT_JUMP], 1u);
      carried = false;
    }
  } else {
    atomicAdd(stats[IBL_STAT_REINIT_NEW], 1u);
  }
  if (!carried) Z = smcInit();
  bool valid = Z > 0.0 && !isinf(Z);
  smcStore(gpx, x, valid ? Z : 0.0, valid);
  if (!valid) return vec3(0.0);
  vec3 sum = vec3(0.0);
  for (int i = 0; i < IBL_SMC_N; ++i) sum += W[i] * ratioContribution(dirs[i]);
  return Z * sum;
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy) + ivec2(0, uRowOffset);
  if (px.x >= int(frame.tile.z) || px.y >= min(int(frame.tile.w), uRowOffset + uRows)) return;
  ivec2 gpx = px + ivec2(frame.tile.xy);
  vec4 direct = texelFetch(uDirect, px, 0);
  float depth = texelFetch(uDepth, px, 0).r;
  uvec4 m = texelFetch(uMaterial, px, 0);
  bool receiver = depth < 1.0 && (frame.counts.y == 1 || gbufferSource(m) != NL_SOURCE_SCAN);
  if (!receiver) {
    if (uPass == 0) imageStore(uOut, px, direct);
    if (uEstimator == IBL_SMC) {
      S.n = vec3(0.0, 0.0, 1.0);
      smcStore(gpx, vec3(0.0), 0.0, false);
    }
    return;
  }
  if (uPass == 0) atomicAdd(stats[IBL_STAT_RECEIVERS], 1u);
  rngState = pcgHash(uint(gpx.x) * 9781u + uint(gpx.y) * 6271u +
                     pcgHash(uSeed + uint(frame.counts.z) * 26699u + uint(uPass) * 7919u));
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  vec3 x = wp.xyz / wp.w;
  vec3 wo = normalize(frame.eye.xyz - x);
  vec4 nn = texelFetch(uNormal, px, 0);
  S.n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  if (dot(S.n, wo) < 0.0) S.n = -S.n;
  S.F = frameFromNormal(S.n);
  S.woL = toLocal(wo);
  vec3 emission;
  vec4 base = texelFetch(uBaseColour, px, 0);
  S.mat = gbufferMaterial(base.rgb, m, emission);
  // Rays leave from above the surface. A scan point from 1.5 splat radii: scan noise puts its
  // neighbours' discs millimetres above its plane, and the reference leaves a disc by that
  // surface's thickness (its neighbours' reach above the plane, capped at the disc's radius), which
  // this bounds without the per-point thickness the G-buffer does not carry (pbgi's receivers
  // leave alike). A mesh by a hair relative to the distance (its own triangle).
  S.x = x + S.n * max(1e-4 * max(length(x - frame.eye.xyz), 1e-3), base.a > 0.0 ? 1.5 * base.a : 0.0);
  vec3 L = vec3(0.0);
  if (!envBlack() || uEstimator == IBL_SMC) {
    if (uEstimator == IBL_MIS) L = estimateMis(uBrdfSamples, uEnvSamples);
    else if (uEstimator == IBL_ENVIRONMENT) L = estimateMis(0, uEnvSamples);
    else if (uEstimator == IBL_BRDF) L = estimateMis(uBrdfSamples, 0);
    else if (uEstimator == IBL_BIS) L = estimateBis(uBisM, uBisN);
    else L = estimateSmc(gpx, x);
  }
  atomicAdd(stats[IBL_STAT_RAYS], rays);
  if (loopSteps > 60000u) atomicAdd(stats[IBL_STAT_LOOP_LIMIT], 1u);
  if (moves > 0u) {
    atomicAdd(stats[IBL_STAT_MOVES], moves);
    atomicAdd(stats[IBL_STAT_ACCEPTED], accepted);
  }
  if (any(isnan(L)) || any(isinf(L))) L = vec3(0.0);
  vec4 before = uPass == 0 ? direct : imageLoad(uOut, px);
  imageStore(uOut, px, vec4(before.rgb + L, direct.a));
}
