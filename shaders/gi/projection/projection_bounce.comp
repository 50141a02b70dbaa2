// A further bounce's update of S's radiance (Maletz, Wang and Bowers 2011, section 3.1: "the same
// gather at the points of S"): each point's direct light (projection_light.comp's) plus its
// albedo over pi times the irradiance gathered at its bounce receiver (the point of its cluster
// that gathered for it: the nearest one whose normal agrees).
layout(local_size_x = 64) in;
#include "../../interface/frame_interface.glsl"
#include "projection_interface.glsl"
layout(std430, binding = PROJECTION_SSBO_POINTS) readonly buffer Points { ProjectionPoint points[]; };
layout(std430, binding = PROJECTION_SSBO_FILTERED) readonly buffer Direct { vec4 direct[]; };
layout(std430, binding = PROJECTION_SSBO_PIXELS) readonly buffer Gathered { vec4 gathered[]; };
layout(std430, binding = PROJECTION_SSBO_LIST) readonly buffer ReceiverOf { uint receiverOf[]; };
layout(std430, binding = PROJECTION_SSBO_RADIANCE) writeonly buffer Radiance { vec4 radiance[]; };
uniform uint uCount;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uCount) return;
  vec3 albedo = min(points[i].normalColour.yzw, vec3(1.0));
  vec3 E = gathered[2u * receiverOf[i]].rgb;
  radiance[i] = vec4(direct[i].rgb + albedo * 0.318309886183791 * E, 0.0);
}
