#include "nestlight/gl/program.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "nestlight/gl/program_catalogue.h"
#include "nestlight/octree/error.h"
#include "nestlight/shaders/embedded.h"

namespace nestlight::gl {

namespace {

const shaders::EmbeddedFile* findFile(const std::string& path) {
  for (const auto& f : shaders::embeddedFiles())
    if (f.path == path) return &f;
  return nullptr;
}

// A shader file's text: from NESTLIGHT_SHADER_DIR where that folder holds the file, else the
// embedded copy. The override lets a driver's refusal be bisected on a lent machine with edited
// copies of shaders/ and the same binary (docs/GPU.md); files it lacks stay embedded.
bool readShaderText(const std::string& path, std::string& text) {
  if (const char* dir = std::getenv("NESTLIGHT_SHADER_DIR"); dir && *dir) {
    std::ifstream in(std::string(dir) + "/" + path, std::ios::binary);
    if (in) {
      std::ostringstream s;
      s << in.rdbuf();
      text = s.str();
      return true;
    }
  }
  const shaders::EmbeddedFile* f = findFile(path);
  if (!f) return false;
  text = std::string(f->text);
  return true;
}

// "points/../common/a.glsl" -> "common/a.glsl"; an empty result means it leaves shaders/.
std::string normalise(const std::string& path) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    std::string part = path.substr(start, end - start);
    if (part == "..") {
      if (parts.empty()) return {};
      parts.pop_back();
    } else if (!part.empty() && part != ".") {
      parts.push_back(part);
    }
    start = end + 1;
  }
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "/") + p;
  return out;
}

std::string directoryOf(const std::string& path) {
  auto slash = path.rfind('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

enum class Directive { None, Include, Version };

// `#include "file"` (the file's name into `included`) or `#version ...`; whitespace as the GLSL
// preprocessor allows it.
Directive directiveOf(const std::string& line, std::string& included) {
  size_t i = line.find_first_not_of(" \t");
  if (i == std::string::npos || line[i] != '#') return Directive::None;
  i = line.find_first_not_of(" \t", i + 1);
  if (i == std::string::npos) return Directive::None;
  auto word = [&](const char* w) {
    const size_t n = std::strlen(w);
    return line.compare(i, n, w) == 0 &&
           (i + n == line.size() || line[i + n] == ' ' || line[i + n] == '\t');
  };
  if (word("version")) return Directive::Version;
  if (!word("include")) return Directive::None;
  const size_t open = line.find('"', i + 7),
               close = open == std::string::npos ? open : line.find('"', open + 1);
  if (close == std::string::npos || line.find_first_not_of(" \t", close + 1) != std::string::npos)
    return Directive::None;
  included = line.substr(open + 1, close - open - 1);
  return included.empty() ? Directive::None : Directive::Include;
}

void expand(const std::string& path, PreprocessedSource& out, std::vector<std::string>& stack,
            const std::string& from, int fromLine) {
  std::string fileText;
  if (!readShaderText(path, fileText))
    throw Error(from.empty() ? "shaders/" + path : "shaders/" + from,
                from.empty() ? "" : "line " + std::to_string(fromLine),
                "no embedded shader file '" + path + "'");
  for (const auto& s : stack)
    if (s == path)
      throw Error("shaders/" + from, "line " + std::to_string(fromLine),
                  "#include cycle through '" + path + "'");
  stack.push_back(path);
  int number = -1;
  for (size_t i = 0; i < out.files.size(); ++i)
    if (out.files[i] == path) number = static_cast<int>(i);
  if (number < 0) {
    number = static_cast<int>(out.files.size());
    out.files.push_back(path);
  }
  std::istringstream in{fileText};
  std::string line;
  int lineNo = 0;
  out.text += "#line 1 " + std::to_string(number) + "\n";
  while (std::getline(in, line)) {
    ++lineNo;
    std::string included;
    const Directive d = directiveOf(line, included);
    if (d == Directive::Include) {
      const std::string target = normalise(directoryOf(path) + included);
      // Each file once per program, as with #pragma once.
      const bool seen = std::find(out.files.begin(), out.files.end(), target) != out.files.end();
      const bool cycle = std::find(stack.begin(), stack.end(), target) != stack.end();
      if (!seen || cycle) expand(target.empty() ? included : target, out, stack, path, lineNo);
      out.text += "#line " + std::to_string(lineNo + 1) + " " + std::to_string(number) + "\n";
    } else if (d == Directive::Version) {
      throw Error("shaders/" + path, "line " + std::to_string(lineNo),
                  "#version is added by the shader library; remove it from the file");
    } else {
      out.text += line + "\n";
    }
  }
  stack.pop_back();
}

}  // namespace

PreprocessedSource preprocessShader(
    const std::string& path, const std::vector<std::pair<std::string, std::string>>& defines) {
  PreprocessedSource out;
  out.text = "#version 450 core\n";
  for (const auto& [k, v] : defines) out.text += "#define " + k + " " + v + "\n";
  std::vector<std::string> stack;
  expand(path, out, stack, "", 0);
  return out;
}

std::string mapShaderLog(const std::string& log, const std::vector<std::string>& files) {
  // Each line starts with the source-string number: Mesa writes "0:12(5): error: ...", NVIDIA
  // "0(12) : error C0000: ...".
  std::string out;
  size_t start = 0;
  while (start < log.size()) {
    size_t end = log.find('\n', start);
    end = end == std::string::npos ? log.size() : end + 1;
    std::string line = log.substr(start, end - start);
    size_t digits = 0;
    while (digits < line.size() && std::isdigit(static_cast<unsigned char>(line[digits]))) ++digits;
    if (digits > 0 && digits < line.size() && (line[digits] == ':' || line[digits] == '(')) {
      const size_t number = std::stoul(line.substr(0, digits));
      if (number < files.size()) {
        std::string rest = line.substr(digits);
        if (rest[0] == ':') {
          // ":12(5)" -> ":12:5"
          const size_t paren = rest.find('(');
          const size_t close = paren == std::string::npos ? paren : rest.find(')', paren);
          if (close != std::string::npos && rest.find_first_not_of("0123456789", 1) == paren) {
            std::string r(rest, 0, paren);
            r.append(1, ':').append(rest, paren + 1, close - paren - 1).append(rest, close + 1);
            rest = std::move(r);
          }
        } else {
          // "(12)" -> ":12"
          const size_t close = rest.find(')');
          if (close != std::string::npos) {
            std::string r(1, ':');
            r.append(rest, 1, close - 1).append(rest, close + 1);
            rest = std::move(r);
          }
        }
        line = "shaders/" + files[number] + rest;
      }
    }
    out += line;
    start = end;
  }
  return out;
}

namespace {

// Compiles and links `stages`; the program, or 0 with the mapped driver log in `error`. `log`
// collects what the driver said even on success (NVIDIA reports warnings there).
GLuint buildProgram(const std::vector<ShaderProgram::Stage>& stages,
                    const std::vector<std::pair<std::string, std::string>>& defines,
                    std::string& error, std::string* log) {
  std::vector<GLuint> shaders;
  auto infoLog = [](GLuint object, bool program) {
    GLint len = 0;
    if (program)
      glGetProgramiv(object, GL_INFO_LOG_LENGTH, &len);
    else
      glGetShaderiv(object, GL_INFO_LOG_LENGTH, &len);
    std::string text(static_cast<size_t>(std::max(len, 1)), '\0');
    if (program)
      glGetProgramInfoLog(object, len, nullptr, text.data());
    else
      glGetShaderInfoLog(object, len, nullptr, text.data());
    return std::string(text.c_str());
  };
  for (const auto& st : stages) {
    PreprocessedSource src;
    try {
      src = preprocessShader(st.path, defines);
    } catch (const Error& e) {
      for (GLuint s : shaders) glDeleteShader(s);
      error = e.what();
      return 0;
    }
    GLuint s = glCreateShader(st.type);
    const char* text = src.text.c_str();
    glShaderSource(s, 1, &text, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    const std::string said = mapShaderLog(infoLog(s, false), src.files);
    if (log && !said.empty()) *log += "shaders/" + st.path + ":\n" + said;
    if (!ok) {
      glDeleteShader(s);
      for (GLuint t : shaders) glDeleteShader(t);
      error = "shaders/" + st.path + ": does not compile:\n" + said;
      return 0;
    }
    shaders.push_back(s);
  }
  GLuint id = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(id, s);
  glLinkProgram(id);
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(id, GL_LINK_STATUS, &ok);
  const std::string said = infoLog(id, true);
  if (log && !said.empty()) *log += "link:\n" + said;
  if (!ok) {
    glDeleteProgram(id);
    std::string names;
    for (const auto& st : stages) names += (names.empty() ? "" : " + ") + st.path;
    error = "shaders/" + stages.front().path + ": program " + names + " does not link:\n" + said;
    return 0;
  }
  return id;
}

}  // namespace

ShaderProgram::ShaderProgram(const std::vector<Stage>& stages,
                             const std::vector<std::pair<std::string, std::string>>& defines) {
  // A program missing from shaders/programs.json would escape the driver check that compiles
  // the catalogue (`nestlight gl-info --programs`) on a GPU before anyone runs it there.
  const ProgramSpec* spec = findProgram(stages);
  NL_CHECK_MSG(
      spec, "shader program " + describeStages(stages) + " is not listed in shaders/programs.json");
  for (const auto& d : defines)
    NL_CHECK_MSG(spec->defines.count(d.first), "shaders/programs.json: program " + spec->name +
                                                   " does not list the define " + d.first);
  std::string error;
  id_ = buildProgram(stages, defines, error, nullptr);
  if (!id_) throw Error(error);
}

ProgramCheck checkProgram(const ProgramSpec& spec,
                          const std::vector<std::pair<std::string, std::string>>& defines) {
  ProgramCheck c;
  c.name = spec.name;
  for (const auto& [k, v] : defines) c.defines += (c.defines.empty() ? "" : " ") + k + "=" + v;
  for (const auto& ext : spec.extensions)
    if (!epoxy_has_gl_extension(ext.c_str())) {
      c.status = ProgramCheck::Status::Unsupported;
      c.log = "the driver does not offer " + ext;
      return c;
    }
  const auto t0 = std::chrono::steady_clock::now();
  std::string error;
  const GLuint id = buildProgram(spec.stages, defines, error, &c.log);
  glFinish();
  c.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (id) {
    glDeleteProgram(id);
    c.status = ProgramCheck::Status::Ok;
  } else {
    c.status = ProgramCheck::Status::Failed;
    c.log = error;
  }
  return c;
}

std::vector<ProgramCheck> checkCatalogue(const std::vector<std::string>& only) {
  std::vector<ProgramCheck> out;
  for (const ProgramSpec& spec : programCatalogue()) {
    if (!only.empty() && std::find(only.begin(), only.end(), spec.name) == only.end()) continue;
    // Every listed value of every define, one at a time (the others at their first value).
    std::vector<std::vector<std::pair<std::string, std::string>>> variants;
    std::vector<std::pair<std::string, std::string>> base;
    for (const auto& [k, values] : spec.defines) base.emplace_back(k, values.front());
    variants.push_back(base);
    for (size_t i = 0; i < base.size(); ++i)
      for (size_t v = 1; v < spec.defines.at(base[i].first).size(); ++v) {
        auto d = base;
        d[i].second = spec.defines.at(base[i].first)[v];
        variants.push_back(d);
      }
    for (const auto& d : variants) out.push_back(checkProgram(spec, d));
  }
  return out;
}

ShaderProgram::~ShaderProgram() {
  if (id_) glDeleteProgram(id_);
}

ShaderProgram& ShaderProgram::operator=(ShaderProgram&& o) noexcept {
  if (this != &o) {
    if (id_) glDeleteProgram(id_);
    id_ = std::exchange(o.id_, 0);
  }
  return *this;
}

}  // namespace nestlight::gl
