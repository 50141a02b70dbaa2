// The GI frame's G-buffer passes: the meshes', then the scans' splats through
// frame/point_splatting.h (basic splats, high-quality splatting, or the compute rasteriser; the
// papers are cited there) into the same G-buffer, within a guard band around each tile.
#include "nestlight/frame/passes.h"
#include "scene_frame_impl.h"

namespace nestlight::gi::frame_detail {

// The G-buffer alone (the scan pass also writes its own HQS targets, which
// PassContext::bindFramebuffer would attach too).
void RasterMethod::bindGBuffer(const frame::PassContext& ctx) {
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("base_colour"));
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("normal"));
  gbufferFbo_.attach(GL_COLOR_ATTACHMENT2, ctx.target("material"));
  gbufferFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("depth"));
  gbufferFbo_.finish(3, "G-buffer");
  glBindFramebuffer(GL_FRAMEBUFFER, gbufferFbo_.id());
  glViewport(0, 0, ctx.tile().width, ctx.tile().height);
}

// GL drops a point whose centre lies outside the viewport, so splats centred just beyond the
// tile (in the next tile, or beyond the image) would leave their part inside uncovered. Splats
// are drawn into a viewport larger by half the largest splat on every side, with the projection
// narrowed to match: pixels inside the tile map exactly as before. Returns the guarded clip.
glm::mat4 RasterMethod::guardBand(const frame::PassContext& ctx) const {
  const frame::Tile& t = ctx.tile();
  const int g = kGuardPixels;
  glm::mat4 narrow(1.0f);
  narrow[0][0] = float(t.width) / float(t.width + 2 * g);
  narrow[1][1] = float(t.height) / float(t.height + 2 * g);
  glViewport(-g, -g, t.width + 2 * g, t.height + 2 * g);
  return narrow * ctx.uniforms().clipFromWorld;
}

// High-quality splatting's three passes (frame::PointSplatting) for every scan, into the tile's
// G-buffer.
void RasterMethod::hqsScans(const frame::PassContext& ctx) {
  const frame::Tile& tile = ctx.tile();
  const auto& u = ctx.uniforms();
  // The splats' depth starts as the meshes' so that splats behind a mesh take no part.
  glCopyImageSubData(ctx.target("depth").id(), GL_TEXTURE_2D, 0, 0, 0, 0,
                     ctx.target("scan_depth").id(), GL_TEXTURE_2D, 0, 0, 0, 0, tile.width,
                     tile.height, 1);
  hqsDepthFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("scan_depth"));
  hqsDepthFbo_.finish(0, "HQS depth");
  hqsSumFbo_.attach(GL_COLOR_ATTACHMENT0, ctx.target("scan_sum_colour"));
  hqsSumFbo_.attach(GL_COLOR_ATTACHMENT1, ctx.target("scan_sum_normal"));
  hqsSumFbo_.attach(GL_COLOR_ATTACHMENT2, ctx.target("scan_sum_radius"));
  hqsSumFbo_.attach(GL_DEPTH_ATTACHMENT, ctx.target("scan_depth"));
  hqsSumFbo_.finish(3, "HQS sums");
  bindGBuffer(ctx);
  glEnable(GL_PROGRAM_POINT_SIZE);
  glEnable(GL_DEPTH_TEST);
  const glm::mat4 guarded = guardBand(ctx);
  frame::PointSplatting::HqsTargets t;
  t.depthFbo = hqsDepthFbo_.id();
  t.sumFbo = hqsSumFbo_.id();
  t.sums = 3;
  t.sumTextures = {ctx.target("scan_sum_colour").id(), ctx.target("scan_sum_normal").id(),
                   ctx.target("scan_sum_radius").id()};
  t.gbufferFbo = gbufferFbo_.id();
  t.resolveDepthFunc = GL_LESS;  // behind whatever mesh is nearer
  t.width = tile.width, t.height = tile.height;
  splatting_->hqs(t, params_.hqsDepthEpsilon, u.clipFromView,
                  [&](const gl::ShaderProgram& program, bool) {
                    drawScans(program, guarded, u.viewFromWorld, u.eye.w, false);
                  });
}

// The compute rasteriser's three passes (frame::PointSplatting) for every scan, into the tile's
// G-buffer.
void RasterMethod::computeScans(const frame::PassContext& ctx) {
  const frame::Tile& tile = ctx.tile();
  const size_t pixels = size_t(tile.width) * tile.height;
  if (pixels * 16 > gl::kMaxSsboRange)
    throw Error("raster: a " + std::to_string(tile.width) + "x" + std::to_string(tile.height) +
                " tile is too large for the compute rasteriser's per-pixel buffers (128 MiB)");
  const auto& u = ctx.uniforms();
  auto dispatch = [&](const gl::ShaderProgram& prog, bool) {
    prog.use();
    glUniformMatrix4fv(prog.uniform("uClipFromWorld"), 1, GL_FALSE, &u.clipFromWorld[0][0]);
    glUniformMatrix4fv(prog.uniform("uViewFromWorld"), 1, GL_FALSE, &u.viewFromWorld[0][0]);
    glUniform2i(prog.uniform("uViewport"), tile.width, tile.height);
    glUniform1f(prog.uniform("uSizeScale"), params_.splatScale);
    forEachNode(prog, [](const streaming::DrawNode& n) {
      glDispatchCompute((n.numPoints + 127) / 128, 1, 1);
    });
  };
  auto resolveUniforms = [&](const gl::ShaderProgram& r) {
    glUniform2i(r.uniform("uViewport"), tile.width, tile.height);
    glUniformMatrix4fv(r.uniform("uClipFromView"), 1, GL_FALSE, &u.clipFromView[0][0]);
    glUniform1f(r.uniform("uColourScale"), scans_.empty() ? 1.0f : scans_.front().colourScale);
    glUniform1i(r.uniform("uHdrColour"), !scans_.empty() && scans_.front().store->hdrColour());
  };
  bindGBuffer(ctx);
  splatting_->compute(tile.width, tile.height, false, gbufferFbo_.id(), GL_LESS, dispatch,
                      resolveUniforms);
}

// The G-buffer's passes: meshes first (they clear it), then the scans' splats.
void RasterMethod::addGBufferPasses() {
  auto gbufferWrites = [](frame::PassBuilder& b) {
    b.write("depth");
    b.write("base_colour");
    b.write("normal");
    b.write("material");
  };
  auto scanWrites = [gbufferWrites](frame::PassBuilder& b) {
    gbufferWrites(b);
    for (const char* t : {"scan_depth", "scan_sum_colour", "scan_sum_normal", "scan_sum_radius"})
      b.write(t);
  };
  graph_.addPass("gbuffer_meshes", frame::Scope::Tile, gbufferWrites,
                 [this](const frame::PassContext& ctx) {
                   ctx.bindFramebuffer();
                   glEnable(GL_DEPTH_TEST);
                   glDepthFunc(GL_LESS);
                   glDisable(GL_BLEND);
                   glDisable(GL_CULL_FACE);
                   frame::clearGBuffer();
                   drawMeshes(meshGBuffer_, ctx.uniforms().clipFromWorld, true);
                 });
  graph_.addPass("gbuffer_scans", frame::Scope::Tile, scanWrites,
                 [this](const frame::PassContext& ctx) {
                   const auto& u = ctx.uniforms();
                   if (params_.computeRasteriser) {
                     computeScans(ctx);
                     return;
                   }
                   if (params_.hqs) {
                     hqsScans(ctx);
                     return;
                   }
                   bindGBuffer(ctx);
                   glEnable(GL_DEPTH_TEST);
                   glEnable(GL_PROGRAM_POINT_SIZE);
                   drawScans(splatting_->basic(), guardBand(ctx), u.viewFromWorld, u.eye.w, false);
                   glViewport(0, 0, ctx.tile().width, ctx.tile().height);
                 });
}

}  // namespace nestlight::gi::frame_detail
