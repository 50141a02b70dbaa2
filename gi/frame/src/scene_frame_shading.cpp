// The GI frame's shading: direct light from the G-buffer (shaders/gi/raster/direct_light.frag:
// every light through its shadow map, with normal-offset lookups and percentage-closer
// filtering, Reeves, Salesin and Cook 1987, "Rendering Antialiased Shadows with Depth Maps";
// the environment's unshadowed light: irradiance on diffuse lobes, the split sum on glossy ones),
// the tone map to the display, and
// the read-back of a still.
#include "nestlight/frame/passes.h"
#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

// Direct light from the G-buffer: every light through its shadow map, and the environment.
void RasterMethod::addDirectLightPass() {
  graph_.addPass(
      "direct_light", frame::Scope::Tile,
      [](frame::PassBuilder& b) {
        for (const char* t : {"depth", "base_colour", "normal", "material", "shadow_maps"})
          b.read(t);
        b.write("radiance");
        b.margin(1);  // pin-hole filling reads the 3 x 3 neighbourhood
      },
      [this](const frame::PassContext& ctx) {
        ctx.bindFramebuffer();
        glDisable(GL_DEPTH_TEST);
        directLight_.use();
        ctx.bindTexture("depth", 0);
        ctx.bindTexture("base_colour", 1);
        ctx.bindTexture("normal", 2);
        ctx.bindTexture("material", 3);
        const gl::Texture& maps = ctx.target("shadow_maps");
        maps.setFilter(GL_LINEAR, GL_LINEAR);
        maps.setDepthCompare(true);
        glBindTextureUnit(4, maps.id());
        bindEnvironment(directLight_);
        glUniform1i(directLight_.uniform("uSkyInDirectLight"), skyInDirectLight_ ? 1 : 0);
        bindEnvironmentSpecular(directLight_);
        lightsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_LIGHTS);
        shadowViewsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_SHADOW_VIEWS);
        materialsBuffer_.bindBase(GL_SHADER_STORAGE_BUFFER, NL_SSBO_MATERIALS);
        glBindVertexArray(emptyVao_.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
      });
}

// The tone map from what the frame reads back (direct light, or the extension's target) to the
// display.
void RasterMethod::addToneMapPass() {
  frame::addToneMapPass(graph_, radianceTarget_, "display", exposure_);
}

// The read-back target's pixels (RGBA) as an image (RGB).
HdrImage RasterMethod::imageOf(const std::vector<float>& rgba, int W, int H) {
  HdrImage image(W, H);
  for (size_t p = 0; p < size_t(W) * H; ++p)
    for (int k = 0; k < 3; ++k) image.rgb[3 * p + k] = rgba[4 * p + k];
  return image;
}

}  // namespace nestlight::gi::frame_detail
