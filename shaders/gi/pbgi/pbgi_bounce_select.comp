// The albedo mode's further bounces gather at hierarchy nodes rather than at every point: the
// receivers are the highest nodes standing for at most uPoints points (or leaves, whichever comes
// first): every node whose parent stands for more, and a root that stands for no more. Each leaf
// then lies below exactly one receiver. Appends (tree, node) pairs to the receivers' list, one
// invocation per hierarchy node.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
layout(std430, binding = PBGI_SSBO_TABLE) readonly buffer Table { PbgiNode cutNodes[]; };
layout(std430, binding = PBGI_SSBO_NODES) readonly buffer Nodes { BshNode nodes[]; };
uniform uint uPoints;

void emit(uint tree, uint node) {
  uint i = atomicAdd(receivers[0], 1u);
  receivers[4u + 2u * i] = tree;
  receivers[5u + 2u * i] = node;
}

bool small(BshNode A) { return A.links.x == BSH_LEAF || A.links.z <= uPoints; }

void main() {
  uint t = gl_WorkGroupID.y;
  PbgiNode cn = cutNodes[t];
  uint i = gl_GlobalInvocationID.x;
  if (i >= cn.range.y) return;
  BshNode A = nodes[cn.range.x + i];
  if (i == 0u && small(A)) emit(t + 1u, 0u);
  if (small(A)) return;
  if (small(nodes[cn.range.x + A.links.x])) emit(t + 1u, A.links.x);
  if (small(nodes[cn.range.x + A.links.y])) emit(t + 1u, A.links.y);
}
