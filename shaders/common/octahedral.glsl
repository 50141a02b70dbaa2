// Octahedral unit vectors in 2 x 16 bits (Cigolle et al. 2014); the word 0 means "no normal".
vec3 decodeNormal(uint w) {
  if (w == 0u) return vec3(0.0);
  vec2 e = vec2(float(w & 0xffffu), float(w >> 16)) / 65535.0 * 2.0 - 1.0;
  vec3 n = vec3(e.xy, 1.0 - abs(e.x) - abs(e.y));
  if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  return normalize(n);
}
