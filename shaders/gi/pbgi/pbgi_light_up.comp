// The albedo mode's second step: inner nodes take the count-weighted mean of their children's
// radiance, bottom-up (a hierarchy is stored depth first, so children follow their parent: one
// sweep from the last node to the first), one invocation per hierarchy; the top tree's leaves take
// their node's lit root. Sweeps are resumable (llvmpipe's 65,535-iteration loop limit): at most
// uBudget nodes per dispatch, each hierarchy's cursor kept between dispatches.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
layout(std430, binding = PBGI_SSBO_TABLE) readonly buffer Table { PbgiNode cutNodes[]; };
layout(std430, binding = PBGI_SSBO_LIGHT_IN) readonly buffer Lit { BshNode nodesLit[]; };  // top tree's sweep
layout(std430, binding = PBGI_SSBO_LIGHT_OUT) buffer Out { BshNode tree[]; };
layout(std430, binding = PBGI_SSBO_CURSORS) buffer Cursors { uint cursors[]; };
uniform int uTopTree;   // 1: sweep the top tree (one invocation)
uniform int uTrees;     // hierarchies in the table
uniform int uTopCount;
uniform int uBudget;

void main() {
  uint t = gl_GlobalInvocationID.x;
  uint first = 0u;
  if (uTopTree != 0) {
    if (t > 0u) return;
  } else {
    if (t >= uint(uTrees)) return;
    first = cutNodes[t].range.x;
  }
  uint c = cursors[t];
  for (int step = 0; step < uBudget && c > 0u; ++step) {
    c--;
    BshNode A = tree[first + c];
    if (A.links.x == BSH_LEAF) {
      // The table bound is the gather's: its scale is 1 where the lit copy is in scene units.
      if (uTopTree != 0) tree[c].colour.rgb = nodesLit[cutNodes[A.links.y].range.x].colour.rgb * cutNodes[A.links.y].origin.w;
      continue;
    }
    BshNode l = tree[first + A.links.x], r = tree[first + A.links.y];
    float nl = float(l.links.z), nr = float(r.links.z);
    tree[first + c].colour.rgb = (l.colour.rgb * nl + r.colour.rgb * nr) / max(nl + nr, 1.0);
  }
  cursors[t] = c;
  if (c > 0u) atomicAdd(receivers[1], 1u);
}
