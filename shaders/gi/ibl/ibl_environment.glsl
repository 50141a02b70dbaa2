// Sampling the environment by its tabulated row and column CDFs (gi/ibl/environment_table.h):
// the inversion method, a binary search in each table. Densities are per solid angle and equal
// gi::EnvironmentMap's: a texel's luminance over the map's power.
// Needs environment.glsl (uEnvironment, uEnvRotation, uEnvScale) and ibl_interface.glsl.
layout(std430, binding = IBL_SSBO_ENV) readonly buffer EnvTable { float envTable[]; };

int envWidth() { return floatBitsToInt(envTable[IBL_ENV_WIDTH]); }
int envHeight() { return floatBitsToInt(envTable[IBL_ENV_HEIGHT]); }
bool envBlack() { return envTable[IBL_ENV_BLACK] != 0.0; }

// The first i in [0, n) with cdf[base + i + 1] > u (the bin u falls in).
int envSearch(int base, int n, float u) {
  int lo = 0, hi = n - 1;
  while (lo < hi) {
    int mid = (lo + hi) >> 1;
    if (envTable[base + mid + 1] > u) hi = mid; else lo = mid + 1;
  }
  return lo;
}

// The texel a direction falls in (environment.glsl's convention).
ivec2 envTexel(vec3 d) {
  float theta = atan(length(d.xy), d.z);
  float u = (atan(d.y, d.x) - uEnvRotation) / (2.0 * kPi);
  u -= floor(u);
  float v = clamp(theta / kPi, 0.0, 1.0);
  ivec2 size = ivec2(envWidth(), envHeight());
  return min(ivec2(vec2(u, v) * vec2(size)), size - 1);
}

// Density per solid angle of envSample's directions (0 for a black map).
float envPdf(vec3 d) {
  if (envBlack()) return 0.0;
  vec3 c = texelFetch(uEnvironment, envTexel(d), 0).rgb;
  return luminance(c) / envTable[IBL_ENV_POWER];
}

// A direction with density envPdf; false for a black map.
bool envSample(vec2 u, out vec3 d) {
  d = vec3(0.0, 0.0, 1.0);
  if (envBlack()) return false;
  int w = envWidth(), h = envHeight();
  int rowCos = IBL_ENV_HEADER, marginal = rowCos + h + 1, conditional = marginal + h + 1;
  u = clamp(u, vec2(0.0), vec2(0.99999994));
  int row = envSearch(marginal, h, u.y);
  float r0 = envTable[marginal + row], r1 = envTable[marginal + row + 1];
  float t = r1 > r0 ? clamp((u.y - r0) / (r1 - r0), 0.0, 1.0) : 0.5;
  int base = conditional + row * (w + 1);
  int col = envSearch(base, w, u.x);
  float c0 = envTable[base + col], c1 = envTable[base + col + 1];
  float s = c1 > c0 ? clamp((u.x - c0) / (c1 - c0), 0.0, 1.0) : 0.5;
  // cos theta uniform inside the row: the texel's density per solid angle is constant.
  float cosTheta = mix(envTable[rowCos + row], envTable[rowCos + row + 1], t);
  float sinTheta = sqrt(max(0.0, 1.0 - cosTheta * cosTheta));
  float phi = 2.0 * kPi * (float(col) + s) / float(w) + uEnvRotation;
  d = vec3(sinTheta * cos(phi), sinTheta * sin(phi), cosTheta);
  return true;
}
