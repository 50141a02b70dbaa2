// Splat sizes from the data (the adaptive point size of Potree: Schütz, "Potree: Rendering Large
// Point Clouds in Web Browsers", 2016, section 4.4), with the spacing measured by the builder.
//
// In a nested octree a location is drawn by the points of every drawn node that contains it:
// the root's sparse sample, then each level's share down to the finest drawn node. Together they
// are as dense as that finest node's measured spacing says (the builder measures it on exactly
// this union), so every point is sized by the finest drawn node at its position, whichever level
// it belongs to. Sizing a root point by the root's own spacing would draw it several times wider
// than the points around it, the "pile of coins" look.
//
// The draw tree (one entry per drawn node, written by the frame renderer each frame): the index
// of the drawn child in each octant (-1: none) and the node's measured point spacing.
struct DrawTreeNode {
  int child[8];
  float spacing;  // world units
  float pad0, pad1, pad2;
};
layout(std430, binding = NL_SSBO_DRAW_TREE) readonly buffer DrawTree { DrawTreeNode nodes[]; } drawTree;

uniform int uNodeIndex;   // this node's entry in the draw tree
uniform float uNodeSize;  // its cube's edge, world units

// `local`: the point relative to the node's cube origin. Children split the cube at its middle,
// child index (x >= half) * 4 + (y >= half) * 2 + (z >= half), as the octree format numbers them.
float finestSpacing(vec3 local) {
  int idx = uNodeIndex;
  float size = uNodeSize;
  for (int level = 0; level < 32; ++level) {
    float halfSize = 0.5 * size;
    bvec3 upper = greaterThanEqual(local, vec3(halfSize));
    int octant = (upper.x ? 4 : 0) | (upper.y ? 2 : 0) | (upper.z ? 1 : 0);
    int c = drawTree.nodes[idx].child[octant];
    if (c < 0) break;
    local -= vec3(upper) * halfSize;
    size = halfSize;
    idx = c;
  }
  return drawTree.nodes[idx].spacing;
}
