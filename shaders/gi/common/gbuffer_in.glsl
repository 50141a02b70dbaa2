// Reading a G-buffer sample (shaders/interface/frame_interface.glsl's encoding) back into a BSDF:
// scan points are Lambert reflectors of their colour (clamped to 1, as gi/reference treats them
// in the albedo mode), meshes take their material's parameters from NL_SSBO_MATERIALS.
#include "brdf.glsl"
layout(std430, binding = NL_SSBO_MATERIALS) readonly buffer Materials { MaterialRecord materials[]; };

int gbufferSource(uvec4 m) { return int(m.x >> 8); }

// `emission` receives the material's emitted radiance (meshes), 0 otherwise.
MaterialParams gbufferMaterial(vec3 base, uvec4 m, out vec3 emission) {
  MaterialParams mat;
  mat.type = int(m.x & 255u);
  mat.baseColor = gbufferSource(m) == NL_SOURCE_SCAN ? min(base, vec3(1.0)) : base;
  mat.roughness = float(m.y) / 65535.0;
  mat.metallic = float(m.z) / 65535.0;
  mat.specular = 0.5, mat.specularTint = 0.0, mat.sheen = 0.0, mat.sheenTint = 0.5;
  mat.clearcoat = 0.0, mat.clearcoatGloss = 1.0;
  emission = vec3(0.0);
  if (m.w != uint(NL_NO_MATERIAL)) {
    MaterialRecord r = materials[m.w];
    mat.specular = r.params.z, mat.specularTint = r.params.w;
    mat.sheen = r.params2.x, mat.sheenTint = r.params2.y, mat.clearcoat = r.params2.z, mat.clearcoatGloss = r.params2.w;
    emission = r.emission.rgb;
  }
  return mat;
}

// The diffuse lobe's albedo: Lambert's, the (1 - metallic) part of the others.
vec3 diffuseAlbedo(MaterialParams mat) {
  return mat.type == NL_MATERIAL_LAMBERT ? mat.baseColor : (1.0 - mat.metallic) * mat.baseColor;
}

// Roughly how much light the surface reflects in all (diffuse and specular), for weights and
// demodulation: the diffuse albedo plus the specular lobe's normal-incidence reflectance.
vec3 albedoEstimate(MaterialParams mat) {
  return diffuseAlbedo(mat) + (mat.type == NL_MATERIAL_LAMBERT ? vec3(0.0) : mix(vec3(0.04), mat.baseColor, mat.metallic));
}
