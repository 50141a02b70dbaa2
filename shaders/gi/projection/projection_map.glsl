// The micro-buffer's hemi-octahedral map (Maletz, Wang and Bowers, "Importance-Driven Point
// Projection for GPU-based Final Gathering", 2011, section 4.2, eq. 2): a direction of the
// receiver's upper hemisphere, in a frame whose +y is the receiver's normal, projected onto the
// octahedron |x| + |y| + |z| = 1 and its upper half unfolded into the unit square turned by 45
// degrees. The map is piecewise linear on the octahedron, so a texel's solid angle is exact
// (gi/projection/hemi_octahedral.h tabulates it); the inverse is exact too.

// Unit square coordinates of direction w (w.y >= 0; any length but 0).
vec2 hemiOctEncode(vec3 w) {
  vec3 o = w / (abs(w.x) + abs(w.y) + abs(w.z));
  return vec2(0.5 * (1.0 - o.x + o.z), 0.5 * (1.0 - o.x - o.z));
}

// The unit direction at unit square coordinates t (the inverse of hemiOctEncode).
vec3 hemiOctDecode(vec2 t) {
  float x = 1.0 - t.x - t.y, z = t.x - t.y;
  return normalize(vec3(x, max(1.0 - abs(x) - abs(z), 0.0), z));
}
