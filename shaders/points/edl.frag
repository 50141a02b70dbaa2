// Eye-dome lighting (Boucheny 2009, as in Potree): shade each pixel by how much nearer it is
// than its neighbours in log depth, which shows shape on scans without normals.
in vec2 vUv;
uniform sampler2D uColour;
uniform sampler2D uDepth;
uniform float uNear;
uniform float uFar;
uniform float uStrength;     // 0 disables
uniform float uRadius;       // pixels
uniform vec3 uBackground;

out vec4 outColour;

// log2 of the linear depth, which is negative closer than one world unit: background is told
// apart by the depth buffer's clear value, never by the sign.
bool covered(vec2 uv) { return texture(uDepth, uv).r < 1.0; }
float logDepth(vec2 uv) {
  float z = texture(uDepth, uv).r * 2.0 - 1.0;
  return log2(2.0 * uNear * uFar / (uFar + uNear - z * (uFar - uNear)));
}

void main() {
  bool isScan = covered(vUv);
  float centre = isScan ? logDepth(vUv) : 0.0;
  vec2 texel = uRadius / vec2(textureSize(uDepth, 0));
  float response = 0.0;
  int neighbours = 0;
  for (int k = 0; k < 8; ++k) {
    float a = float(k) * 0.78539816;
    vec2 uv = vUv + vec2(cos(a), sin(a)) * texel;
    if (!covered(uv)) continue;  // background neighbours say nothing about shape
    ++neighbours;
    if (isScan) response += max(0.0, centre - logDepth(uv));
  }
  if (!isScan) {
    // Background next to the scan: a dark outline around silhouettes (as Potree does).
    float outline = uStrength > 0.0 && neighbours > 0 ? 1.0 - exp(-float(neighbours) * uStrength) : 0.0;
    outColour = vec4(uBackground * (1.0 - outline), 1.0);
    return;
  }
  vec3 colour = texture(uColour, vUv).rgb;
  if (uStrength > 0.0) colour *= exp(-response / 8.0 * 300.0 * uStrength);
  outColour = vec4(colour, 1.0);
}
