// Test pass (tests/frame): colour from the pixel's position in the full image, so a tile shows
// the same pixels as the untiled frame only if the graph placed it right; plus the palette.
#include "../interface/frame_interface.glsl"
layout(binding = 0) uniform sampler2D uPalette;
layout(location = 0) out vec4 outColour;
void main() {
  vec2 p = gl_FragCoord.xy - 0.5 + frame.tile.xy;  // full-image pixel
  uint h = uint(p.x) * 73856093u ^ uint(p.y) * 19349663u;
  vec4 pal = texelFetch(uPalette, ivec2(p) % 4, 0);
  outColour = vec4(p.x * frame.image.z, p.y * frame.image.w, float(h % 1024u) / 1024.0, 1.0) * pal.a + vec4(0, 0, pal.b, 0);
}
