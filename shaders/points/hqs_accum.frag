// High-quality splatting, pass 2 of 3: additive blending of weighted colour, normal and linear
// depth of the splat fragments within epsilon of the front surface (depth test against pass 1,
// no depth writes). The weight falls from 1 at a splat's centre to nearly 0 at its rim
// (1 - r^2, an Epanechnikov kernel), so neighbouring splats fade into each other.
in vec4 vColour;
in vec3 vNormal;
flat in vec3 vViewPos;

layout(location = 0) out vec4 outColour;  // rgb * w, w
layout(location = 1) out vec4 outNormal;  // normal * w, linear depth * w

void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  float r2 = dot(d, d);
  if (r2 > 1.0) discard;
  // A floor keeps a lone splat's rim visible: the weight only has to order neighbours.
  float w = max(1.0 - r2, 1.0 / 64.0);
  outColour = vec4(vColour.rgb * w, w);  // blended in linear light (the vertex shader decodes)
  outNormal = vec4(vNormal * w, -vViewPos.z * w);
}
