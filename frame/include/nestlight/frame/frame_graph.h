// The GI frame: a small frame graph after Filament's (fg/FrameGraph.h). Passes are added in the
// order they run; each declares the targets it reads and writes, and the graph checks the
// declarations (every read has an earlier writer, names are unique, per-frame passes do not read
// per-tile targets), drops passes whose results nobody reads, owns the targets, binds each pass's
// framebuffer, times every pass on the GPU, and renders large images in tiles.
//
// Two scopes, so per-frame work is done once however many tiles an image takes:
// - Frame passes (light views, shadow maps, VPLs, hierarchies) run once per frame and write
//   fixed-size targets;
// - Tile passes (G-buffer, shading, eye-dome lighting, tone mapping) run once per tile and write
//   targets of the tile's size. A pass that reads neighbours declares a margin; tiles overlap by
//   the sum of the live passes' margins (chained neighbourhood passes widen the need), so every
//   tile equals the same pixels of an untiled frame.
//
// The graph owns the frame's uniform block (shaders/interface/frame_interface.glsl): the method
// fills the camera, the graph writes each tile's projection into it and binds it at NL_UBO_FRAME.
#pragma once

#include <epoxy/gl.h>

#include <functional>
#include <glm/glm.hpp>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nestlight/frame/interface.h"
#include "nestlight/gl/resources.h"

namespace nestlight::frame {

enum class Scope { Frame, Tile };
const char* scopeName(Scope s);

struct TargetDesc {
  GLenum format = GL_RGBA16F;
  // Tile targets (fixedSize false) have the size of the largest tile; fixed ones their own.
  bool fixedSize = false;
  int width = 0, height = 0;
  int layers = 0;     // > 0: a 2D array texture of this many layers (shadow maps, atlases)
  bool cube = false;  // a cube map, width x width per face (fixed size)
};

// What one tile of the image is: the region of the full image (GL pixels, y up) this run of the
// tile passes covers, including the margin. Tile targets hold it at their lower-left corner.
struct Tile {
  int fullWidth = 0, fullHeight = 0;
  int x0 = 0, y0 = 0, width = 0, height = 0;
  glm::mat4 clipFromFullClip{1.0f};  // full-image clip space -> this tile's
};

class PassBuilder {
 public:
  void read(const std::string& target) { reads_.push_back(target); }
  void write(const std::string& target) { writes_.push_back(target); }
  // Pixels around each pixel the pass reads from its inputs (tiles overlap by this much).
  void margin(int pixels) { margin_ = pixels; }
  // Keep the pass even when nothing reads what it writes (it has effects outside the graph).
  void sideEffect() { sideEffect_ = true; }

  const std::vector<std::string>& reads() const { return reads_; }
  const std::vector<std::string>& writes() const { return writes_; }

 private:
  friend class FrameGraph;
  std::vector<std::string> reads_, writes_;
  int margin_ = 0;
  bool sideEffect_ = false;
};

class FrameGraph;

class PassContext {
 public:
  // A target the pass declared (reading or writing); anything else is a programming error.
  const gl::Texture& target(const std::string& name) const;
  const Tile& tile() const { return *tile_; }
  // Binds a framebuffer with the pass's written 2D targets attached (a depth-format target as
  // the depth attachment, the others as colour attachments 0, 1, ... in declaration order) and
  // sets the viewport to the tile (or the fixed target's size).
  void bindFramebuffer() const;
  // Binds a read target to a texture unit.
  void bindTexture(const std::string& name, GLuint unit) const;
  const FrameBlock& uniforms() const;

 private:
  friend class FrameGraph;
  const FrameGraph* graph_ = nullptr;
  size_t pass_ = 0;
  const Tile* tile_ = nullptr;
};

struct PassTiming {
  std::string name;
  Scope scope = Scope::Tile;
  double gpuMs = 0;  // GL_TIME_ELAPSED, summed over the frame's tiles
  // With setSyncTiming: wall time between glFinish() before and after the pass, summed over the
  // tiles. A CPU rasteriser (llvmpipe) runs compute dispatches at the next synchronisation, so
  // its timer queries charge them to a later pass; this charges every pass its own work.
  double wallMs = 0;
  int runs = 0;  // 1 for frame passes, the number of tiles for tile passes
};

class FrameGraph {
 public:
  using SetupFn = std::function<void(PassBuilder&)>;
  using RunFn = std::function<void(const PassContext&)>;

  FrameGraph();
  ~FrameGraph();
  FrameGraph(const FrameGraph&) = delete;
  FrameGraph& operator=(const FrameGraph&) = delete;

  void addTarget(const std::string& name, const TargetDesc& desc);
  // A buffer the passes that write it own (VPLs, shadow-map atlases in SSBOs): declared so that
  // passes order and cull by it like a fixed target (any pass writes or reads it: a tile pass that
  // writes one owns what it means per tile);
  // the graph allocates nothing and PassContext::target() refuses it.
  void addBuffer(const std::string& name);
  void addPass(const std::string& name, Scope scope, const SetupFn& setup, RunFn run);
  // Checks the declarations and culls, working back from `output` (a tile target). Throws
  // nestlight::Error naming the pass and the target at fault.
  void compile(const std::string& output);

  // The camera and frame data; the graph fills tile, image and the tile's projection.
  FrameBlock& uniforms() { return uniforms_; }

  // Renders width x height: the frame passes once, then the tile passes for each tile of at most
  // maxTile pixels a side; returns the output's RGBA pixels, rows top first.
  std::vector<float> execute(int width, int height, int maxTile = 4096);
  // One tile of the whole image, no read-back: for the window, which shows the output target.
  void executeToTarget(int width, int height);
  const gl::Texture& target(const std::string& name) const;

  const std::vector<PassTiming>& timings() const { return timings_; }
  void setTiming(bool on) { timing_ = on; }
  void setSyncTiming(bool on) { syncTiming_ = on; }
  bool isCulled(const std::string& pass) const;
  // One line per pass: "name (scope): reads a, b; writes c", culled passes marked.
  std::string describe() const;

 private:
  friend class PassContext;
  struct Pass;
  struct Target;
  void runPasses(Scope scope, const Tile& tile);
  void allocate(int tileWidth, int tileHeight);
  void uploadUniforms(const Tile& tile);

  std::vector<std::unique_ptr<Pass>> passes_;
  std::map<std::string, std::unique_ptr<Target>> targets_;
  std::string output_;
  bool compiled_ = false, timing_ = true, syncTiming_ = false;
  int margin_ = 0;
  FrameBlock uniforms_{};
  glm::mat4 fullClipFromView_{1.0f};
  gl::Buffer ubo_;
  std::vector<PassTiming> timings_;
  int allocW_ = 0, allocH_ = 0;
};

}  // namespace nestlight::frame
