// The `diffrender` method's counters and slots as C++ (gi/diffrender) and GLSL share them. Kept
// to the preprocessor subset both read.

// Counters (uint[DR_STAT_COUNT]) at the node-layer slot 3, which no GI pass binds.
#define DR_SSBO_STATS 3

#define DR_STAT_SCAN_PIXELS 0     // dL samples taken on scan pixels (at 1 / delta_scale)
#define DR_STAT_OBJECT_PIXELS 1   // pixels of inserted meshes shaded
#define DR_STAT_RHO_CLAMPED 2     // material estimates clamped at rho_max (or with no light in)
#define DR_STAT_UNCONVERGED 3     // DIT lookups that did not converge (grazing rays)
#define DR_STAT_BOX_HITS 4        // cosine directions that met the objects' box (|H|)
#define DR_STAT_TRACED 5          // of them traced (|H_a|)
#define DR_STAT_OBJECT_FIRST 6    // traced rays that met an object before the scene
#define DR_STAT_SELF_SHADOWED 7   // object rays blocked by the objects' own volume
#define DR_STAT_HIDDEN 8          // DIT rays that start behind the impostor's surface (unseen from its centre)
#define DR_STAT_COMPARED 9          // compare_exact: material rays whose exact trace met the scene
#define DR_STAT_WITHIN_FOOTPRINT 10 // of them, the query's hit within an impostor texel's footprint
#define DR_STAT_COMPARED_SEEN 11   // of the compared, exact hits the impostor holds (its centre sees them)
#define DR_STAT_WITHIN_SEEN 12     // of those, the query's hit within the footprint
#define DR_STAT_COUNT 13

// exact: the captured scene's meshes (inserted false) as a triangle BVH (TriBvhNode[], and
// TriBvhTriangle[] whose v0.w holds the material index's bits); slots 3 and 4 of the methods'.
#define DR_SSBO_MESH_BVH (NL_SSBO_METHOD0 + 3)
#define DR_SSBO_MESH_TRIANGLES (NL_SSBO_METHOD0 + 4)

// Texture units of the passes (4 is the frame's shadow maps, lights.glsl; 5 the environment's,
// environment.glsl).
#define DR_UNIT_IMPOSTOR 6
#define DR_UNIT_OCCUPANCY 7
#define DR_UNIT_SURFACE 8
#define DR_UNIT_DELTA 9
#define DR_UNIT_GUIDE 10
#define DR_UNIT_DIRECT 11          // the frame's direct light (scan pixels: the capture)
#define DR_UNIT_SHADOW_WITHOUT 12  // shadow maps of the lights' views without the inserted meshes
#define DR_UNIT_BACKGROUND 13      // the photograph (`background`)
#define DR_UNIT_SCENE_RADIANCE 14  // vct: the scene volume's radiance (premultiplied) and its mips
#define DR_UNIT_SCENE_OPACITY 15   // vct: its opacity
// vct: the inserted meshes' boundary voxels' light (object_light.comp) for eq. 6's cones. Unit 16:
// GL 4.5 promises 16 units a stage, llvmpipe and NVIDIA's driver give 32.
#define DR_UNIT_OBJECT_LIGHT 16
// vct: the scene volume's directional opacity from level 1 on (scene_opacity_mip.comp).
#define DR_UNIT_SCENE_OPACITY_DIR 17

// Inserted meshes at most: each its own voxel grid, stacked in one texture.
#define DR_VOLUMES_MAX 16

// Queries (DiffrenderParameters::Query).
#define DR_QUERY_EM 0
#define DR_QUERY_DIT 1
#define DR_QUERY_VCT 2
#define DR_QUERY_EXACT 3
