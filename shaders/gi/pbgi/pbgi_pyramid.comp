// The receivers' pyramid of MIP-PBGI and X-PBGI (Sabbadin et al. 2019, section 5.2.1): level 0
// holds each receiver (its position as a sphere of radius 0, its normal as a cone of aperture 0);
// each coarser texel bounds its 2 x 2 children: the smallest sphere containing their spheres and
// the smallest cone containing their normal cones (the paper's mip operator for normals, with
// Barequet and Elber's minimum cone taken pairwise as in the hierarchy). Empty texels have a
// negative radius.
layout(local_size_x = 8, local_size_y = 8) in;
#include "pbgi_common.glsl"
layout(std430, binding = PBGI_SSBO_PYRAMID) buffer Pyramid { vec4 pyramid[]; };
uniform int uLevel;
uniform ivec2 uSize;        // this level's texels
uniform ivec2 uChildSize;   // the finer level's
uniform int uOffset;        // this level's first texel (2 vec4 each)
uniform int uChildOffset;

// The smallest cone containing both (unit axes; aperture in w, >= pi: every direction).
vec4 mergeCones(vec4 a, vec4 b) {
  if (a.w >= kPi || b.w >= kPi) return vec4(0.0, 0.0, 1.0, kPi);
  float theta = acos(clamp(dot(a.xyz, b.xyz), -1.0, 1.0));
  if (theta + b.w <= a.w) return a;
  if (theta + a.w <= b.w) return b;
  float h2 = 0.5 * (theta + a.w + b.w);
  if (h2 >= kPi) return vec4(0.0, 0.0, 1.0, kPi);
  vec3 perp = b.xyz - dot(a.xyz, b.xyz) * a.xyz;
  if (length(perp) < 1e-6) perp = abs(a.x) < 0.9 ? vec3(1.0, 0.0, 0.0) - a.x * a.xyz : vec3(0.0, 1.0, 0.0) - a.y * a.xyz;
  perp = normalize(perp);
  float rot = h2 - a.w;
  return vec4(normalize(cos(rot) * a.xyz + sin(rot) * perp), h2 + 1e-4);
}

vec4 mergeSpheres(vec4 a, vec4 b) {
  vec3 d = b.xyz - a.xyz;
  float dist = length(d);
  if (dist + b.w <= a.w) return a;
  if (dist + a.w <= b.w) return b;
  float r = 0.5 * (dist + a.w + b.w);
  return vec4(a.xyz + d * ((r - a.w) / dist), r * 1.0001);
}

void main() {
  ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  if (t.x >= uSize.x || t.y >= uSize.y) return;
  int k = uOffset + t.y * uSize.x + t.x;
  vec4 sphere = vec4(0.0, 0.0, 0.0, -1.0), cone = vec4(0.0, 0.0, 1.0, 0.0);
  if (uLevel == 0) {
    if (isReceiver(t)) {
      Receiver R = receiverAt(t);
      sphere = vec4(R.x, 0.0);
      cone = vec4(R.n, 0.0);
    }
  } else {
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        ivec2 c = 2 * t + ivec2(i, j);
        if (c.x >= uChildSize.x || c.y >= uChildSize.y) continue;
        int ck = uChildOffset + c.y * uChildSize.x + c.x;
        vec4 s = pyramid[2 * ck], n = pyramid[2 * ck + 1];
        if (s.w < 0.0) continue;
        if (sphere.w < 0.0) {
          sphere = s;
          cone = n;
        } else {
          sphere = mergeSpheres(sphere, s);
          cone = mergeCones(cone, n);
        }
      }
  }
  pyramid[2 * k] = sphere;
  pyramid[2 * k + 1] = cone;
}
