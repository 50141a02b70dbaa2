// vct's directional opacity, one level of it (Crassin, Neyret, Sainz, Green and Eisemann,
// "Interactive Indirect Illumination Using Voxel Cone Tracing", 2011, section 5: anisotropic
// voxels): per axis, each 2x2x2 block's four pairs of voxels along the axis composited
// (a + b - a b, the opacity a ray along that axis meets through both) and averaged. Averaged mips
// halve a one-voxel wall's opacity at every level, so cones leaked through a closed room's walls;
// along the wall's normal the composite keeps it whole. Opacity alone: compositing it is the same
// in both directions along an axis, so three channels hold all six directions.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(rgba8, binding = 0) uniform writeonly image3D uOut;  // this level: x, y, z opacity
layout(r8, binding = 1) uniform readonly image3D uBase;     // the scene volume's opacity, level 0
layout(rgba8, binding = 2) uniform readonly image3D uPrev;  // the level before (not uFromBase)
uniform ivec3 uDims, uSourceDims;
uniform bool uFromBase;

vec3 sourceAt(ivec3 s) {
  s = min(s, uSourceDims - 1);
  if (uFromBase) return vec3(imageLoad(uBase, s).r);
  return imageLoad(uPrev, s).rgb;
}

float through(float a, float b) { return a + b - a * b; }

void main() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(v, uDims))) return;
  vec3 a[8];
  for (int i = 0; i < 8; ++i) a[i] = sourceAt(2 * v + ivec3(i & 1, (i >> 1) & 1, i >> 2));
  vec3 o = vec3(0.0);
  for (int i = 0; i < 8; ++i) {
    if ((i & 1) == 0) o.x += through(a[i].x, a[i + 1].x);
    if ((i & 2) == 0) o.y += through(a[i].y, a[i + 2].y);
    if ((i & 4) == 0) o.z += through(a[i].z, a[i + 4].z);
  }
  imageStore(uOut, v, vec4(0.25 * o, 1.0));
}
