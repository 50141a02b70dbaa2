// One frame of the resident cut: points into a G-buffer (colour, view-space normal, depth) by
// either rasteriser, then eye-dome lighting into the output. The GI passes of later issues read
// the same G-buffer and the same draw list.
#pragma once

#include <epoxy/gl.h>

#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "nestlight/streaming/streamer.h"
#include "nestlight/viewer/camera.h"
#include "nestlight/viewer/gl_node_store.h"
#include "nestlight/viewer/image.h"
#include "nestlight/viewer/shader_library.h"

namespace nestlight::viewer {

enum class Rasteriser { Points, Compute };
const char* rasteriserName(Rasteriser r);
Rasteriser parseRasteriser(const std::string& name);  // "points" or "compute"

struct RenderSettings {
  Rasteriser rasteriser = Rasteriser::Points;
  float sizeScale = 1.5f;        // GL_POINTS splat diameter in node spacings
  float minPointSize = 1.0f;
  float maxPointSize = 16.0f;
  float fixedPointSize = 0.0f;   // > 0: every splat this many pixels (the compute path draws 1)
  bool roundPoints = true;
  float edlStrength = 1.0f;      // 0 disables eye-dome lighting
  float edlRadius = 1.4f;
  glm::vec3 background{0.08f, 0.08f, 0.10f};
  int maxTile = 2048;            // larger images render in tiles (SSBO and FBO limits)
  bool allowAtomic64 = true;     // compute path: one 64-bit pass where the GPU has 64-bit atomics
};

struct DrawTimings {
  double msDraw = 0;     // CPU-side wall time of the frame's GL work, finished (glFinish)
  uint64_t points = 0;   // points submitted
};

class FrameRenderer {
 public:
  FrameRenderer();
  ~FrameRenderer();
  FrameRenderer(const FrameRenderer&) = delete;
  FrameRenderer& operator=(const FrameRenderer&) = delete;

  // Renders width x height (tiled when larger than settings.maxTile) and reads it back.
  Image render(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store, const Camera& camera,
               int width, int height, const RenderSettings& settings, DrawTimings* timings = nullptr);

  // Renders into the output texture (no read-back, no tiling): for the window.
  GLuint renderToTexture(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
                         const Camera& camera, int width, int height, const RenderSettings& settings,
                         DrawTimings* timings = nullptr);
  GLuint outputFramebuffer() const { return outputFbo_; }
  // "one-pass 64-bit" where GL_NV_shader_atomic_int64 compiled, else "two-pass 32-bit".
  const char* computeVariant() const { return atomic64_ ? "one-pass 64-bit" : "two-pass 32-bit"; }

 private:
  struct Targets;
  void ensureTargets(int w, int h, bool compute);
  void drawTile(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store, const Camera& camera,
                int fullW, int fullH, int x0, int y0, int w, int h, const RenderSettings& s, DrawTimings* t);

  ShaderProgram points_, depthPass_, colourPass_, resolve_, edl_;
  std::unique_ptr<ShaderProgram> atomic64_, resolve64_;  // only with 64-bit atomics
  GLuint packedSsbo_ = 0;
  GLuint vao_ = 0;
  GLuint gbuffer_ = 0, outputFbo_ = 0;
  GLuint colourTex_ = 0, normalTex_ = 0, depthTex_ = 0, outputTex_ = 0;
  GLuint depthSsbo_ = 0, accumSsbo_ = 0, normalSsbo_ = 0;
  int w_ = 0, h_ = 0;
  size_t ssboPixels_ = 0;
};

}  // namespace nestlight::viewer
