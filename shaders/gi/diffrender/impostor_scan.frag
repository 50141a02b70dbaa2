// A scan point into a face of the distance impostor (diffrender_common.glsl): its captured
// radiance and the distance from the impostor's centre (the face camera's origin) along the
// texel's ray to the point's disc. Splats are cut to their discs and write the disc's depth: a
// floor seen at a grazing angle from the centre would otherwise stand up as round splats in
// front of the walls behind it, and the stored distances follow the surface instead of stepping
// from splat centre to splat centre (DIT's search and secant read them as a continuous
// function). A point without a normal is a disc facing the centre.
in vec3 vColour;
flat in vec3 vViewPos;
flat in vec3 vViewNormal;
flat in float vRadius;
uniform float uFaceSize;  // texels per side of the face (a 90-degree frustum)
uniform float uNear, uFar;
layout(location = 0) out vec4 outImpostor;

void main() {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  if (dot(d, d) > 1.0) discard;
  vec2 ndc = gl_FragCoord.xy / uFaceSize * 2.0 - 1.0;
  vec3 ray = normalize(vec3(ndc, -1.0));
  vec3 n = dot(vViewNormal, vViewNormal) > 0.5 ? normalize(vViewNormal) : -normalize(vViewPos);
  float facing = dot(ray, n);
  if (abs(facing) < 1e-3) discard;
  float t = dot(vViewPos, n) / facing;
  // A little beyond the disc's radius, so that neighbouring discs overlap without gaps.
  if (!(t > 0.0) || length(ray * t - vViewPos) > 1.25 * vRadius) discard;
  float z = -t * ray.z;  // the view depth
  float ndcZ = ((uFar + uNear) * z - 2.0 * uFar * uNear) / ((uFar - uNear) * z);
  gl_FragDepth = clamp(ndcZ * 0.5 + 0.5, 0.0, 1.0);
  outImpostor = vec4(vColour, max(t, 1e-6));
}
