// The `ibl` method's buffers as C++ (gi/ibl) writes them and GLSL reads them: macros only, kept to
// the preprocessor subset both share; include frame_interface.glsl first (NL_SSBO_METHOD0). The
// meshes' BVH is gi/shared's (triangle_bvh_interface.glsl).

// Slots (the GI frame's method slots). The scan's hierarchies sit where the pbgi method puts
// them (PBGI_SSBO_TOP, _NODES, _TABLE: NL_SSBO_METHOD0 + 0 to 2), so its node layout is shared.
#define IBL_SSBO_ENV (NL_SSBO_METHOD0 + 3)        // float[]: the environment's sampling table (IBL_ENV_*)
#define IBL_SSBO_BVH (NL_SSBO_METHOD0 + 4)        // TriBvhNode[]: the meshes' triangles' BVH, root first
#define IBL_SSBO_TRIANGLES (NL_SSBO_METHOD0 + 5)  // TriBvhTriangle[]: in the BVH's leaf order
#define IBL_SSBO_STATE_IN (NL_SSBO_METHOD0 + 6)   // uint[]: SMC, the previous frame's per-pixel samples
#define IBL_SSBO_STATE_OUT (NL_SSBO_METHOD0 + 7)  // uint[]: SMC, this frame's
// Counters (uint[IBL_STAT_COUNT]) at the node-layer slot 3, which no GI pass binds.
#define IBL_SSBO_STATS 3

// The environment table: a header of 4 floats, then rows + 1 edges in cos theta (top first),
// rows + 1 marginal CDF values over rows, rows x (columns + 1) conditional CDF values.
#define IBL_ENV_WIDTH 0        // float bits of an int
#define IBL_ENV_HEIGHT 1       // float bits of an int
#define IBL_ENV_POWER 2        // sum over texels of luminance x solid angle (unscaled map)
#define IBL_ENV_BLACK 3        // 1: nothing to sample
#define IBL_ENV_HEADER 4

// Estimators (IblParameters::Estimator).
#define IBL_MIS 0
#define IBL_BIS 1
#define IBL_SMC 2
#define IBL_ENVIRONMENT 3     // environment-map sampling alone (the baseline of the benchmark)
#define IBL_BRDF 4            // BSDF sampling alone

// Counters.
#define IBL_STAT_RECEIVERS 0
#define IBL_STAT_RAYS 1
#define IBL_STAT_REINIT_JUMP 2      // SMC: Z_t / Z_t-1 jumped (the paper's reinitialisation)
#define IBL_STAT_REINIT_NEW 3       // SMC: no previous samples here (first frame, disocclusion, moved)
#define IBL_STAT_RESAMPLED 4        // SMC: effective sample size fell below 2N/3
#define IBL_STAT_MOVES 5            // SMC: Metropolis-Hastings proposals
#define IBL_STAT_ACCEPTED 6         // ... accepted
#define IBL_STAT_REPROJECTED 7      // SMC: pixels that took their samples from the previous frame
#define IBL_STAT_LOOP_LIMIT 8        // pixels whose loops neared llvmpipe's 65,535 iterations per invocation
#define IBL_STAT_COUNT 9

#define IBL_PASS_SAMPLES 64      // MIS and the baselines: samples per pixel and dispatch, at most
#define IBL_PASS_PROPOSALS 1024  // BIS: proposals per pixel and dispatch, at most (half search the map)

