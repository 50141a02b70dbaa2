#include "nestlight/gl/context.h"

#include <epoxy/egl.h>
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

#include "nestlight/octree/error.h"

namespace nestlight::gl {

namespace {

std::string eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    default: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "EGL error 0x%x", e);
      return buf;
    }
  }
}

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)); p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// EGL keeps one display per platform and device for the process, and eglInitialize does not
// count its callers: the first eglTerminate would end every other context on it (two headless
// methods alive at once, one destroyed). Each context holds a use of its display here; the
// last one terminates it.
std::mutex displayUsersMutex;
std::map<EGLDisplay, int>& displayUsers() {
  static std::map<EGLDisplay, int> users;
  return users;
}
void acquireDisplay(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(displayUsersMutex);
  displayUsers()[d]++;
}
void releaseDisplay(EGLDisplay d) {
  std::lock_guard<std::mutex> lock(displayUsersMutex);
  auto it = displayUsers().find(d);
  if (it != displayUsers().end() && --it->second > 0) return;
  if (it != displayUsers().end()) displayUsers().erase(it);
  eglTerminate(d);
}

class EglContext : public GlContext {
 public:
  EglContext(EGLDisplay d, EGLContext c, const std::string& platform) : display_(d), context_(c) {
    try {
      makeCurrent();
      describe(platform);  // throws for a context Nestlight cannot use
    } catch (...) {
      release();  // the destructor does not run for a constructor that throws
      throw;
    }
  }
  ~EglContext() override { release(); }
  void release() {
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display_, context_);
    releaseDisplay(display_);
  }
  void makeCurrent() override {
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_))
      throw Error("EGL: eglMakeCurrent failed: " + eglErrorName(eglGetError()));
  }

 private:
  EGLDisplay display_;
  EGLContext context_;
};

// A GL 4.5 core context on `display` without a surface, or an empty string and the reason.
EGLContext createEglContext(EGLDisplay display, std::string& why) {
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) {
    why = "eglInitialize failed (" + eglErrorName(eglGetError()) + ")";
    return EGL_NO_CONTEXT;
  }
  acquireDisplay(display);
  const char* ext = eglQueryString(display, EGL_EXTENSIONS);
  if (!hasExtension(ext, "EGL_KHR_surfaceless_context")) {
    why = "the display lacks EGL_KHR_surfaceless_context";
    releaseDisplay(display);
    return EGL_NO_CONTEXT;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    why = "no desktop OpenGL API (" + eglErrorName(eglGetError()) + ")";
    releaseDisplay(display);
    return EGL_NO_CONTEXT;
  }
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!hasExtension(ext, "EGL_KHR_no_config_context") &&
      !hasExtension(ext, "EGL_MESA_configless_context")) {
    const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint n = 0;
    if (!eglChooseConfig(display, want, &config, 1, &n) || n < 1) {
      why = "no EGL config with desktop OpenGL";
      releaseDisplay(display);
      return EGL_NO_CONTEXT;
    }
  }
  bool debug = false;
#ifndef NDEBUG
  debug = true;
#endif
  if (const char* e = std::getenv("NESTLIGHT_GL_DEBUG")) debug = std::strcmp(e, "0") != 0;
  const EGLint attrs[] = {EGL_CONTEXT_MAJOR_VERSION,
                          4,
                          EGL_CONTEXT_MINOR_VERSION,
                          5,
                          EGL_CONTEXT_OPENGL_PROFILE_MASK,
                          EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                          EGL_CONTEXT_OPENGL_DEBUG,
                          debug ? EGL_TRUE : EGL_FALSE,
                          EGL_NONE};
  EGLContext c = eglCreateContext(display, config, EGL_NO_CONTEXT, attrs);
  if (c == EGL_NO_CONTEXT) {
    why = "no OpenGL 4.5 core context (" + eglErrorName(eglGetError()) + "; EGL " +
          std::to_string(major) + "." + std::to_string(minor) + ")";
    releaseDisplay(display);
  }
  return c;
}

}  // namespace

void GlContext::describe(const std::string& platform) {
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  description_ = platform + ": " + (version ? version : "?") + ", " + (renderer ? renderer : "?");
  software_ = renderer && (std::strstr(renderer, "llvmpipe") || std::strstr(renderer, "softpipe"));
  int64Atomics_ = epoxy_has_gl_extension("GL_NV_shader_atomic_int64");
  if (epoxy_gl_version() < 45)
    throw Error(platform + " gave OpenGL " + (version ? version : "?") +
                "; Nestlight needs 4.5 core");
  // GL 4.5 promises 8 shader-storage bindings; the GI frame's interface numbers 16
  // (shaders/interface/frame_interface.glsl). Every driver Nestlight runs on has more (llvmpipe
  // and NVIDIA 32 or more); a context with fewer is refused here rather than failing a pass.
  GLint ssboBindings = 0;
  glGetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS, &ssboBindings);
  if (ssboBindings < 16)
    throw Error(platform + " offers " + std::to_string(ssboBindings) +
                " shader-storage buffer bindings; Nestlight needs 16");
#ifndef NDEBUG
  enableGlDebugOutput();
#else
  if (const char* e = std::getenv("NESTLIGHT_GL_DEBUG"); e && std::strcmp(e, "0") != 0)
    enableGlDebugOutput();
#endif
}

std::unique_ptr<GlContext> createOsMesaContext(std::string& why);  // osmesa_context.cpp

std::unique_ptr<GlContext> createHeadlessContext() {
  std::string report;
  // NESTLIGHT_GL_PLATFORM=device|surfaceless|osmesa tries only that one.
  const char* forced = std::getenv("NESTLIGHT_GL_PLATFORM");
  const std::string only = forced ? forced : "";
  if (!only.empty() && only != "device" && only != "surfaceless" && only != "osmesa")
    throw Error("NESTLIGHT_GL_PLATFORM is '" + only + "'; use device, surfaceless or osmesa");
  auto wanted = [&](const char* p) { return only.empty() || only == p; };
  const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  // 1. EGL device platform: GPUs without a display server (NVIDIA), hardware devices first.
  if (!wanted("device")) {
  } else if (hasExtension(clientExt, "EGL_EXT_platform_device") &&
             hasExtension(clientExt, "EGL_EXT_device_enumeration")) {
    EGLint n = 0;
    eglQueryDevicesEXT(0, nullptr, &n);
    std::vector<EGLDeviceEXT> devices(static_cast<size_t>(std::max(n, 0)));
    if (n > 0) eglQueryDevicesEXT(n, devices.data(), &n);
    std::vector<EGLDeviceEXT> ordered;
    for (int pass = 0; pass < 2; ++pass)
      for (auto d : devices) {
        const char* de = eglQueryDeviceStringEXT(d, EGL_EXTENSIONS);
        const bool software = hasExtension(de, "EGL_MESA_device_software");
        if ((pass == 0) != software) ordered.push_back(d);
      }
    std::string why = ordered.empty() ? "no devices" : "";
    for (auto d : ordered) {
      EGLDisplay display = eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, d, nullptr);
      if (display == EGL_NO_DISPLAY) {
        why += (why.empty() ? "" : "; ") + std::string("eglGetPlatformDisplayEXT failed");
        continue;
      }
      std::string w;
      EGLContext c = createEglContext(display, w);
      if (c != EGL_NO_CONTEXT) {
        std::unique_ptr<EglContext> ctx;
        try {
          ctx = std::make_unique<EglContext>(display, c, "EGL device");
        } catch (const Error& e) {
          why += (why.empty() ? "" : "; ") + std::string(e.what());
          continue;
        }
        if (!ctx->isSoftware() || only == "device") return ctx;
        // Mesa's software device works, but the surfaceless platform below names itself
        // better; keep this one only if that fails.
        why += (why.empty() ? "" : "; ") + std::string("only a software device");
        break;
      }
      why += (why.empty() ? "" : "; ") + w;
    }
    report += "  EGL device platform: " + why + "\n";
  } else {
    report += "  EGL device platform: EGL_EXT_platform_device not offered by libEGL\n";
  }
  // 2. Mesa's surfaceless platform: llvmpipe without any display.
  if (!wanted("surfaceless")) {
  } else if (hasExtension(clientExt, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay display =
        eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    std::string why = "eglGetPlatformDisplayEXT failed";
    if (display != EGL_NO_DISPLAY) {
      EGLContext c = createEglContext(display, why);
      if (c != EGL_NO_CONTEXT) {
        try {
          return std::make_unique<EglContext>(display, c, "EGL surfaceless");
        } catch (const Error& e) {
          why = e.what();
        }
      }
    }
    report += "  EGL surfaceless platform: " + why + "\n";
  } else {
    report +=
        "  EGL surfaceless platform: EGL_MESA_platform_surfaceless not offered (install "
        "libegl-mesa0)\n";
  }
  // 3. OSMesa: Mesa rendering into client memory, for a libEGL without the platforms above.
  if (wanted("osmesa")) {
    std::string why;
    if (auto ctx = createOsMesaContext(why)) return ctx;
    report += "  OSMesa: " + why + "\n";
  }
  throw Error("no OpenGL 4.5 core context could be created headless" +
              (only.empty() ? std::string() : " (NESTLIGHT_GL_PLATFORM=" + only + ")") +
              "; tried:\n" + report +
              "On Debian: apt-get install libegl-mesa0 libgl1-mesa-dri (Mesa llvmpipe), or an "
              "NVIDIA driver.");
}

WindowContext::WindowContext(int width, int height, const std::string& title) {
  if (!glfwInit()) {
    const char* msg = nullptr;
    glfwGetError(&msg);
    throw Error(std::string("no window: GLFW cannot start (") + (msg ? msg : "no display?") +
                "); use `nestlight render` for headless images");
  }
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
#ifndef NDEBUG
  glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
#endif
  window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
  if (!window_) {
    const char* msg = nullptr;
    glfwGetError(&msg);
    glfwTerminate();
    throw Error(std::string("no OpenGL 4.5 core window: ") + (msg ? msg : "unknown GLFW error"));
  }
  makeCurrent();
  glfwSwapInterval(1);
  describe("GLFW window");
}

WindowContext::~WindowContext() {
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void WindowContext::makeCurrent() {
  glfwMakeContextCurrent(window_);
}

void enableGlDebugOutput() {
  glEnable(GL_DEBUG_OUTPUT);
  glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
  glDebugMessageCallback(
      [](GLenum, GLenum type, GLuint, GLenum severity, GLsizei, const GLchar* message,
         const void*) {
        if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
        std::fprintf(stderr, "GL %s: %s\n", type == GL_DEBUG_TYPE_ERROR ? "error" : "debug",
                     message);
      },
      nullptr);
}

}  // namespace nestlight::gl
