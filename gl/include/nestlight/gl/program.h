// GLSL programs from the embedded shaders/ files.
//
// GLSL has no #include and its #line takes a source-string number, not a file name. The library
// expands `#include "file.glsl"` itself, emits `#line <line> <file number>` around each piece
// and, when the driver reports an error, rewrites "<number>:<line>" (Mesa) and "<number>(<line>)"
// (NVIDIA) in the log back to "file.glsl:<line>".
#pragma once

#include <epoxy/gl.h>

#include <string>
#include <utility>
#include <vector>

namespace nestlight::gl {

struct PreprocessedSource {
  std::string text;                // ready for glShaderSource
  std::vector<std::string> files;  // source-string number -> file path
};

// `defines` are inserted after #version as `#define NAME VALUE`. Throws nestlight::Error for a
// missing file or an include cycle, naming the including file and line.
PreprocessedSource preprocessShader(
    const std::string& path, const std::vector<std::pair<std::string, std::string>>& defines = {});

// Replaces source-string numbers in a driver's info log by file names.
std::string mapShaderLog(const std::string& log, const std::vector<std::string>& files);

// A linked program; throws nestlight::Error with the mapped log on a compile or link error.
class ShaderProgram {
 public:
  struct Stage {
    GLenum type;
    std::string path;
  };
  ShaderProgram() = default;
  ShaderProgram(const std::vector<Stage>& stages,
                const std::vector<std::pair<std::string, std::string>>& defines = {});
  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  ShaderProgram& operator=(ShaderProgram&& o) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  GLuint id() const { return id_; }
  void use() const { glUseProgram(id_); }
  GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }

 private:
  GLuint id_ = 0;
};

}  // namespace nestlight::gl
