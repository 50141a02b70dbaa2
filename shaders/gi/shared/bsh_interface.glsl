// The bounding-sphere hierarchy (gi/shared: pbgi gathers over it, ibl traces rays through it) as
// C++ writes it and GLSL reads it. Kept to the preprocessor subset both share; include
// frame_interface.glsl first (NL_STRUCT).
//
// One hierarchy per resident octree node, uploaded as the node's layer: an array of BshNode in
// depth-first order, the root at index 0, positions in the node's frame (metres from the node
// cube's minimum corner, as the node's points). A node's left child is the next node; `right`
// says where its right child starts. Depth is at most BSH_MAX_DEPTH (Morton codes of 63 bits
// give every split a longer common prefix), so a fixed traversal stack suffices.

#define BSH_LEAF 0xffffffffu       // BshNode.links.x of a leaf
#define BSH_MAX_DEPTH 64           // levels below the root, at most
#define BSH_CONE_NONE 3.14159265   // half aperture of a node whose normals bound nothing (pi)

// 48 bytes (the paper's 40, with float colour: HDR beyond half-float range survives).
NL_STRUCT(BshNode) {
  vec4 sphere;   // xyz centre, w radius: contains every point's disc below it
  vec4 colour;   // rgb mean linear colour of the points below (scan units), w: the normal cone's
                 // half aperture in radians (0: one direction; BSH_CONE_NONE: no bound)
  uvec4 links;   // x: left child index or BSH_LEAF, y: right child index (a leaf: its disc's radius
                 // as float bits; a top tree's leaf: the node it enters), z: points it stands for,
                 // w: the cone's axis, octahedral 2 x 16 bits (0: none)
};

// The gather's buffers (the GI frame's method slots).
#define PBGI_SSBO_TOP (NL_SSBO_METHOD0 + 0)     // BshNode[]: the top tree over the cut's nodes (scene frame)
#define PBGI_SSBO_NODES (NL_SSBO_METHOD0 + 1)   // BshNode[]: every included node's hierarchy, one after another
#define PBGI_SSBO_TABLE (NL_SSBO_METHOD0 + 2)   // PbgiNode[]: where each one starts, its frame and colour scale
#define PBGI_SSBO_MICRO (NL_SSBO_METHOD0 + 3)   // vec4[M x M]: m-pixel mean directions and solid angles
#define PBGI_SSBO_STATE (NL_SSBO_METHOD0 + 4)   // PbgiTraversal[]: each receiver's traversal in progress
#define PBGI_SSBO_STACK (NL_SSBO_METHOD0 + 5)   // uvec2[PBGI_STACK]: each receiver's traversal stack
#define PBGI_SSBO_MB (NL_SSBO_METHOD0 + 6)      // vec4[M x M]: each receiver's micro-buffer (rgb, distance)
#define PBGI_SSBO_RECEIVERS (NL_SSBO_METHOD0 + 7) // uint[]: [0] receivers, [1] unfinished, [2] spare, [3]
                                                // spare, then each receiver's pixel (x | y << 16)
// MIP-PBGI and X-PBGI (pbgi_pyramid.comp, pbgi_pairs.comp) reuse the slots the classic pass
// binds for its traversal, and the classic pass reads their per-receiver lists at the node-layer
// slots, which no GI pass binds.
#define PBGI_SSBO_PYRAMID (NL_SSBO_METHOD0 + 4) // vec4[2 per texel]: receiver blocks (sphere, normal cone) of every level
#define PBGI_SSBO_PAIRS_IN (NL_SSBO_METHOD0 + 5)  // uvec4[]: (node index, tree, texel, 0) pairs to refine
#define PBGI_SSBO_PAIRS_OUT (NL_SSBO_METHOD0 + 6) // uvec4[]: the pairs they refine into
#define PBGI_SSBO_LIGHT_IN (NL_SSBO_METHOD0 + 4)  // BshNode[]: the albedo mode's lighting pass: nodes in...
#define PBGI_SSBO_LIGHT_OUT (NL_SSBO_METHOD0 + 5) // ...and the same nodes with their radiance as colour
#define PBGI_SSBO_CURSORS (NL_SSBO_METHOD0 + 6)   // uint[]: the bottom-up sweep's cursor per hierarchy
#define PBGI_SSBO_LIST_HEAD NL_SSBO_NODE_LAYER1    // uint[tile pixels]: each receiver's first list entry
#define PBGI_SSBO_LIST NL_SSBO_NODE_LAYER2         // uvec4[]: (node index, tree, next entry, 0)
#define PBGI_SSBO_BOUNCE 3                         // vec4[] per hierarchy node: the albedo mode's gathered bounce
                                                // (rgb: irradiance / pi at the node's receiver, w: 1 where set);
                                                // node-layer slot 3, which no GI pass binds
#define PBGI_LIFTS 16                              // materials with a receiver lift of their own (pbgi_common.glsl)
#define PBGI_LIFT_BOXES 32                         // meshes whose receivers take their own lift (pbgi_common.glsl)
#define PBGI_END 0xffffffffu                       // the end of a receiver's list
#define PBGI_STACK (2 * BSH_MAX_DEPTH + 8)      // a top tree and a node's tree, each at most BSH_MAX_DEPTH deep
#define PBGI_DONE 0xffffffffu                   // PbgiTraversal.header.x of a finished receiver

// A node of the cut as the gather enters it from a top-tree leaf.
NL_STRUCT(PbgiNode) {
  vec4 origin;   // xyz: the node cube's corner in the scene frame (its hierarchy's frame), w: colour scale
  uvec4 range;   // x: index of its root in PBGI_SSBO_NODES, y: its node count, z: 0 for a scan
                 // node, a mesh's material + 1; w: its leaves' disc radius (float bits)
};

// A receiver's traversal between dispatches: its stack depth and the splat in progress (a node
// larger than an m-pixel is rasterised one m-pixel per step).
NL_STRUCT(PbgiTraversal) {
  uvec4 header;  // x: stack depth (PBGI_DONE: finished), y: splat in progress (0/1), z: its cursor, w: hit (0/1)
  vec4 sphere;   // the splat's node: centre (scene frame), radius
  vec4 colour;   // rgb, w: 1 for a leaf (its disc), 0 for an inner node (its silhouette)
  vec4 normal;   // xyz: the node's plane normal, w: a leaf's disc radius
  ivec4 box;     // m-pixel box: lo.x, lo.y, hi.x, hi.y
  uvec4 list;    // x: the next entry of the receiver's list of sub-trees (PBGI_END: none left)
};
