#include "nestlight/frame/frame_graph.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <set>

#include "nestlight/octree/error.h"

namespace nestlight::frame {

const char* scopeName(Scope s) {
  return s == Scope::Frame ? "frame" : "tile";
}

struct FrameGraph::Target {
  TargetDesc desc;
  gl::Texture texture;
  int writer = -1;  // first writing pass
};

struct FrameGraph::Pass {
  std::string name;
  Scope scope = Scope::Tile;
  PassBuilder decl;
  RunFn run;
  bool culled = false;
  gl::Framebuffer fbo;  // its written 2D targets, made on first use
  std::unique_ptr<gl::GpuTimer> timer;
};

namespace {

bool isDepthFormat(GLenum f) {
  return f == GL_DEPTH_COMPONENT32F || f == GL_DEPTH_COMPONENT24 || f == GL_DEPTH_COMPONENT16 ||
         f == GL_DEPTH32F_STENCIL8 || f == GL_DEPTH24_STENCIL8;
}

}  // namespace

const gl::Texture& PassContext::target(const std::string& name) const {
  const auto& p = *graph_->passes_[pass_];
  const bool declared = std::count(p.decl.reads().begin(), p.decl.reads().end(), name) ||
                        std::count(p.decl.writes().begin(), p.decl.writes().end(), name);
  NL_CHECK_MSG(declared, "pass '" + p.name + "' uses target '" + name + "' it did not declare");
  return graph_->target(name);
}

void PassContext::bindFramebuffer() const {
  auto& p = *graph_->passes_[pass_];
  int w = tile_->width, h = tile_->height;
  if (!p.fbo) {
    p.fbo = gl::Framebuffer::create();
    int colour = 0;
    for (const auto& name : p.decl.writes()) {
      const auto& t = *graph_->targets_.at(name);
      if (t.desc.layers > 0 || t.desc.cube) continue;  // attached by the pass itself, per layer
      if (t.desc.format == GL_NONE) continue;          // a buffer the pass owns
      if (isDepthFormat(t.desc.format))
        p.fbo.attach(GL_DEPTH_ATTACHMENT, t.texture);
      else
        p.fbo.attach(GLenum(GL_COLOR_ATTACHMENT0 + colour++), t.texture);
    }
    p.fbo.finish(colour, "pass '" + p.name + "'");
  }
  for (const auto& name : p.decl.writes()) {
    const auto& t = *graph_->targets_.at(name);
    if (t.desc.fixedSize && !t.desc.layers && !t.desc.cube && t.desc.format != GL_NONE)
      w = t.desc.width, h = t.desc.height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, p.fbo.id());
  glViewport(0, 0, w, h);
}

void PassContext::bindTexture(const std::string& name, GLuint unit) const {
  glBindTextureUnit(unit, target(name).id());
}

const FrameBlock& PassContext::uniforms() const {
  return graph_->uniforms_;
}

FrameGraph::FrameGraph() = default;
FrameGraph::~FrameGraph() = default;

void FrameGraph::addTarget(const std::string& name, const TargetDesc& desc) {
  if (targets_.count(name)) throw Error("frame: target '" + name + "' is declared twice");
  if ((desc.fixedSize || desc.cube || desc.layers) &&
      (desc.width <= 0 || (!desc.cube && desc.height <= 0)))
    throw Error("frame: fixed-size target '" + name + "' needs a size");
  auto t = std::make_unique<Target>();
  t->desc = desc;
  if (desc.cube || desc.layers) t->desc.fixedSize = true;
  targets_[name] = std::move(t);
  compiled_ = false;
}

void FrameGraph::addBuffer(const std::string& name) {
  if (targets_.count(name)) throw Error("frame: target '" + name + "' is declared twice");
  auto t = std::make_unique<Target>();
  t->desc.format = GL_NONE;
  t->desc.fixedSize = true;
  targets_[name] = std::move(t);
  compiled_ = false;
}

void FrameGraph::addPass(const std::string& name, Scope scope, const SetupFn& setup, RunFn run) {
  for (const auto& p : passes_)
    if (p->name == name) throw Error("frame: pass '" + name + "' is added twice");
  auto p = std::make_unique<Pass>();
  p->name = name;
  p->scope = scope;
  if (setup) setup(p->decl);
  p->run = std::move(run);
  passes_.push_back(std::move(p));
  compiled_ = false;
}

void FrameGraph::compile(const std::string& output) {
  auto out = targets_.find(output);
  if (out == targets_.end())
    throw Error("frame: the output '" + output + "' is not a declared target");
  if (out->second->desc.fixedSize)
    throw Error("frame: the output '" + output + "' must be a tile target");
  for (auto& [name, t] : targets_) t->writer = -1;
  margin_ = 0;
  for (size_t i = 0; i < passes_.size(); ++i) {
    Pass& p = *passes_[i];
    for (const auto& r : p.decl.reads_) {
      auto t = targets_.find(r);
      if (t == targets_.end())
        throw Error("frame: pass '" + p.name + "' reads '" + r + "', which is not a target");
      if (t->second->writer < 0)
        throw Error("frame: pass '" + p.name + "' reads '" + r + "' before any pass writes it");
      if (p.scope == Scope::Frame && !t->second->desc.fixedSize)
        throw Error("frame: frame pass '" + p.name + "' reads tile target '" + r +
                    "' (frame passes run once, before any tile)");
    }
    for (const auto& w : p.decl.writes_) {
      auto t = targets_.find(w);
      if (t == targets_.end())
        throw Error("frame: pass '" + p.name + "' writes '" + w + "', which is not a target");
      if (p.scope == Scope::Frame && !t->second->desc.fixedSize)
        throw Error("frame: frame pass '" + p.name + "' writes tile target '" + w + "'");
      if (p.scope == Scope::Tile && t->second->desc.fixedSize && t->second->desc.format != GL_NONE)
        throw Error("frame: tile pass '" + p.name + "' writes fixed target '" + w +
                    "' (each tile would overwrite it)");
      if (t->second->writer < 0) t->second->writer = int(i);
    }
  }
  if (targets_[output]->writer < 0)
    throw Error("frame: no pass writes the output '" + output + "'");
  // Cull back from the output: a pass lives when it writes something a live pass (or the output)
  // needs, or has effects outside the graph.
  std::set<std::string> needed{output};
  for (size_t k = passes_.size(); k-- > 0;) {
    Pass& p = *passes_[k];
    p.culled = !p.decl.sideEffect_ &&
               std::none_of(p.decl.writes_.begin(), p.decl.writes_.end(),
                            [&](const std::string& w) { return needed.count(w) > 0; });
    if (!p.culled) {
      needed.insert(p.decl.reads_.begin(), p.decl.reads_.end());
      // Chained neighbourhood passes widen what a tile needs: their margins add up.
      if (p.scope == Scope::Tile) margin_ += p.decl.margin_;
    }
  }
  output_ = output;
  compiled_ = true;
  timings_.clear();
  for (const auto& p : passes_)
    if (!p->culled) timings_.push_back({p->name, p->scope, 0, 0});
}

bool FrameGraph::isCulled(const std::string& pass) const {
  for (const auto& p : passes_)
    if (p->name == pass) return p->culled;
  throw Error("frame: no pass '" + pass + "'");
}

std::string FrameGraph::describe() const {
  std::string s;
  for (const auto& p : passes_) {
    s += p->name + " (" + scopeName(p->scope) + "): reads ";
    for (size_t i = 0; i < p->decl.reads_.size(); ++i) s += (i ? ", " : "") + p->decl.reads_[i];
    if (p->decl.reads_.empty()) s += "-";
    s += "; writes ";
    for (size_t i = 0; i < p->decl.writes_.size(); ++i) s += (i ? ", " : "") + p->decl.writes_[i];
    if (p->culled) s += " [culled]";
    s += "\n";
  }
  return s;
}

const gl::Texture& FrameGraph::target(const std::string& name) const {
  auto t = targets_.find(name);
  NL_CHECK_MSG(t != targets_.end(), "no frame target '" + name + "'");
  return t->second->texture;
}

void FrameGraph::allocate(int tw, int th) {
  for (auto& [name, t] : targets_) {
    const TargetDesc& d = t->desc;
    if (d.format == GL_NONE) continue;  // a buffer: its passes own it
    if (t->texture && (d.fixedSize || (tw == allocW_ && th == allocH_))) continue;
    if (d.cube)
      t->texture = gl::Texture::cubeMap(d.format, d.width);
    else if (d.layers)
      t->texture = gl::Texture::array2d(d.format, d.width, d.height, d.layers);
    else if (d.fixedSize)
      t->texture = gl::Texture(d.format, d.width, d.height);
    else
      t->texture = gl::Texture(d.format, tw, th);
  }
  if (tw != allocW_ || th != allocH_)
    for (auto& p : passes_)
      if (p->scope == Scope::Tile) p->fbo.reset();  // attachments were replaced
  allocW_ = tw, allocH_ = th;
}

void FrameGraph::uploadUniforms(const Tile& tile) {
  uniforms_.clipFromView = tile.clipFromFullClip * fullClipFromView_;
  uniforms_.clipFromWorld = uniforms_.clipFromView * uniforms_.viewFromWorld;
  uniforms_.worldFromClip = glm::inverse(uniforms_.clipFromWorld);
  uniforms_.tile = glm::vec4(tile.x0, tile.y0, tile.width, tile.height);
  uniforms_.image =
      glm::vec4(tile.fullWidth, tile.fullHeight, 1.0f / tile.fullWidth, 1.0f / tile.fullHeight);
  if (!ubo_)
    ubo_ = gl::Buffer(sizeof(FrameBlock));  // here, not in the constructor: a context is current
  ubo_.upload(&uniforms_, sizeof uniforms_);
  ubo_.bindBase(GL_UNIFORM_BUFFER, NL_UBO_FRAME);
}

void FrameGraph::runPasses(Scope scope, const Tile& tile) {
  size_t timingIndex = 0;
  for (size_t i = 0; i < passes_.size(); ++i) {
    Pass& p = *passes_[i];
    if (p.culled) continue;
    PassTiming& timing = timings_[timingIndex++];
    if (p.scope != scope) continue;
    PassContext ctx;
    ctx.graph_ = this;
    ctx.pass_ = i;
    ctx.tile_ = &tile;
    if (syncTiming_) glFinish();
    const auto wall0 = std::chrono::steady_clock::now();
    if (timing_) {
      if (!p.timer) p.timer = std::make_unique<gl::GpuTimer>();
      p.timer->begin();
    }
    p.run(ctx);
    if (timing_) {
      p.timer->end();
      timing.gpuMs += p.timer->milliseconds();
    }
    if (syncTiming_) {
      glFinish();
      timing.wallMs +=
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall0)
              .count();
    }
    ++timing.runs;
  }
}

std::vector<float> FrameGraph::execute(int width, int height, int maxTile) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw Error("frame: image size " + std::to_string(width) + "x" + std::to_string(height) +
                " is out of range");
  if (!compiled_) throw Error("frame: execute() before compile()");
  NL_CHECK(maxTile >= 16);
  for (auto& t : timings_) t.gpuMs = 0, t.wallMs = 0, t.runs = 0;
  fullClipFromView_ = uniforms_.clipFromView;
  const int tile = std::min(maxTile, std::max(width, height));
  const bool single = width <= tile && height <= tile;
  const int m = single ? 0 : margin_;
  const int allocW = std::min(width, tile + 2 * m), allocH = std::min(height, tile + 2 * m);
  allocate(allocW, allocH);
  // Frame passes see the whole image as their "tile" (for the uniforms' image size).
  Tile whole{width, height, 0, 0, width, height, glm::mat4(1.0f)};
  uploadUniforms(whole);
  runPasses(Scope::Frame, whole);
  std::vector<float> image(size_t(width) * height * 4, 0.0f), px;
  for (int ty = 0; ty < height; ty += tile)
    for (int tx = 0; tx < width; tx += tile) {
      const int w = std::min(tile, width - tx), h = std::min(tile, height - ty);
      // GL rows go up, image rows down: the image's row band [ty, ty + h) is GL's [H - ty - h, H -
      // ty).
      const int glY = height - ty - h;
      const int x0 = std::max(0, tx - m), y0 = std::max(0, glY - m);
      const int x1 = std::min(width, tx + w + m), y1 = std::min(height, glY + h + m);
      Tile t{width, height, x0, y0, x1 - x0, y1 - y0, glm::mat4(1.0f)};
      // Clip x in [-1, 1] over the full width -> over [x0, x1): scale W / tw, offset.
      const float sx = float(width) / t.width, sy = float(height) / t.height;
      const float cx = (2.0f * x0 + t.width) / width - 1.0f,
                  cy = (2.0f * y0 + t.height) / height - 1.0f;
      t.clipFromFullClip[0][0] = sx;
      t.clipFromFullClip[1][1] = sy;
      t.clipFromFullClip[3][0] = -cx * sx;
      t.clipFromFullClip[3][1] = -cy * sy;
      uploadUniforms(t);
      runPasses(Scope::Tile, t);
      px.resize(size_t(t.width) * t.height * 4);
      if (px.size() * sizeof(float) > size_t(INT32_MAX))
        throw Error("frame: a tile of " + std::to_string(t.width) + "x" + std::to_string(t.height) +
                    " pixels is too large to read back; use smaller tiles");
      glGetTextureSubImage(target(output_).id(), 0, 0, 0, 0, t.width, t.height, 1, GL_RGBA,
                           GL_FLOAT, GLsizei(px.size() * sizeof(float)), px.data());
      for (int y = 0; y < h; ++y) {
        const int glRow = glY + y;  // full-image GL row
        const int imgRow = height - 1 - glRow;
        const float* src = &px[4 * (size_t(glRow - y0) * t.width + (tx - x0))];
        std::copy(src, src + 4 * size_t(w), &image[4 * (size_t(imgRow) * width + tx)]);
      }
    }
  uniforms_.clipFromView = fullClipFromView_;
  return image;
}

void FrameGraph::executeToTarget(int width, int height) {
  if (!compiled_) throw Error("frame: execute() before compile()");
  for (auto& t : timings_) t.gpuMs = 0, t.wallMs = 0, t.runs = 0;
  fullClipFromView_ = uniforms_.clipFromView;
  allocate(width, height);
  Tile whole{width, height, 0, 0, width, height, glm::mat4(1.0f)};
  uploadUniforms(whole);
  runPasses(Scope::Frame, whole);
  runPasses(Scope::Tile, whole);
  uniforms_.clipFromView = fullClipFromView_;
}

}  // namespace nestlight::frame
