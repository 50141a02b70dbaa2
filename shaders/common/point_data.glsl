// A node's points as the GL node store writes them (nestlight/frame/gl_node_store.h), in the
// layout shaders/interface/frame_interface.glsl declares: NL_POINT_WORDS words per point.
#include "../interface/frame_interface.glsl"
layout(std430, binding = NL_SSBO_NODE_POINTS) readonly buffer NodePoints { uint words[]; } node;

uniform vec3 uNodeOffset;      // node origin minus eye, computed in double on the CPU
uniform mat4 uViewFromCamRel;  // rotation only: positions arrive relative to the eye
uniform mat4 uClipFromView;    // projection (times a tile transform for large images)
uniform uint uNumPoints;

// Relative to the node's cube origin.
vec3 pointLocal(uint i) {
  return vec3(uintBitsToFloat(node.words[NL_POINT_WORDS * i]), uintBitsToFloat(node.words[NL_POINT_WORDS * i + 1u]),
              uintBitsToFloat(node.words[NL_POINT_WORDS * i + 2u]));
}
vec3 pointCamRel(uint i) { return uNodeOffset + pointLocal(i); }
uint pointColour(uint i) { return node.words[NL_POINT_WORDS * i + 3u]; }
uint pointNormalWord(uint i) { return node.words[NL_POINT_WORDS * i + 4u]; }

#include "colour_word.glsl"
// Linear colour: the recorded colour decoded, or the store's colour layer.
vec3 pointLinearColour(uint i) { return colourWordLinear(pointColour(i)); }

#include "octahedral.glsl"
