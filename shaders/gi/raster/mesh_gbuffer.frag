// Meshes into the G-buffer: the material's base colour tinted by the vertex colour (as the
// reference tints it), the interpolated normal or, without one, the face's.
#include "../common/gbuffer_out.glsl"
in vec3 vWorld;
in vec3 vNormal;
in vec3 vColour;
uniform vec3 uBaseColor;
uniform int uMaterialType;
uniform float uRoughness, uMetallic;
uniform uint uMaterialIndex;
void main() {
  vec3 n = vNormal;
  if (!(dot(n, n) > 0.0)) n = cross(dFdx(vWorld), dFdy(vWorld));
  n = dot(n, n) > 0.0 ? normalize(n) : vec3(0.0);
  writeGBuffer(uBaseColor * vColour, 0.0, n, uMaterialType, NL_SOURCE_MESH, uRoughness, uMetallic, uMaterialIndex);
}
