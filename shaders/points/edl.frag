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

float logDepth(vec2 uv) {
  float d = texture(uDepth, uv).r;
  if (d >= 1.0) return -1.0;  // background
  float z = d * 2.0 - 1.0;
  return log2(2.0 * uNear * uFar / (uFar + uNear - z * (uFar - uNear)));
}

void main() {
  float centre = logDepth(vUv);
  vec2 texel = uRadius / vec2(textureSize(uDepth, 0));
  float response = 0.0;
  int covered = 0;
  for (int k = 0; k < 8; ++k) {
    float a = float(k) * 0.78539816;
    float n = logDepth(vUv + vec2(cos(a), sin(a)) * texel);
    if (n < 0.0) continue;  // background neighbours say nothing about shape
    ++covered;
    response += max(0.0, centre - n);
  }
  if (centre < 0.0) {
    // Background next to the scan: a dark outline around silhouettes (as Potree does).
    float outline = uStrength > 0.0 && covered > 0 ? 1.0 - exp(-float(covered) * uStrength) : 0.0;
    outColour = vec4(uBackground * (1.0 - outline), 1.0);
    return;
  }
  vec3 colour = texture(uColour, vUv).rgb;
  if (uStrength > 0.0) colour *= exp(-response / 8.0 * 300.0 * uStrength);
  outColour = vec4(colour, 1.0);
}
