// The tone map of gi/metrics (nestlight/gi/tone_map.h), on the GPU: 2^exposure, clamp to [0, 1],
// the sRGB transfer function (IEC 61966-2-1). NaN shows as magenta, as the PNG writer does.
#include "../interface/frame_interface.glsl"
#include "../common/srgb.glsl"
layout(binding = 0) uniform sampler2D uLinear;
uniform float uScale;  // 2^exposure
layout(location = 0) out vec4 outDisplay;

void main() {
  vec3 c = texelFetch(uLinear, ivec2(gl_FragCoord.xy), 0).rgb;
  if (any(isnan(c))) {
    outDisplay = vec4(1.0, 0.0, 1.0, 1.0);
    return;
  }
  // min() keeps +Inf (and overflow of the product) at 1 without relying on clamp(Inf).
  c = min(c * uScale, vec3(1.0));
  outDisplay = vec4(srgbEncode(c.r), srgbEncode(c.g), srgbEncode(c.b), 1.0);
}
