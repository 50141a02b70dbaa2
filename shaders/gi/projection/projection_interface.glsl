// The `projection` method's buffers (Maletz, Wang and Bowers, "Importance-Driven Point Projection
// for GPU-based Final Gathering", 2011) as C++ writes them and GLSL reads them. Kept to the
// preprocessor subset both share; include frame_interface.glsl first (NL_STRUCT).

#define PROJECTION_SSBO_POINTS (NL_SSBO_METHOD0 + 0)    // ProjectionPoint[]: S, cluster by cluster
#define PROJECTION_SSBO_CLUSTERS (NL_SSBO_METHOD0 + 1)  // uint[K + 1]: each cluster's first point
#define PROJECTION_SSBO_SOLID (NL_SSBO_METHOD0 + 2)     // float[M x M]: the texels' solid angles
#define PROJECTION_SSBO_RADIANCE (NL_SSBO_METHOD0 + 3)  // vec4[]: each point's outgoing radiance
#define PROJECTION_SSBO_PIXELS (NL_SSBO_METHOD0 + 5)    // vec4[2 per tile pixel]: (E, state), (glossy rest, level)
#define PROJECTION_SSBO_FILTERED (NL_SSBO_METHOD0 + 7)  // vec4[2 per tile pixel]: the post filter's output
#define PROJECTION_SSBO_LIST (NL_SSBO_METHOD0 + 6)      // uint[]: [0] pixels to gather, then each pixel (x | y << 16)
#define PROJECTION_SSBO_STATS (NL_SSBO_METHOD0 + 4)     // uint[8]: receivers, unweighted pdfs, empty texels, splats, filled texels

// A receiver's samples are told apart in the micro-buffer's depth words by 12 bits.
#define PROJECTION_MAX_SAMPLES 4096
#define PROJECTION_NO_SAMPLE 0xffffffffu
#define PROJECTION_BACK_FACING 0x80000000u  // a sample's flag: it shows the receiver its back

// 48 bytes.
NL_STRUCT(ProjectionPoint) {
  vec4 positionArea;  // xyz scene-local position, w: the surface area it stands for (Delta A)
  vec4 normalColour;  // x: its normal, octahedral word (0: none), yzw: its linear colour (a scan
                      // point: the radiance-cache mode's radiance, the albedo mode's albedo; a
                      // mesh's surfel: its albedo)
  uvec4 source;       // x: 0 a scan point, else a mesh's surfel: its material + 1; y: a glossy
                      // surfel's lobes, slot + 1 (0: diffuse); zw: its diffuse colour, half
                      // floats (r, g), (b, 0)
};

// A glossy surfel's lobes follow the points' radiance in PROJECTION_SSBO_RADIANCE: from
// radiance[count + 2 x PROJECTION_LOBES x (slot - 1)], per lobe (direction to its light, 0) and
// (the irradiance that light gives, 0).
#define PROJECTION_LOBES 4

// A tile pixel's state in the adaptive sampling (PROJECTION_SSBO_PIXELS, first vec4's w).
#define PROJECTION_UNSET 0.0         // not reached yet, or no receiver
#define PROJECTION_GATHERED 1.0      // its micro-buffer was gathered
#define PROJECTION_INTERPOLATED 2.0  // upsampled from the corners of its cell
#define PROJECTION_LISTED 3.0        // to be gathered (progressive frames: not yet)
