// The direction a texel of a cube map face stands for (the GL cube map's faces: +x, -x, +y, -y,
// +z, -z; s to the right, t up the rows).
const float kImpostorFar = 1e30;  // the distance of a texel that shows the environment

vec3 impostorDirection(ivec3 p, int size) {
  vec2 st = (vec2(p.xy) + 0.5) / float(size) * 2.0 - 1.0;
  float s = st.x, t = st.y;
  vec3 d;
  if (p.z == 0) d = vec3(1.0, -t, -s);
  else if (p.z == 1) d = vec3(-1.0, -t, s);
  else if (p.z == 2) d = vec3(s, 1.0, t);
  else if (p.z == 3) d = vec3(s, -1.0, -t);
  else if (p.z == 4) d = vec3(s, -t, 1.0);
  else d = vec3(-s, -t, -1.0);
  return normalize(d);
}
