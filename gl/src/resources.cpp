#include "nestlight/gl/resources.h"

#include <algorithm>
#include <cstdio>

#include "nestlight/octree/error.h"

namespace nestlight::gl {

Buffer::Buffer(size_t bytes, const void* data, GLbitfield flags) {
  GLuint id = 0;
  glCreateBuffers(1, &id);
  static_cast<Object&>(*this) = Object(id);
  // Zero-sized storage is an error in GL; one byte keeps the name valid for empty content.
  glNamedBufferStorage(id, GLsizeiptr(std::max<size_t>(bytes, 1)), data, flags);
  bytes_ = bytes;
}

bool Buffer::reserve(size_t bytes, GLbitfield flags) {
  if (*this && bytes <= bytes_) return false;
  *this = Buffer(std::max(bytes, bytes_ + bytes_ / 2), nullptr, flags);
  return true;
}

void Buffer::upload(const void* data, size_t bytes, size_t offset) const {
  NL_CHECK(offset + bytes <= bytes_);
  if (bytes) glNamedBufferSubData(id(), GLintptr(offset), GLsizeiptr(bytes), data);
}

void Buffer::bindRange(GLenum target, GLuint index, size_t offset, size_t size) const {
  NL_CHECK(offset + size <= std::max<size_t>(bytes_, 1));
  NL_CHECK(target != GL_SHADER_STORAGE_BUFFER || size <= kMaxSsboRange);
  glBindBufferRange(target, index, id(), GLintptr(offset), GLsizeiptr(std::max<size_t>(size, 1)));
}

void Buffer::bindBase(GLenum target, GLuint index) const {
  if (target == GL_SHADER_STORAGE_BUFFER && bytes_ > kMaxSsboRange)
    throw Error("a " + std::to_string(bytes_ >> 20) +
                " MiB buffer bound whole as an SSBO (at most 128 MiB)");
  glBindBufferBase(target, index, id());
}

Texture Texture::make(GLenum target, GLenum internalFormat, int width, int height, int depth,
                      int levels) {
  NL_CHECK(width > 0 && height > 0 && depth > 0 && levels > 0);
  Texture t;
  GLuint id = 0;
  glCreateTextures(target, 1, &id);
  static_cast<Object&>(t) = Object(id);
  if (target == GL_TEXTURE_2D_ARRAY || target == GL_TEXTURE_3D)
    glTextureStorage3D(id, levels, internalFormat, width, height, depth);
  else
    glTextureStorage2D(id, levels, internalFormat, width, height);
  t.width_ = width;
  t.height_ = height;
  t.format_ = internalFormat;
  // Clamped, nearest: passes fetch texels; a pass that wants filtering sets it.
  for (GLenum w : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTextureParameteri(id, w, GL_CLAMP_TO_EDGE);
  t.setFilter(GL_NEAREST, GL_NEAREST);
  return t;
}

Texture::Texture(GLenum internalFormat, int width, int height, int levels) {
  *this = make(GL_TEXTURE_2D, internalFormat, width, height, 1, levels);
}

Texture Texture::cubeMap(GLenum internalFormat, int size, int levels) {
  return make(GL_TEXTURE_CUBE_MAP, internalFormat, size, size, 1, levels);
}

Texture Texture::volume(GLenum internalFormat, int width, int height, int depth, int levels) {
  return make(GL_TEXTURE_3D, internalFormat, width, height, depth, levels);
}

Texture Texture::array2d(GLenum internalFormat, int width, int height, int layers, int levels) {
  return make(GL_TEXTURE_2D_ARRAY, internalFormat, width, height, layers, levels);
}

void Texture::setFilter(GLenum minFilter, GLenum magFilter) const {
  glTextureParameteri(id(), GL_TEXTURE_MIN_FILTER, GLint(minFilter));
  glTextureParameteri(id(), GL_TEXTURE_MAG_FILTER, GLint(magFilter));
}

void Texture::setDepthCompare(bool on) const {
  glTextureParameteri(id(), GL_TEXTURE_COMPARE_MODE, on ? GL_COMPARE_REF_TO_TEXTURE : GL_NONE);
  glTextureParameteri(id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
}

Framebuffer Framebuffer::create() {
  GLuint id = 0;
  glCreateFramebuffers(1, &id);
  Framebuffer f;
  static_cast<Object&>(f) = Object(id);
  return f;
}

void Framebuffer::attach(GLenum attachment, const Texture& t, int level) const {
  glNamedFramebufferTexture(id(), attachment, t.id(), level);
}

void Framebuffer::attachRaw(GLenum attachment, GLuint texture, int level) const {
  glNamedFramebufferTexture(id(), attachment, texture, level);
}

void Framebuffer::attachLayer(GLenum attachment, const Texture& t, int layer, int level) const {
  glNamedFramebufferTextureLayer(id(), attachment, t.id(), level, layer);
}

void Framebuffer::finish(int colourAttachments, const std::string& what) const {
  GLenum bufs[8];
  NL_CHECK(colourAttachments >= 0 && colourAttachments <= 8);
  for (int i = 0; i < colourAttachments; ++i) bufs[i] = GLenum(GL_COLOR_ATTACHMENT0 + i);
  if (colourAttachments)
    glNamedFramebufferDrawBuffers(id(), colourAttachments, bufs);
  else
    glNamedFramebufferDrawBuffer(id(), GL_NONE);
  const GLenum status = glCheckNamedFramebufferStatus(id(), GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "0x%x", status);
    throw Error(what + ": framebuffer incomplete (status " + buf + ")");
  }
}

VertexArray VertexArray::create() {
  GLuint id = 0;
  glCreateVertexArrays(1, &id);
  VertexArray v;
  static_cast<Object&>(v) = Object(id);
  return v;
}

GpuTimer::GpuTimer() {
  GLuint ids[2] = {0, 0};
  glCreateQueries(GL_TIMESTAMP, 2, ids);
  start_ = Object<QueryDeleter>(ids[0]);
  stop_ = Object<QueryDeleter>(ids[1]);
}

void GpuTimer::begin() {
  if (pending_) milliseconds();  // a query object holds one result: collect it before reuse
  glQueryCounter(start_.id(), GL_TIMESTAMP);
}

void GpuTimer::end() {
  glQueryCounter(stop_.id(), GL_TIMESTAMP);
  pending_ = true;
}

double GpuTimer::milliseconds() {
  if (pending_) {
    GLuint64 t0 = 0, t1 = 0;
    glGetQueryObjectui64v(start_.id(), GL_QUERY_RESULT, &t0);
    glGetQueryObjectui64v(stop_.id(), GL_QUERY_RESULT, &t1);
    last_ = t1 >= t0 ? double(t1 - t0) * 1e-6 : 0.0;
    pending_ = false;
  }
  return last_;
}

}  // namespace nestlight::gl
