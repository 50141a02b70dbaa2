// Interleaved shading with a geometry-aware filter: Preiner, "Real-Time Global Illumination in
// Point Clouds". Interleaved sampling: Keller and Heidrich 2001, "Interleaved Sampling".
#include "vpl_extension.h"

namespace nestlight::gi::vpl {

// Interleaved shading: each pixel takes the VPLs of its subset of n x n.
void VplExtension::addShadePass(SceneFrame& f) {
  frame::FrameGraph& g = f.graph();
  g.addPass(
      "vpl_shade", frame::Scope::Tile,
      [this](frame::PassBuilder& b) {
        for (const char* t : {"depth", "base_colour", "normal", "material", "vpls"}) b.read(t);
        if (usesIsms()) b.read("ism");
        if (exact()) b.read("vpl_exact");
        b.write("vpl_indirect");
        b.write("vpl_clamp_loss");
      },
      [this, &f](const frame::PassContext& ctx) {
        ctx.bindFramebuffer();
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_BLEND);
        // The ISM-against-exact comparison is a program of its own: NVIDIA's compiler (driver
        // 580) failed inside on that code ("C9999 ... DUI_foreachId"), and the frames users run
        // never take it.
        if (exact() && !shadeExact_.id())
          shadeExact_ = gl::ShaderProgram({{GL_VERTEX_SHADER, "common/fullscreen.vert"},
                                           {GL_FRAGMENT_SHADER, "gi/vpl/vpl_shade.frag"}},
                                          {{"VPL_EXACT_VISIBILITY", "1"}});
        const gl::ShaderProgram& shade = exact() ? shadeExact_ : shade_;
        shade.use();
        bindCommon(f);
        ctx.bindTexture("depth", 0);
        ctx.bindTexture("base_colour", 1);
        ctx.bindTexture("normal", 2);
        ctx.bindTexture("material", 3);
        if (usesIsms()) ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
        if (exact()) {
          exactBits_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_EXACT, 0, exactBits_.bytes());
          agreement_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_AGREEMENT, 0, agreement_.bytes());
        }
        glUniform1i(shade.uniform("uExactWords"), exactWords_);
        glUniform1i(shade.uniform("uVplCount"), params_.count * generationsRun_);
        glUniform1i(shade.uniform("uInterleave"), params_.interleave);
        glUniform1i(shade.uniform("uIsmSize"), params_.ismSize);
        glUniform1f(shade.uniform("uClampDistance"), clampDistance_);
        glUniform1f(shade.uniform("uIsmBias"), params_.ismBias);
        glUniform1i(shade.uniform("uVisibility"), exact() ? 2 : usesIsms() ? 1 : 0);
        glBindVertexArray(emptyVao_.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
      });
}

// The geometry-aware filter over the n x n subsets, and the direct light added.
void VplExtension::addFilterPass(SceneFrame& f) {
  frame::FrameGraph& g = f.graph();
  g.addPass(
      "vpl_filter", frame::Scope::Tile,
      [this](frame::PassBuilder& b) {
        for (const char* t : {"depth", "base_colour", "normal", "material", "vpl_indirect",
                              "vpl_clamp_loss", "radiance"})
          b.read(t);
        b.write("radiance_gi");
        b.margin(params_.interleave / 2 + 1);
      },
      [this, &f](const frame::PassContext& ctx) {
        ctx.bindFramebuffer();
        glDisable(GL_DEPTH_TEST);
        filter_.use();
        f.bindSceneBuffers();
        ctx.bindTexture("depth", 0);
        ctx.bindTexture("base_colour", 1);
        ctx.bindTexture("normal", 2);
        ctx.bindTexture("material", 3);
        ctx.bindTexture("vpl_indirect", 4);
        ctx.bindTexture("vpl_clamp_loss", 5);
        ctx.bindTexture("radiance", 6);
        glUniform1i(filter_.uniform("uInterleave"), params_.interleave);
        glBindVertexArray(emptyVao_.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
      });
}

}  // namespace nestlight::gi::vpl
