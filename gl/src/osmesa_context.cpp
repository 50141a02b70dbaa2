// The OSMesa fallback: an OpenGL 4.5 core context rendered by Mesa into client memory, for
// systems whose libEGL lacks the surfaceless platform. libepoxy resolves GL functions only
// through EGL or GLX, so once the context is current every function pointer of epoxy's table
// (all of them, listed at build time by gl/gl_functions.cmake, so a call from any library
// works) that OSMesa provides is pointed at OSMesa's own.
// epoxy must come before any GL header, which sorting would put first.
// clang-format off
#include <epoxy/gl.h>
#include <GL/osmesa.h>
// clang-format on

#include <dlfcn.h>

#include <span>
#include <string>
#include <vector>

#include "nestlight/gl/context.h"
#include "nestlight/octree/error.h"

namespace nestlight::gl {

namespace {

using GetProc = OSMESAproc (*)(const char*);

// epoxy's function pointer for each GL function, by name. A table (constant-initialised data)
// rather than a statement per function: 3,000 unrolled statements took the compiler nine minutes
// under AddressSanitizer. Every epoxy_* pointer is a plain function-pointer variable, so its
// address is stored as void** (function and data pointers have one size on every platform with
// dlsym).
struct FunctionSlot {
  const char* name;
  void** slot;
};

std::span<const FunctionSlot> functionTable() {
  static const FunctionSlot table[] = {
#define NL_GL(name) {#name, reinterpret_cast<void**>(&epoxy_##name)},
#include "osmesa_gl_functions.inc"
#undef NL_GL
  };
  return table;
}

class OsMesaContext : public GlContext {
 public:
  OsMesaContext(void* lib, OSMesaContext ctx) : lib_(lib), ctx_(ctx), pixels_(4, 0) {
    makeCurrent();
    const auto getProc = reinterpret_cast<GetProc>(dlsym(lib_, "OSMesaGetProcAddress"));
    // A function OSMesa lacks keeps epoxy's resolver, which reports it by name when called.
    const auto table = functionTable();
    saved_.reserve(table.size());
    for (const FunctionSlot& f : table) {
      saved_.push_back(*f.slot);
      if (auto p = getProc(f.name)) {
        *f.slot = reinterpret_cast<void*>(p);
        ++resolved_;
      }
    }
    try {
      describe("OSMesa");
    } catch (...) {
      release();  // the destructor does not run for a constructor that throws
      throw;
    }
  }
  ~OsMesaContext() override { release(); }
  void release() {
    // Give epoxy its own resolvers back: a later EGL or GLX context must not call into OSMesa.
    const auto table = functionTable();
    for (size_t i = 0; i < saved_.size() && i < table.size(); ++i) *table[i].slot = saved_[i];
    auto destroy = reinterpret_cast<void (*)(OSMesaContext)>(dlsym(lib_, "OSMesaDestroyContext"));
    if (destroy) destroy(ctx_);
    dlclose(lib_);
  }
  void makeCurrent() override {
    auto make = reinterpret_cast<GLboolean (*)(OSMesaContext, void*, GLenum, GLsizei, GLsizei)>(
        dlsym(lib_, "OSMesaMakeCurrent"));
    // Every pass draws into FBOs; the client buffer is a 1x1 placeholder.
    if (!make || !make(ctx_, pixels_.data(), GL_UNSIGNED_BYTE, 1, 1))
      throw Error("OSMesa: OSMesaMakeCurrent failed");
  }

 private:
  void* lib_;
  OSMesaContext ctx_;
  std::vector<unsigned char> pixels_;
  std::vector<void*> saved_;
  size_t resolved_ = 0;
};

}  // namespace

// Loaded at run time so that machines without libOSMesa still start.
std::unique_ptr<GlContext> createOsMesaContext(std::string& why) {
  void* lib = nullptr;
  for (const char* name : {"libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so"})
    if ((lib = dlopen(name, RTLD_NOW | RTLD_LOCAL))) break;
  if (!lib) {
    why = "libOSMesa is not installed (apt-get install libosmesa6)";
    return nullptr;
  }
  auto create = reinterpret_cast<OSMesaContext (*)(const int*, OSMesaContext)>(
      dlsym(lib, "OSMesaCreateContextAttribs"));
  if (!create || !dlsym(lib, "OSMesaGetProcAddress") || !dlsym(lib, "OSMesaMakeCurrent")) {
    why = "libOSMesa lacks OSMesaCreateContextAttribs";
    dlclose(lib);
    return nullptr;
  }
  const int attrs[] = {OSMESA_FORMAT,
                       OSMESA_RGBA,
                       OSMESA_DEPTH_BITS,
                       0,
                       OSMESA_PROFILE,
                       OSMESA_CORE_PROFILE,
                       OSMESA_CONTEXT_MAJOR_VERSION,
                       4,
                       OSMESA_CONTEXT_MINOR_VERSION,
                       5,
                       0};
  OSMesaContext ctx = create(attrs, nullptr);
  if (!ctx) {
    why = "no OpenGL 4.5 core context from OSMesaCreateContextAttribs";
    dlclose(lib);
    return nullptr;
  }
  try {
    return std::make_unique<OsMesaContext>(lib, ctx);
  } catch (const Error& e) {
    why = e.what();
    return nullptr;
  }
}

}  // namespace nestlight::gl
