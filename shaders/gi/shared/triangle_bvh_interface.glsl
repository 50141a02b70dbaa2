// A triangle BVH's nodes and triangles (gi/shared/triangle_bvh.h builds it) as C++ and GLSL share
// them; include frame_interface.glsl first (NL_STRUCT). Guarded: a shader may reach it twice.
#ifndef NL_TRIANGLE_BVH_INTERFACE
#define NL_TRIANGLE_BVH_INTERFACE

#define TRI_BVH_LEAF 0x80000000u  // TriBvhNode.lo.w bits of a leaf: first triangle | TRI_BVH_LEAF
#define TRI_BVH_STACK 64

// 32 bytes: a binary BVH node.
NL_STRUCT(TriBvhNode) {
  vec4 lo;   // xyz: box minimum; w: float bits of the left child's index (the right follows its
             // sub-tree), or of first triangle | TRI_BVH_LEAF
  vec4 hi;   // xyz: box maximum; w: float bits of the right child's index, or of the leaf's
             // triangle count
};

// 48 bytes: a triangle in the scene (local) frame.
NL_STRUCT(TriBvhTriangle) {
  vec4 v0;   // xyz; w: float bits of the input triangle's index (users may put their own there)
  vec4 e1;   // v1 - v0
  vec4 e2;   // v2 - v0
};

#endif
