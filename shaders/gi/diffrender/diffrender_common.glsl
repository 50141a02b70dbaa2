// What the diffrender passes share: the distance impostor's queries (Rohmer, Jendersie and Grosch
// 2017, section 6: EM, a lookup by direction as from a distant environment; DIT, distance impostor
// tracing after Szirmay-Kalos, Aszodi, Lazanyi and Premecz, "Approximate Ray-Tracing on the GPU
// with Distance Impostors", 2005), the inserted meshes' solid voxel volume marched by rays, and
// the random numbers, and the light an object's voxel sends back. Include gbuffer_in.glsl (the
// materials), brdf_sample.glsl, environment.glsl, lights.glsl and diffrender_interface.glsl first.
#include "impostor_direction.glsl"

layout(binding = DR_UNIT_IMPOSTOR) uniform samplerCube uImpostor;  // rgb radiance, a distance
layout(binding = DR_UNIT_OCCUPANCY) uniform sampler3D uOccupancy;  // 1 solid, 0.5 shell, mips the mean
layout(binding = DR_UNIT_SURFACE) uniform sampler3D uSurface;      // n * 0.5 + 0.5, (material + 1) / 255
layout(std430, binding = DR_SSBO_STATS) buffer DiffrenderStats { uint stats[]; };

uniform vec3 uImpostorCentre;
uniform int uImpostorSize;
uniform int uImpostorLevels;
uniform float uImpostorReach;  // the scene's farthest extent from the centre
uniform int uQuery;
uniform int uDitIterations;
// One solid voxel grid per inserted mesh, each over its own box, stacked along z in the two
// textures (grid k's voxels at z + k uVolumeSize.z).
uniform int uVolumeCount;
// The voxel cone tracer's scene volume: cubic voxels of uSceneCell from uSceneOrigin,
// uSceneDims of them; radiance premultiplied by opacity, and opacity, with averaged mips.
layout(binding = DR_UNIT_SCENE_RADIANCE) uniform sampler3D uSceneRadiance;
layout(binding = DR_UNIT_SCENE_OPACITY) uniform sampler3D uSceneOpacity;
// Its levels from 1 on with each axis' opacity apart (x, y, z: scene_opacity_mip.comp), level k of
// this texture the volume's k + 1.
layout(binding = DR_UNIT_SCENE_OPACITY_DIR) uniform sampler3D uSceneOpacityDir;
uniform vec3 uSceneOrigin;
uniform float uSceneCell;
uniform ivec3 uSceneDims;
uniform int uSceneLevels;  // its mips (each side a multiple of 2^(levels - 1))
uniform vec3 uVolumeLo[DR_VOLUMES_MAX], uVolumeHi[DR_VOLUMES_MAX];
uniform ivec3 uVolumeSize;
uniform uint uSeed;

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

uint unconverged = 0u, hidden = 0u;

// The mip level whose texels span `solidAngle` about `dir` (a cone's, or a sample's 1 / (N pdf):
// Colbert and Krivanek, "GPU-Based Importance Sampling", 2007). A face texel at face coordinates
// (u, v) spans (2 / w)^2 / (1 + u^2 + v^2)^(3/2) = (2 / w)^2 (m / |dir|)^3, m the major axis'
// component: twice as much at a face's middle as at its corners.
float impostorLod(float solidAngle, vec3 dir) {
  vec3 a = abs(dir);
  float m = max(a.x, max(a.y, a.z)) / max(length(dir), 1e-20);
  float side = 2.0 / float(uImpostorSize);
  float texel = side * side * m * m * m;
  return clamp(0.5 * log2(max(solidAngle, 1e-12) / texel), 0.0, float(uImpostorLevels - 1));
}

float impostorDistance(vec3 dir) { return textureLod(uImpostor, dir, 0.0).a; }

// Where the ray x + t d (x relative to the centre) is `dist` from the centre: the far root of
// |x + t d| = dist; -1 when the ray misses that sphere.
float sphereExit(vec3 x, vec3 d, float dist) {
  if (dist >= kImpostorFar * 0.5) return kImpostorFar;
  float b = dot(x, d), c = dot(x, x) - dist * dist;
  float disc = b * b - c;
  if (disc < 0.0) return -1.0;
  return -b + sqrt(disc);
}

// Two face texels' footprint at a point relative to the centre (a texel spans about 2 / size
// radians).
float footprint(vec3 p) { return 4.0 * length(p) / float(uImpostorSize); }

// How far the point x + t d (x relative to the centre) lies beyond the captured surface in its
// direction: positive past it.
float beyondSurface(vec3 x, vec3 d, float t) {
  vec3 p = x + t * d;
  return length(p) - impostorDistance(p);
}

// The scene's radiance along the ray o + t d (scene-local), over a cone of `solidAngle` about it,
// and the distance it meets the scene at (kImpostorFar: the environment). VCT marches a cone
// through the scene volume. EM reads the impostor by the direction alone. DIT finds where the
// ray passes the captured surface as the impostor stores it: a search in steps that grow with the
// distance (the surface's first crossing), then `uDitIterations` secant steps; a crossing the
// secant does not pin down to a quarter of a texel's footprint (radially, so that the hit lies
// within a texel's footprint along the ray: with two texels, one in twenty hits strayed further
// in a closed room) is counted unconverged (grazing rays) and keeps its last estimate.
vec3 coneTrace(vec3 o, vec3 d, float solidAngle, out float tScene);
vec3 exactQuery(vec3 o, vec3 d, out float tScene);

// surfaceAngle: the solid angle the lookup filters over where the impostor holds a surface (a
// texel at a finite distance); its texels at infinity, the environment, filter over solidAngle.
float fetchAngle(vec3 dir, float solidAngle, float surfaceAngle) {
  return impostorDistance(dir) >= kImpostorFar * 0.5 ? solidAngle : surfaceAngle;
}

vec3 ditQuery(vec3 o, vec3 d, float solidAngle, float surfaceAngle, out float tScene) {
  float lod = impostorLod(fetchAngle(d, solidAngle, surfaceAngle), d);
  vec3 x = o - uImpostorCentre;
  // Steps out to the far side of the scene's bounds (uImpostorReach from the centre).
  float tMax = sphereExit(x, d, uImpostorReach);
  if (!(tMax > 0.0)) tMax = uImpostorReach;
  const int kSteps = 16;
  // A ray that starts behind the stored surface (a point the centre does not see, hidden by
  // something nearer the centre) first has to come out in front of it; only a crossing from in
  // front to beyond is the surface it meets.
  float ta = 0.0, fa = 0.0, tb = -1.0, fb = 0.0;
  bool inFront = false;
  for (int k = 1; k <= kSteps; ++k) {
    float u = float(k) / float(kSteps);
    float t = tMax * u * u;
    float f = beyondSurface(x, d, t);
    if (f <= 0.0) {
      ta = t, fa = f, inFront = true;
    } else if (inFront && f > footprint(x + t * d)) {
      // Past the surface by more than a texel's footprint: the surface the ray leaves, seen from
      // the centre, stands a little off its own position in the stored distances.
      tb = t, fb = f;
      break;
    }
  }
  if (!inFront) {
    // Behind the stored surface all the way: the impostor cannot say; the direction's lookup.
    hidden++;
    float t = sphereExit(x, d, impostorDistance(d));
    tScene = t < 0.0 ? kImpostorFar : t;
    return textureLod(uImpostor, d, lod).rgb;
  }
  if (tb < 0.0) {  // no crossing: the ray leaves to the environment
    tScene = kImpostorFar;
    return textureLod(uImpostor, d, lod).rgb;
  }
  // Regula falsi with the Illinois rule (an end kept twice has its value halved), so that a
  // curved or stepped distance does not hold one end for every step.
  float t = tb;
  bool converged = false;
  int side = 0;
  for (int k = 0; k < uDitIterations; ++k) {
    t = ta + (tb - ta) * (-fa) / max(fb - fa, 1e-20);
    float f = beyondSurface(x, d, t);
    if (abs(f) <= 0.125 * footprint(x + t * d)) { converged = true; break; }
    if (f > 0.0) {
      tb = t, fb = f;
      if (side == 1) fa *= 0.5;
      side = 1;
    } else {
      ta = t, fa = f;
      if (side == -1) fb *= 0.5;
      side = -1;
    }
  }
  if (!converged) unconverged++;
  tScene = t;
  // The cone's footprint where it meets the surface, t^2 solidAngle, seen from the centre |p| away
  // spans t^2 / |p|^2 of its solid angle: a point far from the centre looking at a wall near it
  // fetches a finer level (at the cone's own solid angle the coarse levels mixed the spot-lit
  // floor into the walls' texels above it).
  vec3 p = x + t * d;
  lod = impostorLod(fetchAngle(p, solidAngle, surfaceAngle) * t * t / max(dot(p, p), 1e-12), p);
  return textureLod(uImpostor, normalize(p), lod).rgb;
}

vec3 queryScene(vec3 o, vec3 d, float solidAngle, out float tScene) {
  if (uQuery == DR_QUERY_VCT) return coneTrace(o, d, solidAngle, tScene);
  if (uQuery == DR_QUERY_EXACT) return exactQuery(o, d, tScene);
  if (uQuery == DR_QUERY_EM) {
    vec3 x = o - uImpostorCentre;
    float t = sphereExit(x, d, impostorDistance(d));
    tScene = t < 0.0 ? kImpostorFar : t;
    return textureLod(uImpostor, d, impostorLod(solidAngle, d)).rgb;
  }
  return ditQuery(o, d, solidAngle, solidAngle, tScene);
}

// The material estimate's incoming light (eq. 5): EM's lookup by direction cannot answer for a
// point away from the centre, so EM's material is DIT's. The surfaces the impostor holds are read
// at its finest level here: eq. 5 divides by the mean, which has to be unbiased, and a mip of the
// impostor seen from off the centre mixes surfaces the point does not see together (the spot-lit
// floor into the walls above it); filtered at the samples' solid angle the floor's estimate came
// out 6% low, at the finest level 4% (exact's 2%). Its texels at infinity, the environment, have
// no parallax and stay filtered: read at the finest level, an HDR sky's brightest texels hit or
// missed by 16 samples made the estimate speckle (the lion's close view: 4802 pixels brightening
// by over 10% against 2884).
vec3 queryMaterial(vec3 o, vec3 d, float solidAngle, out float tScene) {
  if (uQuery == DR_QUERY_EM || uQuery == DR_QUERY_DIT)
    return ditQuery(o, d, solidAngle, 0.0, tScene);
  return queryScene(o, d, solidAngle, tScene);
}

// The ray's span [t0, t1] inside grid k's box; false when it misses.
bool volumeSpan(int k, vec3 o, vec3 d, out float t0, out float t1) {
  vec3 inv = 1.0 / d;
  vec3 a = (uVolumeLo[k] - o) * inv, b = (uVolumeHi[k] - o) * inv;
  vec3 lo = min(a, b), hi = max(a, b);
  t0 = max(max(lo.x, lo.y), max(lo.z, 0.0));
  t1 = min(min(hi.x, hi.y), hi.z);
  return t0 <= t1;
}

// Whether the ray meets any inserted mesh's box (the set H of section 7).
bool meetsObjectBoxes(vec3 o, vec3 d) {
  for (int k = 0; k < uVolumeCount; ++k) {
    float t0, t1;
    if (volumeSpan(k, o, d, t0, t1)) return true;
  }
  return false;
}

vec3 volumeCell(int k) { return (uVolumeHi[k] - uVolumeLo[k]) / vec3(uVolumeSize); }
float occupancyAt(int k, ivec3 v) { return texelFetch(uOccupancy, v + ivec3(0, 0, k * uVolumeSize.z), 0).r; }
vec4 surfaceAt(int k, ivec3 v) { return texelFetch(uSurface, v + ivec3(0, 0, k * uVolumeSize.z), 0); }

// The first solid voxel of grid k the ray meets in [tStart, tMax] (Amanatides and Woo's
// traversal): its distance, and its surface normal and material (material -1: an interior voxel).
bool marchVolume(int k, vec3 o, vec3 d, float tStart, float tMax, out float tHit, out vec3 n, out int material) {
  tHit = 0.0, n = -d, material = -1;
  float t0, t1;
  if (!volumeSpan(k, o, d, t0, t1)) return false;
  t0 = max(t0, tStart);
  t1 = min(t1, tMax);
  if (t0 > t1) return false;
  vec3 cell = volumeCell(k);
  vec3 p = (o + d * t0 - uVolumeLo[k]) / cell;
  ivec3 v = clamp(ivec3(floor(p)), ivec3(0), uVolumeSize - 1);
  ivec3 step = ivec3(sign(d));
  vec3 safe = vec3(abs(d.x) > 1e-12 ? d.x : 1e-12, abs(d.y) > 1e-12 ? d.y : 1e-12, abs(d.z) > 1e-12 ? d.z : 1e-12);
  vec3 next = (uVolumeLo[k] + (vec3(v) + max(vec3(step), 0.0)) * cell - o) / safe;
  vec3 delta = abs(cell / safe);
  float t = t0;
  ivec3 before = v;
  for (int i = 0; i < 3 * 1024; ++i) {
    if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, uVolumeSize)) || t > t1) return false;
    if (occupancyAt(k, v) > 0.75) {
      // The surface crosses this voxel or the one the ray came from (a solid voxel whose centre
      // the surface passed just before).
      vec4 s = surfaceAt(k, v);
      if (s.a == 0.0) s = surfaceAt(k, before);
      tHit = t;
      material = int(s.a * 255.0 + 0.5) - 1;
      if (material >= 0) n = normalize(s.xyz * 2.0 - 1.0);
      return true;
    }
    before = v;
    if (next.x < next.y && next.x < next.z) v.x += step.x, t = next.x, next.x += delta.x;
    else if (next.y < next.z) v.y += step.y, t = next.y, next.y += delta.y;
    else v.z += step.z, t = next.z, next.z += delta.z;
  }
  return false;
}

// The nearest solid voxel of any inserted mesh along the ray in [tStart, tMax].
bool marchObjects(vec3 o, vec3 d, float tStart, float tMax, out float tHit, out vec3 n, out int material) {
  bool hit = false;
  tHit = 0.0, n = -d, material = -1;
  for (int k = 0; k < uVolumeCount; ++k) {
    float t;
    vec3 nk;
    int mk;
    if (marchVolume(k, o, d, tStart, tMax, t, nk, mk)) {
      hit = true, tMax = t, tHit = t, n = nk, material = mk;
    }
  }
  return hit;
}

// Eq. 6 (vct): a cone through the inserted meshes' volumes in [0, tMax] (the scene's distance),
// front to back from where it enters each grid's box, the mip from its diameter, steps of an
// eighth of a diameter with the occupancy corrected for them (tau_s): the filtered occupancy
// reaches a texel beyond the surface, and at half a diameter (the scene's cones) a black sphere's
// shadow on the floor came out 17% too dark, at a quarter 7%, at an eighth within 5%. Each step's surface light (the boundary
// voxels' mean, object_light.comp) is weighted by tau_s and by the transmittance alpha = prod
// (1 - tau) of the steps before; `coverage` is 1 - alpha at the end and `radiance` the weighted
// mean, so that dL = coverage (radiance - L_env). Grids are marched one after another, not
// interleaved by depth: meshes whose boxes overlap along a cone are an approximation. False when
// the cone meets no occupancy.
layout(binding = DR_UNIT_OBJECT_LIGHT) uniform sampler3D uObjectLight;
uniform int uObjectLevels;  // the volumes' mips (those whose slabs stay apart in the stack)

bool coneObjects(vec3 o, vec3 d, float solidAngle, float tMax, out float coverage, out vec3 radiance) {
  float cosHalf = clamp(1.0 - solidAngle / (2.0 * kPi), -1.0, 1.0 - 1e-6);
  float tanHalf = sqrt(max(1.0 - cosHalf * cosHalf, 0.0)) / cosHalf;
  float alpha = 1.0, lit = 0.0;
  radiance = vec3(0.0);
  for (int k = 0; k < uVolumeCount; ++k) {
    float t0, t1;
    if (!volumeSpan(k, o, d, t0, t1)) continue;
    t1 = min(t1, tMax);
    vec3 cell = volumeCell(k), extent = uVolumeHi[k] - uVolumeLo[k];
    float voxel = min(cell.x, min(cell.y, cell.z));
    float t = t0;
    for (int i = 0; i < 1024 && t < t1 && alpha > 0.01; ++i) {
      float diameter = max(2.0 * t * tanHalf, voxel);
      float lod = clamp(log2(diameter / voxel), 0.0, float(uObjectLevels - 1));
      vec3 local = (o + t * d - uVolumeLo[k]) / extent;
      // Kept half a texel of the level inside grid k's slab of the stack, so that the filter does
      // not reach the next mesh's grid.
      float margin = 0.5 * exp2(floor(lod) + 1.0) / float(uVolumeSize.z);
      local.z = clamp(local.z, margin, 1.0 - margin);
      vec3 uvw = vec3(local.xy, (local.z + float(k)) / float(uVolumeCount));
      float tau = textureLod(uOccupancy, uvw, lod).r;
      if (tau > 1e-4) {
        float step = 1.0 - pow(1.0 - min(tau, 0.9999), 0.125);
        vec4 l = textureLod(uObjectLight, uvw, lod);
        if (l.a > 1e-4) {
          radiance += alpha * step * l.rgb / l.a;
          lit += alpha * step;
        }
        alpha *= 1.0 - step;
      }
      t += 0.125 * diameter;
    }
  }
  coverage = 1.0 - alpha;
  radiance = lit > 0.0 ? radiance / lit : vec3(0.0);
  return coverage > 1e-3;
}

// The grid whose box holds x, -1 when none does (within half a voxel).
int volumeAt(vec3 x) {
  for (int k = 0; k < uVolumeCount; ++k) {
    vec3 p = (x - uVolumeLo[k]) / volumeCell(k);
    if (all(greaterThanEqual(p, vec3(-0.5))) && all(lessThanEqual(p, vec3(uVolumeSize) + 0.5))) return k;
  }
  return -1;
}

// Whether a scene-local point lies in a solid voxel (or one next to it): pixels of the inserted
// meshes, which the G-buffer does not tell from the captured scene's meshes.
bool inObjects(vec3 x) {
  for (int k = 0; k < uVolumeCount; ++k) {
    vec3 p = (x - uVolumeLo[k]) / volumeCell(k);
    if (any(lessThan(p, vec3(-0.5))) || any(greaterThan(p, vec3(uVolumeSize) + 0.5))) continue;
    ivec3 c = ivec3(floor(p));
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          ivec3 v = c + ivec3(dx, dy, dz);
          if (all(greaterThanEqual(v, ivec3(0))) && all(lessThan(v, uVolumeSize)) && occupancyAt(k, v) > 0.4)
            return true;
        }
  }
  return false;
}

// Voxel cone tracing (Crassin et al. 2011): front to back through the scene volume's mips, each
// step as wide as the cone there (the mip from its diameter), its opacity corrected for steps of
// half a diameter and read by direction (the anisotropic voxels of their section 5: with averaged
// opacity one-voxel walls leaked, the default room's floor material came out 17% high and 40% of
// its samples clamped); the environment behind what the cone's opacity leaves. It starts 1.5
// voxels out, past the voxel of the surface it leaves. The scene's distance: where the opacity
// passes one half.
// The surface a cone leaves (scene-local point and normal; a zero normal: none). A level-k lookup
// reads voxels of 2^k cells within 1.5 of them, so a level that would take in the surface's own
// voxels is not read: the cone is read at the finest level that keeps clear of its surface (and
// sees nothing while under 1.5 cells above it). Weighting the coarse samples down instead (by how
// far they stood above the surface in diameters) hid the walls from every cone under 48 degrees
// of elevation and took two thirds of the ceiling from the upright ones.
vec3 coneBase = vec3(0.0), coneNormal = vec3(0.0);
// How far above its surface (along coneNormal) a scan point's exact rays leave: its neighbours'
// discs stand up to about a splat radius off the position the G-buffer gives it (as ibl's rays
// leave).
float exactLift = 0.0;

// The opacity a cone along d meets at mip level lod: level 0's own, from level 1 on each axis'
// weighted by d's components (Crassin et al. weight by their squares, which sum to one: a wall
// met obliquely then reads partly through its edge-on axes, half empty, and a closed room under
// a bright sky let 16% of it in against 4%; the sum is capped at one), between levels 0 and 1 the
// two mixed. Read from the nearest voxel of a level (levels blended): trilinear reads of a
// one-voxel wall come out partial at every step across it (7% of the sky in).
float directionalOpacity(vec3 uvw, float lod, vec3 d) {
  vec3 w = abs(d);
  if (lod >= 1.0) return min(dot(w, textureLod(uSceneOpacityDir, uvw, lod - 1.0).rgb), 1.0);
  ivec3 v = clamp(ivec3(floor(uvw * vec3(uSceneDims))), ivec3(0), uSceneDims - 1);
  float a0 = texelFetch(uSceneOpacity, v, 0).r;
  return mix(a0, min(dot(w, textureLod(uSceneOpacityDir, uvw, 0.0).rgb), 1.0), max(lod, 0.0));
}

vec3 coneTrace(vec3 o, vec3 d, float solidAngle, out float tScene) {
  float cosHalf = clamp(1.0 - solidAngle / (2.0 * kPi), -1.0, 1.0 - 1e-6);
  float tanHalf = sqrt(max(1.0 - cosHalf * cosHalf, 0.0)) / cosHalf;
  vec3 extent = vec3(uSceneDims) * uSceneCell;
  vec3 colour = vec3(0.0);
  float alpha = 0.0, t = 1.5 * uSceneCell;
  tScene = kImpostorFar;
  bool fromSurface = dot(coneNormal, coneNormal) > 0.0;
  for (int i = 0; i < 512 && alpha < 0.99; ++i) {
    vec3 uvw = (o + t * d - uSceneOrigin) / extent;
    float lod = min(log2(max(2.0 * t * tanHalf, uSceneCell) / uSceneCell), float(uSceneLevels - 1));
    float lift = 1.0;
    if (fromSurface) {
      float h = dot(o + t * d - coneBase, coneNormal) / uSceneCell;
      float room = log2(max(h / 1.5, 1e-6));  // the coarsest level clear of the surface
      if (ceil(lod) > room) lod = max(floor(room), 0.0);  // a fractional level reads the next
      lift = h >= 1.5 ? 1.0 : 0.0;
    }
    float diameter = uSceneCell * exp2(lod);
    // Out of the volume once the lookup reads nothing of it: a wall in its border voxels (a closed
    // room's, at its bounds) is read by the steps about to leave, not stepped over.
    vec3 margin = vec3(diameter) / extent;
    if (any(lessThan(uvw, -margin)) || any(greaterThan(uvw, 1.0 + margin))) break;
    // The radiance is premultiplied by the averaged opacity; what the cone meets is the
    // directional one.
    float coverage = textureLod(uSceneOpacity, uvw, lod).r;
    float a = lift * directionalOpacity(uvw, lod, d);
    if (a > 1e-4 && coverage > 1e-4) {
      vec3 c = textureLod(uSceneRadiance, uvw, lod).rgb / coverage;
      float step = 1.0 - pow(1.0 - min(a, 0.9999), 0.5);
      colour += (1.0 - alpha) * step * c;
      alpha += (1.0 - alpha) * step;
      if (alpha >= 0.5 && tScene >= kImpostorFar) tScene = t;
    }
    t += 0.5 * diameter;
  }
  return colour + (1.0 - alpha) * environment(d);
}

// The light an inserted mesh's voxel sends back, taken as diffuse: its material's albedo times the
// impostor's radiance over the hemisphere about its normal (four cosine lookups at the level of a
// quarter hemisphere) and the scene's lights, plus its emission.
vec3 objectRadiance(vec3 p, vec3 n, int material) {
  if (material < 0) return vec3(0.0);
  MaterialRecord r = materials[material];
  // Taken as diffuse, all the light the material reflects: its diffuse albedo and its specular
  // reflectance at normal incidence (a metal's, its base colour: a bronze object tints the scan
  // it bounces light onto, as the paper's diffuse bounce would lose).
  vec3 base = r.baseColor.rgb;
  float metallic = r.params.y;
  vec3 albedo = int(r.baseColor.w) == NL_MATERIAL_LAMBERT ? base : (1.0 - metallic) * base + mix(vec3(0.04), base, metallic);
  vec3 E = vec3(0.0);
  mat3 F = frameFromNormal(n);
  float cone = kPi / 4.0;
  vec3 savedBase = coneBase, savedNormal = coneNormal;
  float savedLift = exactLift;
  coneBase = p, coneNormal = n, exactLift = 0.0;
  for (int k = 0; k < 4; ++k) {
    vec3 w = F * sampleCosineHemisphereGl(vec2((float(k) + 0.5) / 4.0, fract(0.618034 * float(k) + 0.25)));
    float t;
    E += queryScene(p + n * 1e-3, w, cone, t);
  }
  coneBase = savedBase, coneNormal = savedNormal, exactLift = savedLift;
  E *= kPi / 4.0;  // irradiance: pi times the mean radiance of cosine-distributed directions
  // The scene's lights, shadowed by the frame's maps (the inserted meshes in them), the lookup a
  // voxel off the hit (which lies on the voxel's face, not the mesh).
  int k = max(volumeAt(p), 0);
  vec3 q = p + n * length(volumeCell(k));
  for (int i = 0; i < frame.counts.x; ++i) {
    LightSample s = sampleLight(i, q);
    float c = dot(n, s.wi);
    if (c > 0.0) E += s.radiance * c * visibility(i, q, n, 0.0, s);
  }
  return albedo * kInvPi * E + r.emission.rgb;
}

#include "diffrender_exact.glsl"
