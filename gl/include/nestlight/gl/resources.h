// GL objects owned by C++ values: a Buffer, Texture, Framebuffer or VertexArray deletes its
// name when destroyed and moves but never copies, so a pass that throws half-way leaks nothing
// and no two owners delete one name. All use direct state access (GL 4.5).
#pragma once

#include <epoxy/gl.h>

#include <cstddef>
#include <string>
#include <utility>

namespace nestlight::gl {

// A handle of kind `Deleter`; 0 is empty.
template <class Deleter>
class Object {
 public:
  Object() = default;
  explicit Object(GLuint id) : id_(id) {}
  ~Object() { reset(); }
  Object(Object&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  Object& operator=(Object&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  Object(const Object&) = delete;
  Object& operator=(const Object&) = delete;
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }
  void reset() {
    if (id_) Deleter::destroy(id_);
    id_ = 0;
  }
  GLuint release() { return std::exchange(id_, 0); }

 private:
  GLuint id_ = 0;
};

struct BufferDeleter {
  static void destroy(GLuint id) { glDeleteBuffers(1, &id); }
};
struct TextureDeleter {
  static void destroy(GLuint id) { glDeleteTextures(1, &id); }
};
struct FramebufferDeleter {
  static void destroy(GLuint id) { glDeleteFramebuffers(1, &id); }
};
struct VertexArrayDeleter {
  static void destroy(GLuint id) { glDeleteVertexArrays(1, &id); }
};
struct QueryDeleter {
  static void destroy(GLuint id) { glDeleteQueries(1, &id); }
};

// Immutable storage (glNamedBufferStorage) of `bytes`, optionally initialised from `data`.
class Buffer : public Object<BufferDeleter> {
 public:
  Buffer() = default;
  Buffer(size_t bytes, const void* data = nullptr, GLbitfield flags = GL_DYNAMIC_STORAGE_BIT);
  size_t bytes() const { return bytes_; }
  // Grows (never shrinks) to hold `bytes`, dropping the contents when it grows. Returns true
  // when it was reallocated.
  bool reserve(size_t bytes, GLbitfield flags = GL_DYNAMIC_STORAGE_BIT);
  void upload(const void* data, size_t bytes, size_t offset = 0) const;
  // Binds [offset, offset + size) to an indexed target. SSBO ranges are kept at most
  // kMaxSsboRange: llvmpipe and some drivers reject larger ones.
  void bindRange(GLenum target, GLuint index, size_t offset, size_t size) const;
  void bindBase(GLenum target, GLuint index) const;

 private:
  size_t bytes_ = 0;
};

inline constexpr size_t kMaxSsboRange = size_t(128) << 20;

// A 2D texture with immutable storage (one level unless `levels`), clamped, nearest filtering.
class Texture : public Object<TextureDeleter> {
 public:
  Texture() = default;
  Texture(GLenum internalFormat, int width, int height, int levels = 1);
  Texture(Texture&&) noexcept = default;
  Texture& operator=(Texture&&) noexcept = default;
  static Texture cubeMap(GLenum internalFormat, int size, int levels = 1);
  // A 3D texture (voxel grids).
  static Texture volume(GLenum internalFormat, int width, int height, int depth, int levels = 1);
  static Texture array2d(GLenum internalFormat, int width, int height, int layers, int levels = 1);
  int width() const { return width_; }
  int height() const { return height_; }
  GLenum format() const { return format_; }
  void setFilter(GLenum minFilter, GLenum magFilter) const;
  // GL_TEXTURE_COMPARE_MODE for shadow samplers.
  void setDepthCompare(bool on) const;

 private:
  static Texture make(GLenum target, GLenum internalFormat, int width, int height, int depth,
                      int levels);
  int width_ = 0, height_ = 0;
  GLenum format_ = 0;
};

class Framebuffer : public Object<FramebufferDeleter> {
 public:
  static Framebuffer create();
  void attach(GLenum attachment, const Texture& t, int level = 0) const;
  void attachLayer(GLenum attachment, const Texture& t, int layer, int level = 0) const;
  // A texture owned elsewhere (another library's target), by name.
  void attachRaw(GLenum attachment, GLuint texture, int level = 0) const;
  // Sets the draw buffers to GL_COLOR_ATTACHMENT0..n-1 and throws nestlight::Error naming
  // `what` when the framebuffer is incomplete.
  void finish(int colourAttachments, const std::string& what) const;
};

class VertexArray : public Object<VertexArrayDeleter> {
 public:
  static VertexArray create();
};

// GPU time of the commands between begin() and end(): two GL_TIMESTAMP queries (not
// GL_TIME_ELAPSED, which cannot nest and which llvmpipe answered with nonsense for the first
// query of a context). milliseconds() waits for the result.
class GpuTimer {
 public:
  GpuTimer();
  void begin();
  void end();
  double milliseconds();  // of the last begin/end pair; 0 before one

 private:
  Object<QueryDeleter> start_, stop_;
  bool pending_ = false;
  double last_ = 0;
};

}  // namespace nestlight::gl
