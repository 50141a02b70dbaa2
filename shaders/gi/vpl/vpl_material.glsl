// A VPL's BSDF from its record (shaders/gi/vpl/vpl_interface.glsl), its material's other
// parameters from NL_SSBO_MATERIALS (meshes).
#include "../common/gbuffer_in.glsl"
#include "vpl_interface.glsl"
MaterialParams vplMaterial(VplRecord v) {
  MaterialParams m;
  m.type = int(v.baseColour.w);
  m.baseColor = v.baseColour.rgb;
  m.roughness = v.normal.w;
  m.metallic = v.flux.w;
  m.specular = 0.5, m.specularTint = 0.0, m.sheen = 0.0, m.sheenTint = 0.5, m.clearcoat = 0.0, m.clearcoatGloss = 1.0;
  uint index = uint(v.incident.w);
  if (index < uint(VPL_EMITTER)) {
    MaterialRecord r = materials[index];
    m.specular = r.params.z, m.specularTint = r.params.w;
    m.sheen = r.params2.x, m.sheenTint = r.params2.y, m.clearcoat = r.params2.z, m.clearcoatGloss = r.params2.w;
  }
  return m;
}
