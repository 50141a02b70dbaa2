// Basic splats: the nearest splat wins each pixel. Writes the G-buffer: linear colour (decoded by
// the vertex shader) and view-space normal.
in vec4 vColour;
in vec3 vNormal;
uniform bool uRound;

layout(location = 0) out vec4 outColour;
layout(location = 1) out vec4 outNormal;

void main() {
  if (uRound) {
    vec2 d = gl_PointCoord * 2.0 - 1.0;
    if (dot(d, d) > 1.0) discard;
  }
  outColour = vec4(vColour.rgb, 1.0);
  outNormal = vec4(vNormal, dot(vNormal, vNormal) > 0.0 ? 1.0 : 0.0);
}
