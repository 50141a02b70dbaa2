// A mesh of the captured scene (meshes[].inserted false: a lamp, a light panel) into a face of the
// distance impostor: what the capture records of it is its emission (its reflected light is not
// known without a capture of it), and its distance from the impostor's centre.
#include "../../interface/frame_interface.glsl"
layout(std430, binding = NL_SSBO_MATERIALS) readonly buffer Materials { MaterialRecord materials[]; };
in vec3 vWorld;
uniform uint uMaterialIndex;
uniform vec3 uCentre;
layout(location = 0) out vec4 outImpostor;

void main() {
  outImpostor = vec4(materials[uMaterialIndex].emission.rgb, max(length(vWorld - uCentre), 1e-6));
}
