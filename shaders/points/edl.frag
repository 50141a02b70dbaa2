// Eye-dome lighting (Boucheny 2009, as in Potree): shade each pixel by how much nearer it is
// than its neighbours in log depth, which shows shape on scans without normals. Reads the linear
// G-buffer colour and writes the displayed (sRGB) value, scaled by the shading factor as Potree
// does: the point view's tone map (exposure 0, the sRGB curve) is folded into this pass, which
// saves a full-screen pass per frame (10-20% of a llvmpipe frame at 1920 x 1080).
#include "../common/srgb.glsl"
uniform sampler2D uColour;
uniform sampler2D uDepth;
uniform float uNear;
uniform float uFar;
uniform float uStrength;     // 0 disables
uniform float uRadius;       // pixels
uniform vec3 uBackground;   // display-referred
uniform bool uLinearOutput;  // write linear colour (HDR files), else the sRGB display value
uniform float uExposure;     // linear factor, 2^stops
uniform vec2 uViewport;      // the tile's pixels, at the targets' lower left (targets may be larger)

out vec4 outColour;

// A pixel position to texture coordinates, clamped to the tile as clamp-to-edge would be.
vec2 texUv(vec2 px) { return clamp(px, vec2(0.5), uViewport - 0.5) / vec2(textureSize(uDepth, 0)); }

// log2 of the linear depth, which is negative closer than one world unit: background is told
// apart by the depth buffer's clear value, never by the sign.
bool covered(vec2 uv) { return texture(uDepth, uv).r < 1.0; }
float logDepth(vec2 uv) {
  float z = texture(uDepth, uv).r * 2.0 - 1.0;
  return log2(2.0 * uNear * uFar / (uFar + uNear - z * (uFar - uNear)));
}

void main() {
  vec2 here = texUv(gl_FragCoord.xy);
  bool isScan = covered(here);
  float centre = isScan ? logDepth(here) : 0.0;
  float response = 0.0;
  int neighbours = 0;
  for (int k = 0; k < 8; ++k) {
    float a = float(k) * 0.78539816;
    vec2 uv = texUv(gl_FragCoord.xy + vec2(cos(a), sin(a)) * uRadius);
    if (!covered(uv)) continue;  // background neighbours say nothing about shape
    ++neighbours;
    if (isScan) response += max(0.0, centre - logDepth(uv));
  }
  if (!isScan) {
    // Background next to the scan: a dark outline around silhouettes (as Potree does).
    float outline = uStrength > 0.0 && neighbours > 0 ? 1.0 - exp(-float(neighbours) * uStrength) : 0.0;
    vec3 bg = uLinearOutput ? srgbDecode(uBackground) : uBackground;
    outColour = vec4(bg * (1.0 - outline), 1.0);
    return;
  }
  vec3 colour = texture(uColour, here).rgb;
  colour *= uExposure;
  if (!uLinearOutput) colour = srgbEncode(colour);
  if (uStrength > 0.0) colour *= exp(-response / 8.0 * 300.0 * uStrength);
  outColour = vec4(colour, 1.0);
}
