// The point view: the resident cut drawn through the GI frame's graph
// (nestlight/frame/frame_graph.h) as two tile passes: "points" (either rasteriser into a linear
// G-buffer: colour, view-space normal, depth) and "eye_dome_lighting" (with a margin so tiles see
// their neighbours; it encodes for display itself, the point view's tone map being an exposure and
// the sRGB curve, or writes linear values for HDR files). The graph renders large images in tiles
// and owns the targets. The viewer's window and headless driver (`nestlight render`) draw with
// it; `bench render` measures its rasterisers.
#pragma once

#include <epoxy/gl.h>

#include <glm/glm.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nestlight/frame/camera.h"
#include "nestlight/frame/draw_tree.h"
#include "nestlight/frame/frame_graph.h"
#include "nestlight/frame/gl_node_store.h"
#include "nestlight/frame/gpu_clip.h"
#include "nestlight/frame/image.h"
#include "nestlight/frame/picking.h"
#include "nestlight/frame/point_splatting.h"
#include "nestlight/gl/program.h"
#include "nestlight/streaming/streamer.h"

namespace nestlight::frame {

enum class Rasteriser { Points, Compute };
const char* rasteriserName(Rasteriser r);
Rasteriser parseRasteriser(const std::string& name);  // "points" or "compute"

// How the GL_POINTS rasteriser resolves overlapping splats. Basic: the nearest splat wins each
// pixel (one pass). Hqs: high-quality splatting (Botsch et al. 2005, as Potree's HQS): a depth
// pass, a weighted blend of the splats within epsilon of the front surface, a normalisation;
// smooth colour and depth across splats, at about twice the cost. The compute rasteriser draws
// one pixel per point and always averages the points within 1% of the nearest depth (its
// two-pass variant), which is the same idea at one pixel, so the setting does not apply there.
enum class Splatting { Basic, Hqs };
const char* splattingName(Splatting s);
Splatting parseSplatting(const std::string& name);  // "basic" or "hqs"

struct RenderSettings {
  Rasteriser rasteriser = Rasteriser::Points;
  Splatting splatting = Splatting::Hqs;
  // GL_POINTS splat diameter in measured point spacings of the finest drawn node at the point
  // (see shaders/points/splat_size.glsl and docs/VIEWER.md for how the default was chosen).
  float sizeScale = kDefaultSizeScale;
  static constexpr float kDefaultSizeScale = 2.25f;
  float hqsDepthEpsilon = 1.0f;  // HQS: blend splats within this many splat radii of the front
  float minPointSize =
      2.0f;  // pixels: below 2 a round splat covers fewer pixels than a spacing (holes)
  float maxPointSize =
      64.0f;  // pixels: close to a sparse scan splats grow this far before holes open
  float fixedPointSize = 0.0f;  // > 0: every splat this many pixels (the compute path draws 1)
  bool roundPoints = true;
  float edlStrength = 1.0f;  // 0 disables eye-dome lighting
  float edlRadius = 1.4f;    // pixels, at most kMaxEdlRadius (tiles overlap by that much)
  static constexpr float kMaxEdlRadius = 6.0f;
  glm::vec3 background{0.08f, 0.08f, 0.10f};  // display-referred
  // The colour times 2^exposureStops before display (an HDR colour layer's highlights lie above 1).
  float exposureStops = 0.0f;
  // The output holds linear colour (times the exposure and the eye-dome shading) instead of the
  // sRGB-encoded display value: for EXR files of an HDR colour layer. Background in linear too.
  bool linearOutput = false;
  int maxTile = 2048;         // larger images render in tiles (SSBO and FBO limits)
  bool allowAtomic64 = true;  // compute path: one 64-bit pass where the GPU has 64-bit atomics
  // Clipping volumes (world coordinates): hidden on the GPU in every rasteriser; null or empty:
  // none. Shared, not copied, as settings travel by value every frame.
  std::shared_ptr<const ClipSet> clip;
};

// What picking needs of the settings a frame was drawn with (its splats' sizing and clipping),
// with a search window `windowRadius` pixels each side of the cursor.
inline PickOptions pickOptions(const RenderSettings& s, int windowRadius) {
  PickOptions po;
  po.windowRadius = windowRadius;
  po.sizeScale = s.sizeScale, po.minPointSize = s.minPointSize;
  po.maxPointSize = s.maxPointSize, po.fixedPointSize = s.fixedPointSize;
  po.clip = s.clip.get();
  return po;
}

struct DrawTimings {
  double msDraw = 0;    // CPU-side wall time of the frame's GL work, finished (glFinish)
  uint64_t points = 0;  // points submitted
};

class PointView {
 public:
  PointView();
  ~PointView();
  PointView(const PointView&) = delete;
  PointView& operator=(const PointView&) = delete;

  // Renders width x height (tiled when larger than settings.maxTile) and reads it back.
  Image render(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
               const Camera& camera, int width, int height, const RenderSettings& settings,
               DrawTimings* timings = nullptr);

  // Renders into the output texture (no read-back, no tiling): for the window.
  GLuint renderToTexture(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
                         const Camera& camera, int width, int height,
                         const RenderSettings& settings, DrawTimings* timings = nullptr);
  // A framebuffer with the output texture attached (the window blits from it).
  GLuint outputFramebuffer();
  // The depths drawn (world units along the view) within `radius` pixels of pixel (x, y)
  // (top-left origin) of the last frame, read back from its depth buffer; none when the window
  // shows only background. The last frame must have been one tile (renderToTexture, or render()
  // of an image no larger than settings.maxTile): throws otherwise. Picking starts here.
  std::optional<DepthWindow> depthWindow(double x, double y, int radius);
  // "one-pass 64-bit" where GL_NV_shader_atomic_int64 compiled, else "two-pass 32-bit".
  const char* computeVariant() const {
    return splatting_.hasAtomic64() ? "one-pass 64-bit" : "two-pass 32-bit";
  }

 private:
  struct TileView;
  // The "points" pass: every node of nodes_ into the tile's G-buffer with settings_.
  void rasterise(const PassContext& ctx);
  void splatPoints(const PassContext& ctx, const TileView& view);
  void computePoints(const TileView& view);
  glm::vec3 nodeOffset(const streaming::DrawNode& n) const;
  void begin(const std::vector<streaming::DrawNode>& nodes, const GlNodeStore& store,
             const Camera& camera, const RenderSettings& settings, DrawTimings* timings);

  PointSplatting splatting_;  // the splatting passes, shared with the GI frame
  gl::ShaderProgram edl_;
  FrameGraph graph_;
  gl::VertexArray vao_;
  gl::Framebuffer gbufferFbo_, hqsFbo_,
      outputFbo_;      // attachments set from the graph's targets per run
  DrawTree drawTree_;  // the vertex shader's finest-node lookup (splat_size.glsl)
  // What the passes draw this frame (set by render()/renderToTexture() before the graph runs).
  const std::vector<streaming::DrawNode>* nodes_ = nullptr;
  const GlNodeStore* store_ = nullptr;
  Camera camera_;
  RenderSettings settings_;
  DrawTimings* timings_ = nullptr;
  // With clipping volumes: the nodes they keep (nodes_ points here) and, per node, whether its
  // points are tested (1) or its cube is kept whole (0).
  std::vector<streaming::DrawNode> clippedNodes_;
  std::vector<int> clipTest_;
  GpuClip clip_;
  int lastWidth_ = 0, lastHeight_ = 0;  // the last frame, when it was one tile (frontDepth)
};

}  // namespace nestlight::frame
