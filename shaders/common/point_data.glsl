// A node's points as the GL node store writes them (viewer/include/nestlight/viewer/gl_node_store.h):
// 5 words per point: position (3 floats, relative to the node's cube origin, world units),
// colour RGBA8, normal as 2 x 16-bit octahedral coordinates (0 when the scan has none).
layout(std430, binding = 0) readonly buffer NodePoints { uint words[]; } node;

uniform vec3 uNodeOffset;      // node origin minus eye, computed in double on the CPU
uniform mat4 uViewFromCamRel;  // rotation only: positions arrive relative to the eye
uniform mat4 uClipFromView;    // projection (times a tile transform for large images)
uniform uint uNumPoints;

// Relative to the node's cube origin.
vec3 pointLocal(uint i) {
  return vec3(uintBitsToFloat(node.words[5u * i]), uintBitsToFloat(node.words[5u * i + 1u]),
              uintBitsToFloat(node.words[5u * i + 2u]));
}
vec3 pointCamRel(uint i) { return uNodeOffset + pointLocal(i); }
uint pointColour(uint i) { return node.words[5u * i + 3u]; }
uint pointNormalWord(uint i) { return node.words[5u * i + 4u]; }

#include "octahedral.glsl"
