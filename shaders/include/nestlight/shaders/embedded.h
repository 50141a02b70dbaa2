// The GLSL files of shaders/, embedded at build time. Paths are relative to shaders/.
#pragma once

#include <string_view>
#include <vector>

namespace nestlight::shaders {

struct EmbeddedFile {
  std::string_view path;
  std::string_view text;
};

const std::vector<EmbeddedFile>& embeddedFiles();

}  // namespace nestlight::shaders
