// Pull-push of the imperfect shadow maps: Ritschel, Grosch, Kim, Seidel, Dachsbacher and Kautz
// 2008, "Imperfect Shadow Maps for Efficient Computation of Indirect Illumination", as Preiner,
// "Real-Time Global Illumination in Point Clouds", runs it on the ISM atlas.
#include <algorithm>

#include "vpl_extension.h"

namespace nestlight::gi::vpl {

// Pull-push: the ISMs' holes filled from their coarser levels.
void VplExtension::addPullPushPass(SceneFrame& f) {
  frame::FrameGraph& g = f.graph();
  g.addPass(
      "pull_push", frame::Scope::Frame,
      [](frame::PassBuilder& b) {
        b.read("ism_raw");
        b.write("ism");
      },
      [this](const frame::PassContext&) {
        const int S = params_.ismSize;
        const int levels = std::min(params_.pullPushLevels, log2Exact(S));
        if (levels == 0 || generationsRun_ == 0) return;
        ism_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM, 0, ism_.bytes());
        ismLevels_.bindRange(GL_SHADER_STORAGE_BUFFER, VPL_SSBO_ISM_PYRAMID, 0, ismLevels_.bytes());
        const GLuint isms = GLuint(params_.count * generationsRun_);
        auto run = [&](const gl::ShaderProgram& p, int level) {
          p.use();
          glUniform1i(p.uniform("uIsmSize"), S);
          glUniform1i(p.uniform("uLevel"), level);
          glUniform1i(p.uniform("uFirstVpl"), 0);
          const GLuint n = GLuint(((S >> level) + 7) / 8);
          glDispatchCompute(n, n, isms);
          glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        };
        for (int l = 1; l <= levels; ++l) run(pull_, l);
        for (int l = levels - 1; l >= 0; --l) run(push_, l);
      });
}

}  // namespace nestlight::gi::vpl
