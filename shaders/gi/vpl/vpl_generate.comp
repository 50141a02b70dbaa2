// The first generation of VPLs (Preiner, section 4.2): each warped sample's light G-buffer texel
// becomes a VPL with the texel's position, normal and material, carrying the flux the texel
// receives divided by the count and the sample's probability (an unbiased estimate of the
// reflected light, whatever the importance).
layout(local_size_x = 64) in;
#include "light_texel.glsl"
layout(std430, binding = VPL_SSBO_SAMPLES) readonly buffer Samples { WarpSample samples[]; };
layout(std430, binding = VPL_SSBO_RECORDS) writeonly buffer Vpls { VplRecord vpls[]; };
uniform int uCount;
void main() {
  int k = int(gl_GlobalInvocationID.x);
  if (k >= uCount) return;
  WarpSample s = samples[k];
  VplRecord v;
  v.position = vec4(0.0);
  v.normal = vec4(0.0, 0.0, 1.0, 1.0);
  v.flux = vec4(0.0);
  v.incident = vec4(0.0, 0.0, 1.0, float(NL_NO_MATERIAL));
  v.baseColour = vec4(0.0);
  LightTexel t;
  t.valid = false;
  if (s.texel.w == 1 && s.where.z > 0.0) t = lightTexel(s.texel.xyz);
  if (t.valid) {
    v.position = vec4(t.p, t.radius);
    v.normal = vec4(t.n, t.mat.roughness);
    v.flux = vec4(t.fluxIn / (float(uCount) * s.where.z), t.mat.metallic);
    v.incident = vec4(t.wi, float(t.materialIndex));
    v.baseColour = vec4(t.mat.baseColor, float(t.mat.type));
  }
  vpls[k] = v;
}
