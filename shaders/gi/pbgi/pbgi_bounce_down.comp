// The albedo mode's further bounces, after a gather at the receiver nodes (pbgi_bounce_select.comp,
// pbgi_classic.comp with uNodeReceivers): each receiver's gathered irradiance / pi passes down to
// every node below it (a hierarchy is stored depth first: one forward sweep, parents before
// children), and every leaf's radiance becomes its direct light plus its albedo times that. Inner
// nodes then take their children's mean again (pbgi_light_up.comp). One invocation per hierarchy,
// resumable (llvmpipe's loop limit): at most uBudget nodes per dispatch.
layout(local_size_x = 64) in;
#include "pbgi_common.glsl"
layout(std430, binding = PBGI_SSBO_TABLE) readonly buffer Table { PbgiNode cutNodes[]; };  // colour scales
layout(std430, binding = PBGI_SSBO_LIGHT_IN) readonly buffer Albedo { BshNode albedoNodes[]; };
layout(std430, binding = PBGI_SSBO_NODES) readonly buffer Direct { BshNode direct[]; };
layout(std430, binding = PBGI_SSBO_LIGHT_OUT) buffer Out { BshNode lit[]; };
layout(std430, binding = PBGI_SSBO_CURSORS) buffer Cursors { uint cursors[]; };
layout(std430, binding = PBGI_SSBO_BOUNCE) buffer Bounce { vec4 gathered[]; };
uniform int uTrees;
uniform int uBudget;

void main() {
  uint t = gl_GlobalInvocationID.x;
  if (t >= uint(uTrees)) return;
  PbgiNode cn = cutNodes[t];
  uint first = cn.range.x;
  bool mesh = cn.range.z > 0u;
  uint c = cursors[t];  // counts up to the tree's size
  for (int step = 0; step < uBudget && c < cn.range.y; ++step, ++c) {
    uint g = first + c;
    BshNode A = albedoNodes[g];
    vec4 v = gathered[g];
    if (A.links.x != BSH_LEAF) {
      if (v.w > 0.0) {
        if (gathered[first + A.links.x].w == 0.0) gathered[first + A.links.x] = v;
        if (gathered[first + A.links.y].w == 0.0) gathered[first + A.links.y] = v;
      }
      continue;
    }
    // As pbgi_light.comp: a scan point's colour is its albedo, clamped to 1; a mesh surfel's is its
    // material's directional albedo.
    vec3 albedo = mesh ? A.colour.rgb : min(A.colour.rgb * cn.origin.w, vec3(1.0));
    lit[g].colour.rgb = direct[g].colour.rgb + albedo * v.rgb;
  }
  cursors[t] = c;
  if (c < cn.range.y) atomicAdd(receivers[1], 1u);
}
