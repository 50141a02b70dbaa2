// The `vpl` method's interface, read by C++ (gi/vpl) and GLSL alike: its buffer bindings (the
// GI frame's method slots, NL_SSBO_METHOD0..) and records. Kept to the preprocessor subset both
// share; include frame_interface.glsl first.

#define VPL_SSBO_RECORDS (NL_SSBO_METHOD0 + 0)    // VplRecord[]: every generation's VPLs
#define VPL_SSBO_PYRAMID (NL_SSBO_METHOD0 + 1)    // float[]: importance and its sum pyramid, per layer
#define VPL_SSBO_SAMPLES (NL_SSBO_METHOD0 + 2)    // WarpSample[]: warped Halton points
#define VPL_SSBO_POOL (NL_SSBO_METHOD0 + 3)       // PoolPoint[]: ISM occluders (the lights' cut, surfels)
#define VPL_SSBO_POOL_NODES (NL_SSBO_METHOD0 + 4) // PoolNode[]: their nodes, for LOD selection
#define VPL_SSBO_ISM (NL_SSBO_METHOD0 + 5)        // uint[]: the ISM atlas (distance as float bits)
#define VPL_SSBO_ISM_PYRAMID (NL_SSBO_METHOD0 + 6)// float[]: pull-push levels of every ISM
#define VPL_SSBO_LIGHT_VIEWS (NL_SSBO_METHOD0 + 7)// LightView[]: each light G-buffer layer's inverse

// Visibility "exact" (the ablation): Embree's answer per pixel and VPL of its subset, one bit
// each, and the counts of (pixel, VPL) pairs where the ISM agreed with it. They reuse the warp's
// slots, which shading does not bind.
#define VPL_SSBO_EXACT (NL_SSBO_METHOD0 + 1)      // uint[]: bits, words per pixel in uExactWords
#define VPL_SSBO_AGREEMENT (NL_SSBO_METHOD0 + 2)  // uint[6]: pairs agreeing, compared, ISM occluded but
                                                  // visible, ISM visible but occluded; per pixel the
                                                  // light-weighted share agreeing (sum of 1/1024ths),
                                                  // 1024 x pixels compared

#define VPL_EMITTER 65534.0                        // VplRecord.incident.w of an emitting scan point
#define VPL_FAR_BITS 0x7f7fffffu                  // FLT_MAX: an empty ISM texel

// One VPL. Its emission towards w is flux x f(wi, w) x cos(n, w): the flux that reached it and
// its surface's BSDF (diffuse and glossy VPLs alike). flux = 0: a dead VPL (its sample found
// nothing).
NL_STRUCT(VplRecord) {
  vec4 position;   // xyz world, w: splat radius of its surface (ISM self-occlusion)
  vec4 normal;     // xyz unit (faces where the light came from), w: roughness
  vec4 flux;       // rgb: incident flux (W) divided by the sample's probability, w: metallic
  vec4 incident;   // xyz: unit direction towards where the light came from, w: material index
                   // (VPL_EMITTER: a scan point emitting its colour, radiance-cache mode)
  vec4 baseColour; // rgb linear, w: material type (NL_MATERIAL_*)
};

// A warped sample: which texel of which layer, where in it, with what probability.
NL_STRUCT(WarpSample) {
  ivec4 texel;     // x, y, layer, valid (1) or not (0: nothing had importance)
  vec4 where;      // xy: position in the texel [0,1)^2, z: probability of the texel, w: unused
};

#define VPL_POOL_CLIPPED (-1.0)

// An ISM occluder: scene-local position and splat radius (world).
NL_STRUCT(PoolPoint) {
  vec4 position;   // xyz, w: radius (VPL_POOL_CLIPPED: a point the clipping volumes remove)
  uvec4 surface;   // x: octahedral normal, y: colour rg (half2), z: colour b (half) | material << 16, w: area (float bits)
};

// A node of the pool (a node of the lights' cut, or one mesh's surfels).
NL_STRUCT(PoolNode) {
  vec4 box;        // centre xyz, w: half edge
  vec4 lod;        // x: spacing of its level, y: its parent's (1e30: a root), zw: unused
  ivec4 range;     // x: first point, y: count, zw: unused
};

// A light G-buffer layer: world from clip, and what one texel stands for.
NL_STRUCT(LightView) {
  mat4 worldFromClip;
  vec4 info;       // x: light index, y: tan of the half field of view (perspective) or half extent (ortho), z: 1 orthographic, w: unused
};
