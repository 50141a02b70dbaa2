// Exact visibility for the VPLs of Preiner, "Real-Time Global Illumination in Point Clouds": Embree
// rays on the CPU in place of the imperfect shadow maps (Ritschel, Grosch, Kim, Seidel,
// Dachsbacher and Kautz 2008, "Imperfect Shadow Maps for Efficient Computation of Indirect
// Illumination"), which separates the ISMs' error from the VPLs'.
#include <tbb/parallel_for.h>

#include <algorithm>

#include "vpl_extension.h"

namespace nestlight::gi::vpl {

void VplExtension::addExactPass(SceneFrame& f) {
  frame::FrameGraph& g = f.graph();
  g.addBuffer("vpl_exact");
  g.addPass(
      "vpl_exact", frame::Scope::Tile,
      [](frame::PassBuilder& b) {
        for (const char* t : {"depth", "base_colour", "normal", "vpls"}) b.read(t);
        b.write("vpl_exact");
      },
      [this](const frame::PassContext& ctx) { exactVisibility(ctx); });
}

// Embree's visibility for every (pixel, VPL of its subset) pair of the tile, as bits; the
// receiver and the VPL are lifted off their surfaces by their disc radii and 1e-3 of the
// scene's extent.
void VplExtension::exactVisibility(const frame::PassContext& ctx) {
  const frame::Tile& tile = ctx.tile();
  const int w = tile.width, h = tile.height;
  const frame::FrameBlock& u = ctx.uniforms();
  std::vector<float> depth(size_t(w) * h), base(size_t(w) * h * 4), normal(size_t(w) * h * 4);
  glGetTextureSubImage(ctx.target("depth").id(), 0, 0, 0, 0, w, h, 1, GL_DEPTH_COMPONENT, GL_FLOAT,
                       GLsizei(depth.size() * 4), depth.data());
  glGetTextureSubImage(ctx.target("base_colour").id(), 0, 0, 0, 0, w, h, 1, GL_RGBA, GL_FLOAT,
                       GLsizei(base.size() * 4), base.data());
  glGetTextureSubImage(ctx.target("normal").id(), 0, 0, 0, 0, w, h, 1, GL_RGBA, GL_FLOAT,
                       GLsizei(normal.size() * 4), normal.data());
  const int total = params_.count * generationsRun_;
  std::vector<VplRecord> vpls(size_t(std::max(total, 1)));
  if (total > 0)
    glGetNamedBufferSubData(records_.id(), 0, GLsizeiptr(size_t(total) * sizeof(VplRecord)),
                            vpls.data());
  const int N = params_.interleave;
  const int perSubset = (total + N * N - 1) / (N * N);
  exactWords_ = std::max(1, (perSubset + 31) / 32);
  std::vector<uint32_t> bits(size_t(w) * h * size_t(exactWords_), 0xffffffffu);
  const float eps = 1e-3f * exactScene_->extent();
  const glm::vec3 eye(u.eye);
  tbb::parallel_for(0, h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (!(depth[i] < 1.0f)) continue;
      const glm::vec2 ndc = (glm::vec2(x, y) + 0.5f) / glm::vec2(w, h) * 2.0f - 1.0f;
      const glm::vec4 wp = u.worldFromClip * glm::vec4(ndc, depth[i] * 2 - 1, 1);
      const glm::vec3 p = glm::vec3(wp) / wp.w;
      const glm::vec3 wo = glm::normalize(eye - p);
      glm::vec3 n(normal[4 * i], normal[4 * i + 1], normal[4 * i + 2]);
      n = normal[4 * i + 3] > 0 ? glm::normalize(n) : wo;
      if (glm::dot(n, wo) < 0) n = -n;
      const float radius = base[4 * i + 3];
      const glm::ivec2 g = glm::ivec2(int(u.tile.x) + x, int(u.tile.y) + y);
      const int subset = (g.x % N) + N * (g.y % N);
      for (int k = subset, slot = 0; k < total; k += N * N, ++slot) {
        const VplRecord& v = vpls[size_t(k)];
        if (v.flux.x == 0 && v.flux.y == 0 && v.flux.z == 0) continue;
        const glm::vec3 x0(v.position), nv(v.normal);
        const glm::vec3 d = p - x0;
        const float dist = glm::length(d);
        if (!(dist > 0)) continue;
        const glm::vec3 dir = d / dist;
        if (glm::dot(nv, dir) <= 0 || glm::dot(n, dir) >= 0) continue;  // no light either way
        // Both ends lifted off their surfaces along the normals: positions read back from
        // depth buffers sit a little above or below them.
        const glm::vec3 from = x0 + nv * (v.position.w + eps), to = p + n * (radius + eps);
        const glm::vec3 seg = to - from;
        const float len = glm::length(seg);
        if (!(len > 2 * eps)) continue;
        if (exactScene_->occluded(from, seg / len, len - eps))
          bits[i * size_t(exactWords_) + size_t(slot / 32)] &= ~(1u << (slot % 32));
      }
    }
  });
  exactBits_.reserve(bits.size() * 4);
  exactBits_.upload(bits.data(), bits.size() * 4);
}

}  // namespace nestlight::gi::vpl
