// The resident cut's hierarchies as the gathers read them: the top tree, every node's own
// hierarchy one after another, and where each starts. A reference to a node is (index, tree):
// tree 0 is the top tree, tree k + 1 the hierarchy of the cut's k-th node.
layout(std430, binding = PBGI_SSBO_TOP) readonly buffer Top { BshNode top[]; };
layout(std430, binding = PBGI_SSBO_NODES) readonly buffer Nodes { BshNode nodes[]; };
layout(std430, binding = PBGI_SSBO_TABLE) readonly buffer Table { PbgiNode cutNodes[]; };

// The node, its centre moved to the scene frame and its colour scaled.
BshNode fetchNode(uvec2 e) {
  if (e.y == 0u) return top[e.x];
  PbgiNode cn = cutNodes[e.y - 1u];
  BshNode A = nodes[cn.range.x + e.x];
  A.sphere.xyz += cn.origin.xyz;
  A.colour.rgb *= cn.origin.w;
  return A;
}
