// The environment prefiltered by the GGX lobe for the split sum (Karis 2013, "Real Shading in
// Unreal Engine 4": the radiance integral's first factor, with n = v = r), one roughness per mip
// level of a lat-long texture, so glossy lobes read the sky with one lookup
// (environment_specular.glsl). Samples are importance-sampled half vectors of D(h) (n.h) from a
// Hammersley set, each reading the map's mip level whose texels cover its share of the lobe's
// solid angle (filtered importance sampling, Krivanek and Colbert 2008, "Real-time Shading with
// Filtered Importance Sampling"), which keeps a small bright sun from aliasing into sparkles.
layout(local_size_x = 8, local_size_y = 8) in;
#include "brdf.glsl"
#include "environment.glsl"
layout(binding = 0, rgba32f) uniform writeonly image2D uPrefiltered;
uniform float uRoughness;  // the level's roughness (alpha = roughness^2, as brdf.glsl)
uniform int uSamples;

// The direction of a lat-long texel centre, as environment.glsl maps directions to texels.
vec3 texelDirection(ivec2 t, ivec2 size) {
  vec2 uv = (vec2(t) + 0.5) / vec2(size);
  float phi = 2.0 * kPi * uv.x + uEnvRotation, theta = kPi * uv.y;
  return vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
}

void main() {
  ivec2 size = imageSize(uPrefiltered);
  ivec2 t = ivec2(gl_GlobalInvocationID.xy);
  if (t.x >= size.x || t.y >= size.y) return;
  vec3 n = texelDirection(t, size);
  mat3 worldFromLocal = frameFromNormal(n);
  float alpha = max(1e-3, uRoughness * uRoughness), a2 = alpha * alpha;
  vec3 sum = vec3(0.0);
  float weight = 0.0;
  for (int s = 0; s < uSamples; ++s) {
    float u1 = (float(s) + 0.5) / float(uSamples);
    float u2 = float(bitfieldReverse(uint(s))) * 2.3283064365386963e-10;
    float cos2 = (1.0 - u1) / (1.0 + (a2 - 1.0) * u1);
    float ch = sqrt(cos2), sh = sqrt(max(0.0, 1.0 - cos2));
    vec3 h = vec3(sh * cos(2.0 * kPi * u2), sh * sin(2.0 * kPi * u2), ch);
    vec3 l = vec3(2.0 * ch * h.xy, 2.0 * ch * ch - 1.0);  // reflect v = n = +z about h
    if (l.z <= 0.0) continue;
    // pdf(l) = D(h) (n.h) / (4 v.h) = D(h) / 4 with v = n; each sample stands for 1 / (N pdf).
    float pdf = ggxD(h, a2) * 0.25;
    float solidAngle = 1.0 / (float(uSamples) * pdf);
    sum += environmentOver(worldFromLocal * l, solidAngle) * l.z;
    weight += l.z;
  }
  // The values carry the map's scale (environmentOver's); the frame refilters whenever the map
  // changes.
  imageStore(uPrefiltered, t, vec4(weight > 0.0 ? sum / weight : vec3(0.0), 1.0));
}
