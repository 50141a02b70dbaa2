// The GI frame's interface, read by C++ and GLSL alike (C++ includes it through
// nestlight/frame/interface.h, which supplies the glm types first): buffer and texture bindings,
// the G-buffer's output locations and encodings, the frame's uniform block, the point layout of
// resident nodes. A binding or a field changed here changes on both sides.
//
// Kept to the preprocessor subset GLSL and C++ share: #define, #ifdef, no #include.

// Uniform blocks.
#define NL_UBO_FRAME 0           // FrameBlock, every pass of the frame
#define NL_UBO_PASS 1            // a pass's own block
#define NL_UBO_CLIP 2            // ClipBlock: the clipping volumes (common/clip_volumes.glsl)

// Shader storage. Each resident node's layers bind at NL_SSBO_NODE_POINTS + layer.
#define NL_SSBO_NODE_POINTS 0    // the node's points (NL_POINT_WORDS words each)
#define NL_SSBO_NODE_LAYER1 1    // first method layer of the node (a hierarchy, an HDR colour)
#define NL_SSBO_NODE_LAYER2 2
#define NL_SSBO_LIGHTS 4         // LightRecord[], the frame's lights
#define NL_SSBO_DRAW_TREE 5      // drawn nodes' octants and spacings (points/splat_size.glsl)
#define NL_SSBO_SHADOW_VIEWS 6   // mat4[]: clip of each shadow-map layer's view (light views)
#define NL_SSBO_MATERIALS 7      // MaterialRecord[], the scene's materials
#define NL_SSBO_METHOD0 8        // free for GI methods (VPLs, hierarchies): 8..15 (contexts with fewer
                                 // than 16 bindings are refused, nestlight/gl/context.h)
#define NL_MAX_NODE_LAYERS 4

// The point view's compute rasteriser (points/raster_*.comp): per-pixel buffers. They reuse the
// node-layer and light slots, which the point view does not bind.
#define NL_SSBO_RASTER_DEPTH 1
#define NL_SSBO_RASTER_ACCUM 2
#define NL_SSBO_RASTER_NORMAL 3
#define NL_SSBO_RASTER_PACKED 4         // 64-bit: min(depth << 32 | colour)
#define NL_SSBO_RASTER_PACKED_NORMAL 6  // 64-bit: min(depth << 32 | normal)

// The raster method's compute rasteriser (gi/raster/scan_compute_*): per-pixel buffers.
#define NL_SSBO_SCAN_DEPTH (NL_SSBO_METHOD0 + 0)
#define NL_SSBO_SCAN_ACCUM (NL_SSBO_METHOD0 + 1)
#define NL_SSBO_SCAN_NORMAL (NL_SSBO_METHOD0 + 2)
#define NL_SSBO_SCAN_RADIUS (NL_SSBO_METHOD0 + 3)

// Points of a resident node: position (3 floats, relative to the node's cube origin), display
// colour RGBA8, normal as 2 x 16-bit octahedral coordinates (0: the scan has none).
#define NL_POINT_WORDS 5u

// G-buffer colour outputs (fragment locations), linear HDR.
#define NL_GBUFFER_BASE_COLOUR 0 // RGBA32F: linear base colour (scan: colour x colour_scale), a: splat radius (world; 0 meshes)
#define NL_GBUFFER_NORMAL 1      // RGBA16F: world (scene-local) unit normal, a = 1 when known
#define NL_GBUFFER_MATERIAL 2    // RGBA16UI: type | source << 8, roughness and metallic (unorm16), material index
#define NL_GBUFFER_OUTPUTS 3

// Material types (gi::MaterialType) and sources, as the material target stores them.
#define NL_MATERIAL_LAMBERT 0
#define NL_MATERIAL_GGX 1
#define NL_MATERIAL_PRINCIPLED 2
#define NL_SOURCE_NONE 0
#define NL_SOURCE_SCAN 1
#define NL_SOURCE_MESH 2
#define NL_NO_MATERIAL 65535     // material index of scan points (their material is their colour)

// Light types (gi::LightType).
#define NL_LIGHT_POINT 0
#define NL_LIGHT_SPOT 1
#define NL_LIGHT_DIRECTIONAL 2
#define NL_MAX_LIGHTS 16

#ifdef __cplusplus
#define NL_UNIFORM_BLOCK(b, type) struct alignas(16) type
#define NL_END_BLOCK(instance) ;
#define NL_STRUCT(type) struct alignas(16) type
#else
#define NL_UNIFORM_BLOCK(b, type) layout(std140, binding = b) uniform type
#define NL_END_BLOCK(instance) instance;
#define NL_STRUCT(type) struct type
#endif

// Only vec4, ivec4 and mat4 members: their std140 and std430 layouts equal C++'s.
NL_UNIFORM_BLOCK(NL_UBO_FRAME, FrameBlock) {
  mat4 viewFromWorld;   // world = the scene's local frame (float, relative to its origin)
  mat4 clipFromView;    // the tile's projection: the full image's, scaled and offset to the tile
  mat4 clipFromWorld;
  mat4 worldFromClip;   // inverse of clipFromWorld
  vec4 eye;             // xyz: camera position (world), w: pixels per unit at distance 1 (full image)
  vec4 tile;            // x0, y0 (GL pixels of the full image), width, height of this tile
  vec4 image;           // full width, height, 1 / width, 1 / height
  ivec4 counts;         // x: lights, y: mode (0 radiance cache, 1 albedo), z: frame number, w: unused
}
NL_END_BLOCK(frame)

// One light of the frame (NL_SSBO_LIGHTS), as gi::Light with the shadow map that covers it.
NL_STRUCT(LightRecord) {
  vec4 position;        // xyz world, w: type (NL_LIGHT_*)
  vec4 direction;       // xyz: spot axis or the direction light travels, w: unused
  vec4 intensity;       // rgb: W/sr (point, spot) or W/m^2 (directional), w: unused
  vec4 cone;            // x: cos(outer), y: cos(inner) (spot); z: shadow bias (world units); w: unused
  vec4 shadow;          // x: first shadow-map layer (-1: none; point lights use 6), y: texel size at
                        // distance 1 (perspective) or in world units (orthographic), z: near, w: far
};

// One material of the scene (gi::Material), for shading from the G-buffer's material index.
NL_STRUCT(MaterialRecord) {
  vec4 baseColor;       // rgb linear, w: type (NL_MATERIAL_*)
  vec4 params;          // roughness, metallic, specular, specular tint
  vec4 params2;         // sheen, sheen tint, clearcoat, clearcoat gloss
  vec4 emission;        // rgb emitted radiance, w: unused
};

// Clipping volumes (nestlight/octree/clip_volume.h) in the frame the shader's positions are in
// (the point view: relative to the eye; the GI frame: the scene's local frame), encoded by
// nestlight/frame/gpu_clip.h and tested by shaders/common/clip_volumes.glsl.
#define NL_MAX_CLIP_VOLUMES 16
#define NL_MAX_CLIP_VERTICES 1024  // every polygon's and corridor's vertices together
#define NL_CLIP_BOX 0
#define NL_CLIP_POLYGON 1
#define NL_CLIP_CORRIDOR 2
NL_STRUCT(ClipVolumeRecord) {
  mat4 boxFromFrame;    // box: frame position -> the box's own coordinates, inside in [-1, 1]^3
  ivec4 shape;          // x: NL_CLIP_*, y: 1 outside (removes what it contains), z: first vertex, w: vertices
  vec4 range;           // x, y: z range kept (polygon, corridor; frame), z: corridor half width, w: unused
};
NL_UNIFORM_BLOCK(NL_UBO_CLIP, ClipBlock) {
  ivec4 clipCounts;     // x: volumes, y: 1 when any volume is an inside one, z, w: unused
  ClipVolumeRecord clipVolumes[NL_MAX_CLIP_VOLUMES];
  vec4 clipVertices[NL_MAX_CLIP_VERTICES / 2];  // plan-view vertices (frame), two per vec4: xy, zw
}
NL_END_BLOCK(clipSet)
