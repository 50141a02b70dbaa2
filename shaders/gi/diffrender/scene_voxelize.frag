// The lights' cut into the voxel cone tracer's scene volume (Crassin, Neyret, Sainz, Green and
// Eisemann, "Interactive Indirect Illumination Using Voxel Cone Tracing", 2011): each point is
// drawn as one pixel of an orthographic view down the volume's z (so that the fragment stage runs
// once per point) and adds its captured radiance and a count to its voxel, in fixed point (no
// float atomics on every GL 4.5 driver). Only the slab of z layers the images hold now.
in vec3 vColour;
flat in vec3 vViewPos;  // the view is the identity: the point's scene-local position
layout(r32ui, binding = 0) uniform coherent uimage3D uSumR;
layout(r32ui, binding = 1) uniform coherent uimage3D uSumG;
layout(r32ui, binding = 2) uniform coherent uimage3D uSumB;
layout(r32ui, binding = 3) uniform coherent uimage3D uCount;
uniform vec3 uVolumeOrigin;
uniform float uCell;
uniform ivec3 uDims;
uniform int uSlabFirst, uSlabDepth;
uniform float uFixedPoint;  // units per radiance unit

void main() {
  ivec3 v = ivec3(floor((vViewPos - uVolumeOrigin) / uCell));
  if (any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, uDims))) discard;
  int z = v.z - uSlabFirst;
  if (z < 0 || z >= uSlabDepth) discard;
  ivec3 s = ivec3(v.xy, z);
  // Radiance beyond half-float range is clamped there (the volume stores R11G11B10F).
  vec3 c = clamp(vColour, vec3(0.0), vec3(60000.0)) * uFixedPoint;
  imageAtomicAdd(uSumR, s, uint(c.r + 0.5));
  imageAtomicAdd(uSumG, s, uint(c.g + 0.5));
  imageAtomicAdd(uSumB, s, uint(c.b + 0.5));
  imageAtomicAdd(uCount, s, 1u);
  discard;
}
