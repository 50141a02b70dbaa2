// The scene's environment as the GI frame binds it (SceneFrame::bindEnvironment): the
// lat-long map (as gi::EnvironmentMap samples it) and its irradiance as order-2 spherical
// harmonics (Ramamoorthi and Hanrahan 2001, "An Efficient Representation for Irradiance
// Environment Maps").
layout(binding = 5) uniform sampler2D uEnvironment;
uniform bool uHasEnvironment;
uniform float uEnvRotation;   // radians
uniform float uEnvScale;
uniform vec3 uEnvSh[9];       // irradiance SH coefficients (already convolved, times scale)

vec3 environment(vec3 d) {
  if (!uHasEnvironment) return vec3(0.0);
  float theta = atan(length(d.xy), d.z);
  float u = (atan(d.y, d.x) - uEnvRotation) / (2.0 * kPi);
  u -= floor(u);
  float v = clamp(theta / kPi, 0.0, 1.0);
  ivec2 size = textureSize(uEnvironment, 0);
  ivec2 texel = min(ivec2(vec2(u, v) * vec2(size)), size - 1);
  return texelFetch(uEnvironment, texel, 0).rgb * uEnvScale;
}

// The environment's mean radiance over a cone of `solidAngle` steradians about d, from the map's
// mip levels (box-filtered in latitude and longitude: close to the mean near the equator, wider
// in longitude towards the poles).
vec3 environmentOver(vec3 d, float solidAngle) {
  if (!uHasEnvironment) return vec3(0.0);
  float theta = atan(length(d.xy), d.z);
  float u = (atan(d.y, d.x) - uEnvRotation) / (2.0 * kPi);
  u -= floor(u);
  float v = clamp(theta / kPi, 0.0, 1.0);
  vec2 size = vec2(textureSize(uEnvironment, 0));
  float texel = (2.0 * kPi / size.x) * (kPi / size.y);  // a texel's solid angle at the equator
  float lod = max(0.5 * log2(max(solidAngle, 1e-12) / texel), 0.0);
  return textureLod(uEnvironment, vec2(u, v), lod).rgb * uEnvScale;
}

// Unshadowed irradiance from the environment on a surface of normal n.
vec3 irradiance(vec3 n) {
  return max(uEnvSh[0] + uEnvSh[1] * n.y + uEnvSh[2] * n.z + uEnvSh[3] * n.x + uEnvSh[4] * n.x * n.y +
                 uEnvSh[5] * n.y * n.z + uEnvSh[6] * (3.0 * n.z * n.z - 1.0) + uEnvSh[7] * n.x * n.z +
                 uEnvSh[8] * (n.x * n.x - n.y * n.y),
             vec3(0.0));
}
