// Test harness (tests/gi_gl/ibl_sampler_test.cpp): draws the `ibl` method's samples as its
// estimators do (the environment's tabulated CDFs, the BSDF's lobes) and writes each direction
// with the density the method would weigh it by, for chi-square tests against gi/core's pdfs.
layout(local_size_x = 64) in;
#include "../gi/common/brdf_sample.glsl"
#include "../gi/common/environment.glsl"
#include "../gi/ibl/ibl_interface.glsl"
#include "../gi/ibl/ibl_environment.glsl"
layout(std430, binding = 0) writeonly buffer Samples { vec4 samples[]; };  // xyz, w: pdf (-1: none)
uniform int uMode;  // 0: the environment, 1: the BSDF
uniform int uCount;
uniform uint uSeed;
uniform int uType;
uniform vec3 uBase;
uniform vec4 uParams;   // roughness, metallic, specular, specular tint
uniform vec4 uParams2;  // sheen, sheen tint, clearcoat, clearcoat gloss
uniform vec3 uWo;

uint hashU(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}

void main() {
  int i = int(gl_GlobalInvocationID.x);
  if (i >= uCount) return;
  uint s = hashU(uint(i) ^ hashU(uSeed));
  float u[3];
  for (int k = 0; k < 3; ++k) {
    s = hashU(s);
    u[k] = float(s >> 8) * (1.0 / 16777216.0);
  }
  vec3 d;
  if (uMode == 0) {
    bool ok = envSample(vec2(u[0], u[1]), d);
    samples[i] = vec4(d, ok ? envPdf(d) : -1.0);
  } else {
    MaterialParams m;
    m.type = uType;
    m.baseColor = uBase;
    m.roughness = uParams.x, m.metallic = uParams.y, m.specular = uParams.z, m.specularTint = uParams.w;
    m.sheen = uParams2.x, m.sheenTint = uParams2.y, m.clearcoat = uParams2.z, m.clearcoatGloss = uParams2.w;
    bool ok = sampleBsdf(m, uWo, vec2(u[0], u[1]), u[2], d);
    samples[i] = vec4(d, ok ? pdfBsdf(m, uWo, d) : -1.0);
  }
}
