// Test pass (tests/frame): a per-frame target, 4 x 4 texels of a fixed pattern.
layout(location = 0) out vec4 outColour;
void main() { outColour = vec4(gl_FragCoord.xy / 4.0, 0.25, 1.0); }
