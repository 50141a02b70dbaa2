// Where a fragment of a point sprite meets its splat: the splat is a disc in the point's tangent
// plane (as the reference's discs), so the viewing ray through the fragment is intersected with
// that plane (Botsch, Hornung, Zwicker, Kobbelt, "High-Quality Surface Splatting on Today's
// GPUs", 2005, section 3.1: per-pixel ray casting of splats). A round sprite drawn flat at the
// centre's depth overhangs a surface seen at a grazing angle by the full radius; the disc only by
// the radius times the sine of the viewing angle (at a box's edge seen at 20 degrees: a third),
// and the depth along the disc follows the surface. Points without a normal stay screen-aligned.
flat in vec3 vViewPos;     // the splat's centre, view space
flat in vec3 vViewNormal;  // its normal, view space (zero: no normal)
flat in float vRadius;     // its radius, world units
flat in float vPointSize;  // the sprite's size, pixels
uniform bool uOrthographic;

// The view-space point of the splat under this fragment and its squared distance from the centre
// in radii; false when the fragment lies outside the disc. The fragment holding the centre is
// always inside (a disc seen edge-on, or smaller than a pixel, still covers its own pixel).
bool splatSurface(out vec3 p, out float r2) {
  vec2 d = gl_PointCoord * 2.0 - 1.0;
  // The fragment's offset on the plane through the centre facing the view (gl_PointCoord's y
  // runs down the image, view space's up).
  vec3 q = vViewPos + vec3(d.x, -d.y, 0.0) * vRadius;
  p = q;
  r2 = dot(d, d);
  bool centre = r2 * vPointSize * vPointSize <= 1.0;  // within half a pixel of the centre
  if (dot(vViewNormal, vViewNormal) < 0.25) return r2 <= 1.0;
  vec3 n = vViewNormal;
  if (uOrthographic) {
    // Rays along view -z: move q along z onto the plane.
    if (abs(n.z) < 1e-3) return centre;
    p = q - vec3(0.0, 0.0, dot(q - vViewPos, n) / n.z);
  } else {
    // Rays from the eye (view-space origin) through q.
    float dn = dot(q, n);
    if (abs(dn) < 1e-3 * length(q)) return centre;
    p = q * (dot(vViewPos, n) / dn);
  }
  vec3 off = p - vViewPos;
  r2 = dot(off, off) / (vRadius * vRadius);
  if (r2 <= 1.0) return true;
  if (!centre) return false;
  p = vViewPos, r2 = 0.0;
  return true;
}

// Window depth of a view-space point under `clipFromView`.
float windowDepth(mat4 clipFromView, vec3 viewPos) {
  vec4 clip = clipFromView * vec4(viewPos, 1.0);
  return clamp(clip.z / clip.w * 0.5 + 0.5, 0.0, 1.0);
}
