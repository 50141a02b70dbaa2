#include "nestlight/frame/passes.h"

#include <cmath>

#include "nestlight/gl/program.h"

namespace nestlight::frame {

void addToneMapPass(FrameGraph& graph, const std::string& input, const std::string& output,
                    std::shared_ptr<const float> exposureStops, const std::string& name) {
  auto program = std::make_shared<gl::ShaderProgram>(std::vector<gl::ShaderProgram::Stage>{
      {GL_VERTEX_SHADER, "common/fullscreen.vert"}, {GL_FRAGMENT_SHADER, "frame/tone_map.frag"}});
  auto vao = std::make_shared<gl::VertexArray>(gl::VertexArray::create());
  graph.addPass(
      name, Scope::Tile,
      [&](PassBuilder& b) {
        b.read(input);
        b.write(output);
      },
      [=](const PassContext& ctx) {
        ctx.bindFramebuffer();
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_BLEND);
        program->use();
        glUniform1f(program->uniform("uScale"), float(std::exp2(double(*exposureStops))));
        ctx.bindTexture(input, 0);
        glBindVertexArray(vao->id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
      });
}

void clearGBuffer() {
  const float zero[4] = {0, 0, 0, 0}, one = 1.0f;
  const GLuint noMaterial[4] = {0, 0, 0, NL_NO_MATERIAL};
  glClearBufferfv(GL_DEPTH, 0, &one);
  glClearBufferfv(GL_COLOR, NL_GBUFFER_BASE_COLOUR, zero);
  glClearBufferfv(GL_COLOR, NL_GBUFFER_NORMAL, zero);
  glClearBufferuiv(GL_COLOR, NL_GBUFFER_MATERIAL, noMaterial);
}

}  // namespace nestlight::frame
