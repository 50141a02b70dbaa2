// What the `projection` passes share: the G-buffer's receivers, the micro-buffer size and the
// method's buffers.
#include "../../interface/frame_interface.glsl"
#include "../common/gbuffer_in.glsl"
#include "../../common/octahedral.glsl"
#include "../common/environment.glsl"
#include "projection_interface.glsl"
#ifndef PROJECTION_MB
#define PROJECTION_MB 32  // the method compiles with its micro_buffer; this is for validators
#endif
#define M PROJECTION_MB
layout(binding = 0) uniform sampler2D uDepth;
layout(binding = 1) uniform sampler2D uBaseColour;
layout(binding = 2) uniform sampler2D uNormal;
layout(binding = 3) uniform usampler2D uMaterial;
layout(binding = 4) uniform sampler2D uDirect;
layout(rgba32f, binding = 0) uniform writeonly image2D uOut;

// In the radiance-cache mode a scan point's colour is all its light: only meshes gather. In the
// albedo mode (frame.counts.y 1) scan points gather too.
bool isReceiver(ivec2 px) {
  if (!(texelFetch(uDepth, px, 0).r < 1.0)) return false;
  return frame.counts.y == 1 || gbufferSource(texelFetch(uMaterial, px, 0)) != NL_SOURCE_SCAN;
}

// A pixel's position (scene-local) from the depth buffer, and its normal facing the camera.
vec3 positionAt(ivec2 px) {
  float depth = texelFetch(uDepth, px, 0).r;
  vec2 ndc = ((vec2(px) + 0.5) / frame.tile.zw) * 2.0 - 1.0;
  vec4 wp = frame.worldFromClip * vec4(ndc, depth * 2.0 - 1.0, 1.0);
  return wp.xyz / wp.w;
}

vec3 normalAt(ivec2 px) {
  vec4 nn = texelFetch(uNormal, px, 0);
  vec3 wo = normalize(frame.eye.xyz - positionAt(px));
  vec3 n = nn.w > 0.0 ? normalize(nn.xyz) : wo;
  return dot(n, wo) < 0.0 ? -n : n;
}

struct Receiver {
  vec3 x;   // position, lifted off its surface
  vec3 n;   // normal, facing the camera
  vec3 wo;  // towards the camera
  MaterialParams mat;
};

// A scan pixel leaves from 1.5 splat radii above its surface (base.a: its splat radius), where
// its neighbours' discs, offset by scan noise, no longer stand over it; a mesh pixel by a hair.
Receiver receiverAt(ivec2 px) {
  Receiver R;
  R.x = positionAt(px);
  R.wo = normalize(frame.eye.xyz - R.x);
  R.n = normalAt(px);
  vec3 emission;
  vec4 base = texelFetch(uBaseColour, px, 0);
  R.mat = gbufferMaterial(base.rgb, texelFetch(uMaterial, px, 0), emission);
  R.x += R.n * max(1e-4 * max(length(R.x - frame.eye.xyz), 1e-3), 1.5 * base.a);
  return R;
}
