// Inserted meshes, in the scene's local frame (positions and normals transformed on the CPU).
#include "../../interface/frame_interface.glsl"
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;  // 0 when the mesh has none
layout(location = 2) in vec3 aColour;  // vertex colour, 1 without
uniform mat4 uClipFromWorld;           // the camera's (frame.clipFromWorld) or a light's view
out vec3 vWorld;
out vec3 vNormal;
out vec3 vColour;
void main() {
  vWorld = aPosition;
  vNormal = aNormal;
  vColour = aColour;
  gl_Position = uClipFromWorld * vec4(aPosition, 1.0);
}
