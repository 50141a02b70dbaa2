// Writing the G-buffer (shaders/interface/frame_interface.glsl): the outputs and their encoding.
#include "../../interface/frame_interface.glsl"
layout(location = NL_GBUFFER_BASE_COLOUR) out vec4 gBaseColour;
layout(location = NL_GBUFFER_NORMAL) out vec4 gNormal;
layout(location = NL_GBUFFER_MATERIAL) out uvec4 gMaterial;

// `normal` (world, unit) or 0 when unknown (a scan without normals).
// `radius`: the splat's radius in world units (scan points; 0 for meshes), for shadow offsets.
void writeGBuffer(vec3 baseColour, float radius, vec3 normal, int type, int source, float roughness, float metallic,
                  uint material) {
  gBaseColour = vec4(baseColour, radius);
  gNormal = vec4(normal, dot(normal, normal) > 0.0 ? 1.0 : 0.0);
  gMaterial = uvec4(uint(type) | (uint(source) << 8), uint(clamp(roughness, 0.0, 1.0) * 65535.0 + 0.5),
                    uint(clamp(metallic, 0.0, 1.0) * 65535.0 + 0.5), material);
}
