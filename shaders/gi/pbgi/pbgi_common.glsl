// What the `pbgi` passes share: the hierarchy's layout and buffers, the micro-buffer size, and the
// receiver a G-buffer pixel stands for.
#include "../common/gbuffer_in.glsl"
#include "../../common/octahedral.glsl"
#include "../shared/bsh_interface.glsl"
#include "../common/environment.glsl"
#ifndef PBGI_MB
#define PBGI_MB 16  // the method compiles with its micro_buffer; this is for validators
#endif
#define M PBGI_MB
layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = 4) uniform sampler2D uDirect;
layout(std430, binding = PBGI_SSBO_RECEIVERS) buffer Receivers { uint receivers[]; };
layout(rgba32f, binding = 0) uniform writeonly image2D uOut;
// How far above its surface a mesh pixel receives: the surfel disc radius of its own mesh when
// the meshes' surfels join the gather (a convex surface's neighbouring discs, tangent a little way
// off, rise above its tangent plane by up to that much), else 0. The G-buffer does not say which
// mesh a pixel is on: the PBGI_LIFT_BOXES meshes of the largest discs each give theirs to the
// pixels of their material inside their bounding box (xyz: lo, hi; lo.w: the lift, hi.w: the
// material). A lift per material alone let one coarse mesh lift every receiver of its material:
// a 20 m box of one surfel (a disc of 49 m radius) 1000 km away lifted the floor beside the camera
// 49 m, above everything that lit it. The other meshes' largest disc, per material (the first
// PBGI_LIFTS; the rest take the largest of all), lifts every pixel of their material.
uniform vec4 uLiftBox[2 * PBGI_LIFT_BOXES];
uniform int uLiftBoxes;
uniform float uMeshLift[PBGI_LIFTS];
uniform float uMeshLiftMax;

float meshLiftAt(vec3 x, uint material) {
  float lift = material < uint(PBGI_LIFTS) ? uMeshLift[material] : uMeshLiftMax;
  // The position comes back from depth: its error grows with distance.
  float pad = 1e-3 * max(length(x - frame.eye.xyz), 1e-3) + 1e-6 * max(max(abs(x.x), abs(x.y)), abs(x.z));
  for (int i = 0; i < uLiftBoxes; ++i) {
    vec4 lo = uLiftBox[2 * i], hi = uLiftBox[2 * i + 1];
    if (uint(hi.w) == material && all(greaterThanEqual(x, lo.xyz - pad)) && all(lessThanEqual(x, hi.xyz + pad)))
      lift = max(lift, lo.w);
  }
  return lift;
}

// In the radiance-cache mode a scan point's colour is all its light: only inserted objects
// gather. In the albedo mode (frame.counts.y 1) scan points gather too.
bool isReceiver(ivec2 px) {
  if (!(texelFetch(uDepth, px, 0).r < 1.0)) return false;
  return frame.counts.y == 1 || gbufferSource(texelFetch(uMaterial, px, 0)) != NL_SOURCE_SCAN;
}

struct Receiver {
  vec3 x;   // position, lifted off its surface (its own surface must not occlude it)
  vec3 n;   // normal, facing the camera
  vec3 wo;  // towards the camera
  MaterialParams mat;
};

Receiver receiverAt(ivec2 px) {
  Receiver R;
  float depth = texelFetch(uDepth, px, 0).r;
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  R.x = wp.xyz / wp.w;
  R.wo = normalize(frame.eye.xyz - R.x);
  vec4 nn = texelFetch(uNormal, px, 0);
  R.n = nn.w > 0.0 ? normalize(nn.xyz) : R.wo;
  if (dot(R.n, R.wo) < 0.0) R.n = -R.n;
  vec3 emission;
  vec4 base = texelFetch(uBaseColour, px, 0);
  R.mat = gbufferMaterial(base.rgb, texelFetch(uMaterial, px, 0), emission);
  // A scan point receiving (albedo mode) lies among the discs of its own surface, which scan
  // noise offsets by millimetres above and below its plane: from just above it, a neighbour's
  // disc a few millimetres higher covers every ray but the most grazing, and the micro-buffer
  // sees the surface itself instead of the room (the cornell room's gathered bounce was 23% dark).
  // It leaves from 1.5 splat radii above its surface (base.a: its splat radius; 0 on meshes,
  // which leave from meshLiftAt, or by a hair).
  uint material = texelFetch(uMaterial, px, 0).w;
  float meshLift = base.a > 0.0 ? 0.0 : meshLiftAt(R.x, material);
  R.x += R.n * max(1e-4 * max(length(R.x - frame.eye.xyz), 1e-3), base.a > 0.0 ? 1.5 * base.a : meshLift);
  return R;
}
