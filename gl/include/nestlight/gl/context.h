// OpenGL 4.5 core contexts: headless through EGL (the device platform, which finds NVIDIA GPUs,
// then Mesa's surfaceless platform, which runs llvmpipe on the CPU), or a GLFW window.
// Nothing renders to a default framebuffer: every pass draws into an FBO, so headless and
// windowed frames are the same code.
#pragma once

#include <memory>
#include <string>

struct GLFWwindow;

namespace nestlight::gl {

class GlContext {
 public:
  virtual ~GlContext() = default;
  virtual void makeCurrent() = 0;
  // "EGL surfaceless: 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& description() const { return description_; }
  bool hasInt64Atomics() const { return int64Atomics_; }
  bool isSoftware() const { return software_; }

 protected:
  void describe(const std::string& platform);  // fills the fields from the current context
  std::string description_;
  bool int64Atomics_ = false;
  bool software_ = false;
};

// Tries, in order: EGL device platform (hardware devices first), EGL surfaceless (Mesa).
// Throws nestlight::Error listing each platform tried and why it failed.
std::unique_ptr<GlContext> createHeadlessContext();

class WindowContext : public GlContext {
 public:
  // Throws nestlight::Error when no display or no GL 4.5 window can be had.
  WindowContext(int width, int height, const std::string& title);
  ~WindowContext() override;
  void makeCurrent() override;
  GLFWwindow* window() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

// Turns GL debug output into stderr lines (debug builds; also with NESTLIGHT_GL_DEBUG=1).
void enableGlDebugOutput();

}  // namespace nestlight::gl
